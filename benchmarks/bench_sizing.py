"""Curvature-adaptive sizing (issue #12): triangles against maximal chord error.

For each surface, the uniform mesh at two resolutions (``coarse`` = 32
and 64 boxes per axis, or finer where the surface needs it), and beside
each the coarsest curvature mesh (``size="curvature"``) whose maximal
deviation is no larger than the uniform mesh's (chord tolerances from
twice the uniform mesh's deviation down by factors of 2^(1/4), at most
ten tries: the leaves halve level by level, so the deviation moves in
steps).  The deviation is the largest distance to F = 0 (Newton along grad F from the point, 20
steps) of the triangles' centroids and edge midpoints, relative to the
box's longest side, over the triangles farther than 5% of the box from
every singular point (the fans in the singular points' stars are the
singular refinement's, not the sizing's; the overall maximum is printed
too).  Triangle counts and CPU times at matched deviation.

Run from the repository root::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_sizing.py [--only sphere,cayley]

This is a benchmark that prints figures, not a test.
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np
import sympy as sp

import singmesh

X, Y, Z = sp.symbols("x y z")


def _rotated_ellipsoid() -> str:
    """x^2 + (y/0.5)^2 + (z/0.2)^2 = 0.8^2 rotated by a QR matrix, shifted, with 15-digit coefficients."""
    q, _ = np.linalg.qr(np.random.default_rng(7).normal(size=(3, 3)))
    t = np.array([0.0713, -0.0391, 0.0527])
    u = [sum(q[i, j] * ((X, Y, Z)[i] - t[i]) for i in range(3)) for j in range(3)]
    e = sp.expand(u[0] ** 2 + (u[1] / 0.5) ** 2 + (u[2] / 0.2) ** 2 - 0.64)
    return str(e.xreplace({f: sp.Float(f"{float(f):.15g}") for f in e.atoms(sp.Float)}))


#: (name, equation, box half-width, uniform resolutions): the thin
#: ellipsoid's rim (radius of curvature 0.01) is resolved by the uniform
#: mesh from 128 boxes per axis on; coarser, its deviation is the rim's
#: radius whatever the sizing (the tolerance is over the radius there).
SURFACES = [
    ("sphere", "x^2 + y^2 + z^2 - 1", 1.5, (32, 64)),
    ("ellipsoid 1,1,0.1", "x^2 + y^2 + 100 z^2 - 1", 1.2, (128, 256)),
    ("torus 1, 0.15", "(x^2 + y^2 + z^2 + 1 - 0.0225)^2 - 4 (x^2 + y^2)", 1.3, (32, 64)),
    ("tanglecube", "x^4 - 5x^2 + y^4 - 5y^2 + z^4 - 5z^2 + 11.8", 3.0, (32, 64)),
    ("cayley", "4(x^2 + y^2 + z^2) + 16 x y z - 1", 1.5, (32, 64)),
    ("rotated ellipsoid", _rotated_ellipsoid(), 1.0, (64, 128)),
]


def deviation(m: singmesh.Mesh, away: float = 0.05) -> tuple[float, float]:
    """Maximal distance to F = 0 of centroids and edge midpoints / box side: (away from singular points, all)."""
    v, f = m.vertices, m.faces
    side = float((m.box[:, 1] - m.box[:, 0]).max())
    tri = v[f]
    pts = np.vstack([tri.mean(1), (tri[:, 0] + tri[:, 1]) / 2, (tri[:, 1] + tri[:, 2]) / 2,
                     (tri[:, 2] + tri[:, 0]) / 2])
    with np.errstate(all="ignore"):
        d = np.linalg.norm(pts - m.surface.project(pts, iterations=20), axis=1) / side
    far = np.ones(len(pts), bool)
    if len(m.singular_points):
        owner = np.tile(np.arange(len(f)), 4)
        gap = np.linalg.norm(tri[:, :, None, :] - m.singular_points[None, None], axis=3)
        near = (gap < away * side).any(axis=(1, 2))
        far = ~near[owner]
    return float(d[far].max()), float(d.max())


def run(text: str, half: float, **kw):
    t0 = time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = singmesh.mesh(text, ((-half, half),) * 3, **kw)
    t = time.process_time() - t0
    r = m.report()
    assert r["boundary_edges_off_box"] == 0 and r["non_manifold_edges"] == 0
    return m, t, deviation(m)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--only", default="", help="comma-separated substrings of the surface names")
    p.add_argument("--res", default="", help="uniform resolutions (coarse), comma-separated, for all surfaces "
                   "(default: each surface's own)")
    args = p.parse_args(argv)
    only = [s for s in args.only.split(",") if s]
    print(f"singmesh {singmesh.__version__ if hasattr(singmesh, '__version__') else ''} | CPU seconds | "
          "deviation = max distance to F = 0 of centroids and edge midpoints / box side (away from singular points)")
    head = (f"{'surface':<20s} {'uniform':>8s} {'triangles':>9s} {'max dev':>9s} {'time':>6s} | "
            f"{'chord':>8s} {'triangles':>9s} {'max dev':>9s} {'time':>6s} {'ratio':>6s}  levels")
    print(head)
    print("-" * len(head))
    for name, text, half, resolutions in SURFACES:
        if only and not any(o in name for o in only):
            continue
        for res in [int(r) for r in args.res.split(",")] if args.res else resolutions:
            mu, tu, (du, du_all) = run(text, half, coarse=res)
            # The coarsest curvature mesh of a ladder of chord tolerances
            # whose deviation is no larger than the uniform mesh's.
            chord = 2 * du
            for _ in range(10):
                mc, tc, (dc, dc_all) = run(text, half, size="curvature", chord=chord)
                if dc <= du:
                    break
                chord /= 2 ** 0.25
            levels = ",".join(f"{lvl}:{n}" for lvl, n in enumerate(mc.stats["levels"]) if n)
            print(f"{name:<20s} {res:>8d} {len(mu.faces):>9d} {du:>9.2e} {tu:>6.1f} | "
                  f"{chord:>8.1e} {len(mc.faces):>9d} {dc:>9.2e} {tc:>6.1f} "
                  f"{len(mc.faces) / len(mu.faces):>6.2f}  {levels}",
                  flush=True)
            if du_all != du or dc_all != dc:
                print(f"{'':<20s} {'(all)':>8s} {'':>9s} {du_all:>9.2e} {'':>6s} | {'':>8s} {'':>9s} {dc_all:>9.2e}")
    print("ratio: curvature triangles / uniform triangles, the curvature mesh's deviation no larger "
          "(unless ten tries did not get there: then its deviation column is larger)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
