"""Sweep of surfaces with curves of singular points, in general position.

Every case is meshed under float rotations and shifts written with 15
digits (``tests/test_curves.float_rotated``) at several seeds, and checked
by ``tests/test_curves.check_curve_mesh``: curve samples from an
independent Gauss-Newton solve followed by mesh edges between singular
vertices, edges of more than two triangles on the curve with an even
count, no open edge inside the box, the number of pieces, every triangle
near a dense marching-cubes sample.  One line per case and seed: PASS, or
FAIL with the check that failed.

The cases are the plane curve singularities times a line (translation
surfaces), products of two surfaces meeting in a curve, and the classical
surfaces with a singular curve.

Run from the repository root (a few minutes per seed)::

    .venv/bin/python benchmarks/sweep_curves.py [--seeds plain,3,11,30] [--only cusp,e6]

This is a sweep that prints a table, not a test.
"""

from __future__ import annotations

import argparse
import sys
import time
import traceback
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
from test_curves import check_curve_mesh, float_rotated, rotated_composed  # noqa: E402

B1 = ((-1.0, 1.0),) * 3
B15 = ((-1.5, 1.5),) * 3

#: name, equation, box, pieces of the mesh
CASES = [
    # plane curve singularities times a line
    ("cusp", "y^2 - x^3", B1, 1),
    ("tacnode", "y^2 - x^4", B1, 1),
    ("A4", "y^2 - x^5", B1, 1),
    ("D4", "x^2 y - y^3", B1, 1),
    ("E6", "x^3 - y^4", B1, 1),
    ("E7", "x^3 - x y^3", B1, 1),
    ("E8", "x^3 - y^5", B1, 1),
    ("node-line", "y^2 - x^2 (x + 1)", B15, 1),
    ("crossing-lines", "x^2 - y^2 z^2", B1, 1),
    # products of two surfaces
    ("sphere-cylinder", "(x^2 + y^2 + z^2 - 1)(x^2 + y^2 - 0.25)", B15, 1),
    ("cone-plane", "(x^2 + y^2 - z^2)(z - 0.5)", B1, 1),
    ("two-spheres", "(x^2 + y^2 + z^2 - 1)((x - 1)^2 + y^2 + z^2 - 1)", ((-1.5, 2.5), (-1.5, 1.5), (-1.5, 1.5)), 1),
    ("torus-plane", "((x^2 + y^2 + z^2 + 0.75)^2 - 4 (x^2 + y^2)) (z - 0.2)", ((-1.7, 1.7),) * 3, 1),
    ("cylinder-tangent-plane", "(x^2 + y^2 - 1)(x - 1)", B15, 1),
    ("sphere-plane", "(x^2 + y^2 + z^2 - 1) z", B15, 1),
    ("two-cylinders", "(x^2 + y^2 - 1)(x^2 + z^2 - 1)", B15, 1),
    ("sphere-cylinder-tangent", "(x^2 + y^2 + z^2 - 1)(x^2 + y^2 - 1)", B15, 1),   # a tacnode circle
    # classical surfaces
    ("whitney", "x^2 - y^2 z", B1, 1),
    ("crosscap", "4 x^2 (x^2 + y^2 + z^2 + z) + y^2 (y^2 + z^2 - 1)", ((-1.2, 1.2),) * 3, 1),
    ("roman", "x^2 y^2 + y^2 z^2 + z^2 x^2 - x y z", B1, 1),
    ("pluecker", "(x^2 + y^2) z - 2 x y", ((-1.3, 1.3),) * 3, 1),
    ("three-planes", "x y z", B1, 1),
    ("cayley-ruled", "x y - y^3 - x^2 z", B1, 1),     # Cayley's ruled cubic, double along the z-axis
    # discriminant of t^4 + x t^2 + y t + z: two cuspidal edges and a double curve from the swallowtail point
    ("swallowtail", "16 x^4 z - 4 x^3 y^2 - 128 x^2 z^2 + 144 x y^2 z - 27 y^4 + 256 z^3", B1, 1),
    # Herwig Hauser's gallery (imaginary.org, "Herwig Hauser Classic"), as
    # written there.  Each singular locus checked with sympy (Groebner basis
    # of F, grad F) and Gauss-Newton samples in the box; the curve type in
    # the comment.  Pieces None where not counted independently.
    ("kolibri", "x^3 + x^2 z^2 - y^2", B1, None),          # z-axis: double line (z != 0), cusp point at 0
    ("calyx", "x^2 + y^2 z^3 - z^4", B1, None),            # y-axis: cuspidal edge, A3 at 0
    ("daisy", "(x^2 - y^3)^2 - (z^2 - y^2)^3", B1, None),  # two cusp curves x^2 = y^3, z = +-y: cuspidal edges
    ("eistuete", "(x^2 + y^2)^3 - 4 x^2 y^2 (z^2 + 1)", B15, None),   # z-axis: four sheets, tangent in pairs
    ("helix", "6 x^2 - 2 x^4 - y^2 z^2", B15, None),       # y- and z-axes: double lines crossing at 0
    ("herz", "y^2 + z^3 - z^4 - x^2 z^2", B1, None),       # x-axis: double line, cusp point at 0
    # cusp curve z = 0, x^2 = y^3: cuspidal edge.  Not [-1, 1]^3: the line x = -1, y = 1 (where x^2 - y^3
    # and x + y^2 both vanish) lies on the surface, a fin thinner than the oracle's marching-cubes grid
    # along that box edge (169 triangles "away from the surface" unrotated).
    ("seepferdchen", "(x^2 - y^3)^2 - (x + y^2) z^3", ((-0.9, 0.9),) * 3, None),
    ("spitz", "(y^3 - x^2 - z^2)^3 - 27 x^2 y^3 z^2", B15, None),  # several curves through 0 (sympy: y^2 (x^2 +- 3xz - y^3 + z^2))
    ("wedeln", "x^3 - y (1 - z^2)^2", B15, None),          # lines x = 0, z = +-1: cuspidal edges, D4-like at y = 0
    ("xano", "x^4 + z^3 - y z^2", B1, None),               # y-axis: tacnode edge (y > 0), isolated line (y < 0)
    ("limao", "x^2 - y^3 z^3", B1, None),                  # y- and z-axes: cuspidal edges meeting at 0
    ("miau", "x^2 y z + x^2 z^2 + 2 y^3 z + 3 y^3", ((-2.0, 2.0),) * 3, None),   # x- and z-axes
    ("subway", "x^2 y^2 - (z^2 - 1)^3", B15, None),        # four lines z = +-1, xy = 0: cuspidal edges
    ("nepali", "(x y - z^3 - 1)^2 + (x^2 + y^2 - 1)^3", B15, None),   # space curve: cuspidal edge; A.. point at 0
    ("pilzchen", "(z^3 - 1)^2 + (x^2 + y^2 - 1)^3", B15, None),       # circle z = 1: cuspidal edge; point at 0
    ("berg", "x^2 + y^2 z^2 + z^3", B1, None),             # y-axis: isolated real line, cusp point at 0
    ("wigwam", "x^2 + y^2 z^3", B1, None),                 # z-axis: double (z < 0) / isolated (z > 0); y-axis: cusp edge
    ("tuelle", "y z (x^2 + y - z)", B1, 1),                # three surfaces: x-axis and two parabolas, triple point 0
    ("michelangelo", "x^2 + y^4 + y^3 z^2", B1, None),     # z-axis: cuspidal edge, A3 isolated at 0
    ("zeppelin", "x y z + y z + 2 z^5", ((-1.25, 1.25),) * 3, None),  # plane z = 0 and a quartic: lines y = 0, x = -1
    ("schneeflocke", "x^3 + y^2 z^3 + y z^4", B1, None),   # y-axis: D4 with one real sheet
    ("tobel", "x^3 z + x^2 + y z^3 + z^4 - 3 x y z", B15, None),      # y-axis
    ("geisha", "x^2 y z + x^2 z^2 - y^3 z - y^3", ((-2.0, 2.0),) * 3, None),     # x- and z-axes
    # Whitney's umbrella with other exponents
    ("whitney-y4", "x^2 - y^4 z", B1, None),               # z-axis: tacnode edge (z > 0), isolated (z < 0)
    ("whitney-y3", "x^2 z - y^3", B1, None),               # z-axis: cuspidal edge, D-type point at 0
]


