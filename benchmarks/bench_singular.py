"""Nodal surfaces: how close singmesh and marching cubes get to the nodes.

For Cayley's cubic (4 nodes), Kummer's quartic (16) and the Barth sextic
(50 inside [-2, 2]^3) this prints, side by side for singmesh and for
scikit-image's marching cubes at the same resolution: the time, the
vertex count, the singular points singmesh reports, and the distance
from each true node to the nearest mesh vertex (max and median over the
nodes, relative to the box size).

The true nodes come from ``nodes.py``, which computes them without any
singmesh code (exactly for Cayley, by its own numerical solver for the
others) and checks their number.

Run from the repository root::

    .venv/bin/python benchmarks/bench_singular.py [--res 32 64] [--repeat 3]

This is a benchmark that prints figures, not a test.
"""

from __future__ import annotations

import platform
import sys
import time
from importlib.metadata import version

import numpy as np
from scipy.spatial import cKDTree

import nodes
import singmesh
from common import TIME_COLUMNS, best_time, box_size, format_table, marching_cubes, parse_args, print_footer, sci


def node_distances(true_nodes: np.ndarray, points: np.ndarray, box) -> tuple[float, float]:
    """Max and median over the true nodes of the distance to the nearest point.

    Relative to the box size; NaN when there are no points.
    """
    if not len(points) or not len(true_nodes):
        return float("nan"), float("nan")
    d, _ = cKDTree(points).query(true_nodes)
    d = d / box_size(box)
    return float(d.max()), float(np.median(d))


def main(argv=None) -> int:
    args = parse_args(__doc__, argv)
    print(f"singmesh {version('singmesh')} | python {platform.python_version()} "
          f"| numpy {np.__version__} | best of {args.repeat} warm runs")
    print("true nodes (independent of singmesh):")
    found = {}
    for key, s in nodes.SURFACES.items():
        t0 = time.perf_counter()
        n = nodes.true_nodes(key)  # raises if the count is not the known one
        dt = time.perf_counter() - t0
        # The reference polynomial is written in sympy by hand; singmesh's
        # parse of the SingSurf text must vanish at the same points, or one
        # of the two equations is wrong and the comparison meaningless.
        surf = singmesh.Surface.parse(s.text)
        rel = np.abs(surf(n)) / np.maximum(surf.magnitude(n), 1e-300)
        agree = "agrees" if rel.max() < 1e-12 else "DISAGREES"
        (lo, hi) = s.box[0]
        print(f"  {s.name:15s} {len(n):2d} nodes on [{lo:g},{hi:g}]^3 ({dt:.2f} s); "
              f"singmesh's parse of the text {agree} (max rel |F| at the nodes {sci(rel.max())})")
        found[key] = (s, surf, n)
    print()

    columns = TIME_COLUMNS + [
        ("singular points", "found", ">"), ("singular points", "max err", ">"),
        ("node->vertex max / box", "singmesh", ">"), ("node->vertex max / box", "mc", ">"),
        ("node->vertex median / box", "singmesh", ">"), ("node->vertex median / box", "mc", ">"),
    ]
    rows = []
    for k, (key, (s, surf, true)) in enumerate(found.items()):
        if k:
            rows.append(None)
        for res in args.res:
            fine = max(args.fine, res)
            t_sm, m = best_time(lambda: singmesh.mesh(surf, box=s.box, coarse=res, fine=fine), args.repeat)
            t_mc, mc = best_time(lambda: marching_cubes(surf, s.box, res), args.repeat)
            sing = np.asarray(m.singular_points, dtype=float).reshape(-1, 3)
            # Of each true node, how far the nearest reported singular point is.
            sing_err = node_distances(true, sing, s.box)[0]
            sm_max, sm_med = node_distances(true, m.vertices, s.box)
            mc_max, mc_med = node_distances(true, mc.vertices, s.box)
            rows.append([
                key, str(res),
                f"{t_sm:.3f}", f"{t_mc:.3f}", f"{mc.sample_time:.3f}", f"{t_sm / t_mc:.1f}x",
                str(len(m.vertices)), str(len(mc.vertices)),
                f"{len(sing)}/{len(true)}", "-" if np.isnan(sing_err) else sci(sing_err),
                sci(sm_max), sci(mc_max), sci(sm_med), sci(mc_med),
            ])
            print(f"  done {key} res {res}", file=sys.stderr, flush=True)
    print(format_table(columns, rows))
    print_footer(args.res, ("found = len(m.singular_points) / true nodes in the box; max err = largest distance "
                  "from a true node to the nearest reported singular point / box.",))
    return 0


if __name__ == "__main__":
    sys.exit(main())
