"""Smooth surfaces: singmesh against scikit-image's marching cubes.

For each surface and resolution this prints, side by side, the time of
``singmesh.mesh`` and of marching cubes on the grid of the same
resolution (F sampled vectorised, sampling included), the vertex and face
counts, and the largest vertex distance |F|/|grad F| to the surface,
relative to the box size.

Run from the repository root::

    .venv/bin/python benchmarks/bench_smooth.py [--res 32 64] [--repeat 3]

This is a benchmark that prints figures, not a test.
"""

from __future__ import annotations

import platform
import sys
from importlib.metadata import version

import numpy as np

import singmesh
from common import TIME_COLUMNS, best_time, format_table, marching_cubes, parse_args, print_footer, sci, surface_distance

#: (short name, equation, half-width of the cube box)
SURFACES = [
    ("sphere", "x^2+y^2+z^2-1", 2.0),
    ("tanglecube", "x^4-5x^2+y^4-5y^2+z^4-5z^2+11.8", 3.0),
    ("sextic", "x^6+y^6+z^6-1", 2.0),
]


def main(argv=None) -> int:
    args = parse_args(__doc__, argv)
    print(f"singmesh {version('singmesh')} | python {platform.python_version()} "
          f"| numpy {np.__version__} | best of {args.repeat} warm runs")
    print("surfaces:")
    for name, eq, h in SURFACES:
        print(f"  {name:11s} {eq}  on [{-h:g},{h:g}]^3")
    print()

    columns = TIME_COLUMNS + [
        ("faces", "singmesh", ">"), ("faces", "mc", ">"),
        ("max |F|/|grad F| / box", "singmesh", ">"), ("max |F|/|grad F| / box", "mc", ">"),
    ]
    rows = []
    for k, (name, eq, h) in enumerate(SURFACES):
        box = ((-h, h),) * 3
        # Parsed once, outside the timings: both meshers are then timed on
        # the same evaluator, and sympy's parsing is charged to neither.
        surf = singmesh.Surface.parse(eq)
        if k:
            rows.append(None)
        for res in args.res:
            fine = max(args.fine, res)
            t_sm, m = best_time(lambda: singmesh.mesh(surf, box=box, coarse=res, fine=fine), args.repeat)
            t_mc, mc = best_time(lambda: marching_cubes(surf, box, res), args.repeat)
            rows.append([
                name, str(res),
                f"{t_sm:.3f}", f"{t_mc:.3f}", f"{mc.sample_time:.3f}", f"{t_sm / t_mc:.1f}x",
                str(len(m.vertices)), str(len(mc.vertices)),
                str(len(m.faces)), str(len(mc.faces)),
                sci(surface_distance(surf, m.vertices, box)),
                sci(surface_distance(surf, mc.vertices, box)),
            ])
            print(f"  done {name} res {res}", file=sys.stderr, flush=True)
    print(format_table(columns, rows))
    print_footer(args.res, ())
    return 0


if __name__ == "__main__":
    sys.exit(main())
