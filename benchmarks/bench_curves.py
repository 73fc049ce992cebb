"""Surfaces with curves of singular points: singmesh against marching cubes.

For the Whitney umbrella, the cross-cap, Steiner's Roman surface, a sphere
through a plane, three planes through a line, a cuspidal edge and a
tacnode edge (as typed, and rotated and shifted by 15-digit float rotations,
one row per seed), this prints side by side: the time of ``singmesh.mesh``
at the default settings (coarse 32, fine 256; wall and CPU time, the CPU
time being the steadier figure on a shared machine) and of scikit-image's
marching cubes at 64^3 and 128^3, the curve pieces and special points
singmesh reports, and how the
singular curve is followed.  The curve's samples come from an independent
Gauss-Newton solve of F = grad F = 0 from random starts (tests/test_curves.py):
"followed" is the share of them within 1% of the box of a mesh edge whose
ends are singular vertices, or of a line cell; for marching cubes, of any
mesh edge (it has no singular vertices at all).

Run from the repository root::

    .venv/bin/python benchmarks/bench_curves.py [--repeat 3] [--only roman,whitney] [--seeds 7,9,3]

This is a benchmark that prints figures, not a test.
"""

from __future__ import annotations

import argparse
import platform
import sys
import time
import warnings
from importlib.metadata import version
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
import singmesh  # noqa: E402
from common import best_time, format_table, marching_cubes  # noqa: E402
from test_curves import float_rotated, lambdas, segment_distance, singular_locus  # noqa: E402

SURFACES = [
    ("whitney", "x^2 - y^2 z", 1.0),
    ("crosscap", "4 x^2 (x^2 + y^2 + z^2 + z) + y^2 (y^2 + z^2 - 1)", 1.2),
    ("roman", "x^2 y^2 + y^2 z^2 + z^2 x^2 - x y z", 1.0),
    ("sphere-plane", "(x^2 + y^2 + z^2 - 1) z", 1.5),
    ("three-planes", "x^3 - 3 x y^2", 1.0),
    ("cusp-edge", "x^2 - y^3", 1.0),
    ("tacnode-edge", "x^2 - y^4", 1.0),
]


def best_times(fn, repeat: int):
    """As ``common.best_time`` (one warm-up run, then ``repeat``), with the least CPU time too.

    Returns
    -------
    wall : float
        The least wall-clock time.
    cpu : float
        The least CPU time of the process (``time.process_time``): what
        other load on a shared machine disturbs least.
    result
        What the fastest run (wall clock) returned.
    """
    fn()
    wall, cpu, result = float("inf"), float("inf"), None
    for _ in range(max(repeat, 1)):
        w0, c0 = time.perf_counter(), time.process_time()
        out = fn()
        w, c = time.perf_counter() - w0, time.process_time() - c0
        cpu = min(cpu, c)
        if w < wall:
            wall, result = w, out
    return wall, cpu, result


def followed(text, box, vertices, segments) -> float:
    samples = singular_locus(text, box)
    size = float(np.max(np.asarray(box)[:, 1] - np.asarray(box)[:, 0]))
    if not len(samples) or not len(segments):
        return 0.0
    d = segment_distance(samples, vertices[segments[:, 0]], vertices[segments[:, 1]])
    return float(np.mean(d <= 0.01 * size))


def edges_of(faces) -> np.ndarray:
    e = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    return np.unique(e, axis=0)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--only")
    ap.add_argument("--seeds", default="7", help="seeds of the float rotations, comma-separated (one row each)")
    args = ap.parse_args(argv)
    seeds = [int(s) for s in args.seeds.split(",") if s]
    print(f"singmesh {version('singmesh')} | python {platform.python_version()} | numpy {np.__version__} "
          f"| best of {args.repeat} warm runs | default settings (coarse 32, fine 256)")
    cases = [(n, t, b) for n, t, b in SURFACES if not args.only or n in args.only.split(",")]
    columns = [("surface", "", "<"), ("time s", "singmesh", ">"), ("cpu s", "singmesh", ">"), ("time s", "mc 64", ">"),
               ("time s", "mc 128", ">"), ("curves", "pieces", ">"), ("curves", "special", ">"),
               ("curves", "line cells", ">"), ("followed", "singmesh", ">"), ("followed", "mc 128", ">"),
               ("", "types", "<")]
    rows = []
    for name, text, b in cases:
        for seed in [None] + seeds:
            eq = float_rotated(text, seed) if seed is not None else text
            box = ((-b, b),) * 3
            surf = singmesh.Surface.parse(eq)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                t_sm, cpu, m = best_times(lambda: singmesh.mesh(surf, box=box), args.repeat)
            t64, _ = best_time(lambda: marching_cubes(surf, box, 64), args.repeat)
            t128, mc = best_time(lambda: marching_cubes(surf, box, 128), args.repeat)
            points, lines = m.curve_lines()
            _, g, _, _ = lambdas(eq)
            grad = np.linalg.norm(g(points), axis=1)
            sing = grad <= 1e-6 * np.median(grad[grad > 0])
            e = edges_of(m.faces)
            segs = np.concatenate([e[sing[e[:, 0]] & sing[e[:, 1]]], lines])
            types = sorted({c.type for c in m.singular_curves})
            rows.append([name + (f" rot {seed}" if seed is not None else ""), f"{t_sm:.2f}", f"{cpu:.2f}",
                         f"{t64:.3f}", f"{t128:.3f}",
                         str(len(m.singular_curves)), str(len(m.special_points)), str(len(lines)),
                         f"{followed(eq, box, points, segs):.0%}",
                         f"{followed(eq, box, mc.vertices, edges_of(mc.faces)):.0%}", ", ".join(types)])
            print(f"  done {rows[-1][0]}", file=sys.stderr, flush=True)
    print(format_table(columns, rows))
    print("followed: share of independent samples of the singular curve within 1% of the box of a mesh "
          "edge between singular vertices or a line cell (marching cubes: of any edge).")
    return 0


if __name__ == "__main__":
    t0 = time.perf_counter()
    status = main()
    print(f"total {time.perf_counter() - t0:.0f} s")
    sys.exit(status)