def run(text: str, box, pieces: int | None, seed: int | None) -> str:
    t0 = time.perf_counter()
    try:
        if seed is None:
            check_curve_mesh(text, box, pieces)
        else:
            # The oracle evaluates the rotation composed, not the expanded
            # 15-digit polynomial (Spitz, degree 9: 7 minutes a seed
            # expanded, the mesh 23 s of it).
            check_curve_mesh(float_rotated(text, seed), box, pieces, oracle=rotated_composed(text, seed))
        return f"PASS  {time.perf_counter() - t0:6.1f}s"
    except Exception as e:  # noqa: BLE001 - a sweep reports every failure
        line = traceback.extract_tb(e.__traceback__)[-1].line
        return f"FAIL  {time.perf_counter() - t0:6.1f}s  {type(e).__name__}: {str(e)[:80] or line}"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="3,11,30")
    ap.add_argument("--only", default="")
    args = ap.parse_args(argv)
    # "plain": the equation as typed, unrotated.
    seeds = [None if s == "plain" else int(s) for s in args.seeds.split(",")]
    only = set(filter(None, args.only.split(",")))
    failed = 0
    for name, text, box, pieces in CASES:
        if only and name not in only:
            continue
        for seed in seeds:
            result = run(text, box, pieces, seed)
            failed += result.startswith("FAIL")
            print(f"{name:24s} seed {'plain' if seed is None else seed:>5}  {result}", flush=True)
    print(f"{failed} failed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
