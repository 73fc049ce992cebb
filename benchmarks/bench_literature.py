"""Named surfaces from the literature, meshed as a user would (issue #13).

For each surface: the time of ``singmesh.mesh`` at its defaults, the true
singular points found without singmesh (``nodes.find_nodes`` on the sympy
polynomial; for the degenerate points of the rotated cubics the known centre
of the rotation), how many of them are mesh vertices (within ``TOL`` of the
box size) with as many triangle fans as F = 0 has curves on a small sphere
about the point (``tests/oracles.branches_on_sphere``; 0 curves: an isolated
point, which must be reported as a singular point), the open edges (off the
box) and non-manifold edges counted from the faces, and the singular points
singmesh reports.

Coefficients as users give them: each surface is meshed from its exact text
(sqrt(2), rationals) and, where marked "15 digits", from the same polynomial
with every irrational constant printed to 15 significant digits; the rotated
cubics are composed with a numpy QR rotation and a shift and expanded with
float coefficients (the judge's ``rotated``), so their singular points exist
only up to rounding.

    .venv/bin/python benchmarks/bench_literature.py [--only togliatti,kummer05]

A benchmark that prints figures, not a test.
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import sympy
from scipy.spatial import cKDTree

import nodes
import singmesh

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
from meshcheck import boundary_edges_off_box, fans_at, non_manifold_edges  # noqa: E402
from oracles import branches_on_sphere  # noqa: E402

x, y, z = nodes.VARIABLES

#: A reference point counts as a mesh vertex within this fraction of the box
#: size: float coefficients move the points by ~1e-15 relative for nodes, by
#: up to its square root for the degenerate ones.
TOL = 1e-6


@dataclass
class Case:
    key: str
    name: str
    text: str
    expr: sympy.Expr
    box: tuple
    expected: int | None = None          # number of true singular points, when known
    points: np.ndarray | None = None     # known points (degenerate ones: no node search)
    starts: int = 24


def _d15(v) -> str:
    """A constant to 15 significant digits, as printed in a paper."""
    return f"{float(sympy.N(v, 30)):.15g}"


def _kummer(mu2: sympy.Rational, key: str, digits: bool = False) -> Case:
    """Kummer's family (x^2+y^2+z^2-mu^2)^2 - lam p q r s, lam = (3mu^2-1)/(3-mu^2),
    p, q, r, s the four tetrahedral planes (the form of nodes.SURFACES['kummer'])."""
    lam = (3 * mu2 - 1) / (3 - mu2)
    r2 = sympy.sqrt(2)
    if digits:
        r2 = sympy.Rational(_d15(r2))
        lam = sympy.Rational(_d15(lam))
    expr = (x**2 + y**2 + z**2 - mu2) ** 2 - lam * (1 - z - r2 * x) * (1 - z + r2 * x) \
        * (1 + z + r2 * y) * (1 + z - r2 * y)
    if digits:
        text = (f"(x^2+y^2+z^2-{_d15(mu2)})^2 - {_d15(lam)} (1-z-{_d15(r2)} x)(1-z+{_d15(r2)} x)"
                f"(1+z+{_d15(r2)} y)(1+z-{_d15(r2)} y)")
    else:
        text = (f"(x^2+y^2+z^2-m)^2 - l (1-z-sqrt(2) x)(1-z+sqrt(2) x)(1+z+sqrt(2) y)(1+z-sqrt(2) y);"
                f" m = {mu2}; l = (3 m - 1)/(3 - m);")
    return Case(key, f"Kummer mu^2={mu2}" + (" 15 digits" if digits else ""), text, expr,
                ((-3.0, 3.0),) * 3)


def _togliatti(digits: bool = False) -> Case:
    """Togliatti's quintic, 31 real nodes (Wikipedia after Barth; gallery/catalogue.toml)."""
    s = sympy.sqrt(5 - sympy.sqrt(5))
    c = 1 + 3 * sympy.sqrt(5)
    k = 5 * s
    if digits:
        s, c, k = (sympy.Rational(_d15(v)) for v in (s, c, k))
    quartic = (x**4 - 4 * x**3 - 10 * x**2 * y**2 - 4 * x**2 + 16 * x - 20 * x * y**2 + 5 * y**4
               + 16 - 20 * y**2)
    expr = 64 * (x - 1) * quartic - k * (2 * z - s) * (4 * (x**2 + y**2 - z**2) + c) ** 2
    q = "(x^4 - 4 x^3 - 10 x^2 y^2 - 4 x^2 + 16 x - 20 x y^2 + 5 y^4 + 16 - 20 y^2)"
    if digits:
        text = f"64 (x - 1){q} - {_d15(k)} (2 z - {_d15(s)})(4 (x^2 + y^2 - z^2) + {_d15(c)})^2"
    else:
        text = f"64 (x - 1){q} - 5 s (2 z - s)(4 (x^2 + y^2 - z^2) + 1 + 3 sqrt(5))^2; s = sqrt(5 - sqrt(5));"
    return Case("togliatti" + ("15" if digits else ""), "Togliatti quintic" + (" 15 digits" if digits else ""),
                text, expr, ((-9.0, 8.0), (-9.0, 9.0), (-4.0, 4.0)), expected=31, starts=40)


def _goursat(c: str, key: str, expected: int) -> Case:
    """x^4+y^4+z^4 - 5(x^2+y^2+z^2) + c: the tanglecube's family.  x^4 - 5x^2 has
    critical values 0 (x = 0) and -25/4 (x^2 = 5/2), so c = 25/4, 25/2, 75/4 give
    6 and 12 cone nodes and 8 isolated points (F >= 0, the whole real surface)."""
    expr = x**4 + y**4 + z**4 - 5 * (x**2 + y**2 + z**2) + sympy.Rational(c)
    return Case(key, f"Goursat c={c}", f"x^4+y^4+z^4 - 5(x^2+y^2+z^2) + {c}", expr,
                ((-3.0, 3.0),) * 3, expected=expected)


def _rotation(seed: int):
    rng = np.random.default_rng(seed)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    if np.linalg.det(q) < 0:
        q[:, 0] *= -1
    return q, rng.uniform(-0.3, 0.3, 3)


def _rotate(expr: sympy.Expr, seed: int) -> tuple[sympy.Expr, np.ndarray, np.ndarray]:
    """expr composed with a numpy QR rotation and a shift, expanded with float
    coefficients (the judge's ``cases.rotated``): a point p moves to q^T p + c."""
    q, c = _rotation(seed)
    u = [sum(float(q[i, j]) * ((x, y, z)[j] - float(c[j])) for j in range(3)) for i in range(3)]
    return sympy.expand(sympy.N(expr, 30).subs({x: u[0], y: u[1], z: u[2]}, simultaneous=True)), q, c


def _rotated(eq: str, key: str, name: str, seed: int = 7, box=((-1.0, 1.0),) * 3,
             points=((0, 0, 0),)) -> Case:
    """``eq`` rotated (:func:`_rotate`); its known singular ``points`` (None: search) move with it."""
    e = sympy.sympify(eq.replace("^", "**"), locals={"x": x, "y": y, "z": z})
    e2, q, c = _rotate(e, seed)
    text = str(e2).replace("**", "^")
    pts = None if points is None else np.asarray(points, float) @ q + c
    return Case(key, name, text, e2, box, points=pts)


def _rotated_case(case: Case, box, seed: int = 7) -> Case:
    """A nodal case rotated and expanded with float coefficients; nodes searched again."""
    e2, _, _ = _rotate(case.expr, seed)
    return Case(case.key + "rot", case.name + " rotated", str(e2).replace("**", "^"), e2, box,
                expected=case.expected, starts=case.starts)


def _chart(hom: str) -> str:
    """A projective cubic G(X, Y, Z, W) in the affine chart X + Y + Z + W = 1,
    which holds the coordinate vertices (0,0,0), (1,0,0), (0,1,0), (0,0,1)."""
    return hom.replace("W", "(1 - x - y - z)").replace("X", "x").replace("Y", "y").replace("Z", "z")


def cases() -> list[Case]:
    out = [
        _togliatti(), _togliatti(digits=True),
        _kummer(sympy.Rational(1, 2), "kummer05"), _kummer(sympy.Rational(13, 10), "kummer13"),
        _kummer(sympy.Rational(13, 10), "kummer13d", digits=True), _kummer(sympy.Rational(5, 2), "kummer25"),
        _kummer(sympy.Rational(169, 100), "kummer169d", digits=True),
        _kummer(sympy.Rational(4), "kummer4"),
        _goursat("25/4", "goursat6", 6), _goursat("25/2", "goursat12", 12), _goursat("75/4", "goursat8", 8),
    ]
    for d in (5, 6):
        s = nodes._chmutov(d)
        out.append(Case(f"chmutov{d}", s.name, s.text, s.expr, s.box, expected=s.expected, starts=32))
    # Cubic surfaces with one degenerate point (Bruce-Wall's list), rotated.
    for eq, key, name in (
        ("x^2 + y^2 + z^3", "cubicA2", "cubic A2 x^2+y^2+z^3"),
        ("x^2 - y^2 + z^3", "cubicA2m", "cubic A2 x^2-y^2+z^3"),
        ("x^2 - y^2 + x*z^2", "cubicA3", "cubic A3 x^2-y^2+xz^2"),
        ("x^2 + y^2 + x*z^2", "cubicA3p", "cubic A3 x^2+y^2+xz^2"),
        ("x^2*y - y^3 + z^2", "cubicD4", "cubic D4 x^2y-y^3+z^2"),
        ("x^2*y + y^3 + z^2", "cubicD4p", "cubic D4 x^2y+y^3+z^2"),
        ("x^2 + x*z^2 + y^3", "cubicE6", "cubic E6 x^2+xz^2+y^3"),
    ):
        out.append(_rotated(eq, key, name + " rotated"))
    # Projective cubics with several points (Cayley's / Bruce-Wall's lists) in a
    # chart holding them all (:func:`_chart`): Cayley's 4A1, 3A2 (XZW = Y^3), E6.
    for hom, key, name, pts in (
        ("X*Y*Z + X*Y*W + X*Z*W + Y*Z*W", "cayley4", "Cayley 4A1 (XYZ+XYW+XZW+YZW)",
         ((0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1))),
        ("X*Z*W - Y^3", "cubic3A2", "cubic 3A2 (XZW = Y^3)", ((0, 0, 0), (1, 0, 0), (0, 0, 1))),
        ("W*X^2 + X*Z^2 + Y^3", "cubicE6w", "cubic E6 (WX^2+XZ^2+Y^3)", ((0, 0, 0),)),
    ):
        out.append(_rotated(_chart(hom), key + "rot", name + " chart, rotated", box=((-2.0, 2.0),) * 3,
                            points=pts))
    cay = _rotated("4*(x^2+y^2+z^2) + 16*x*y*z - 1", "cayleyrot", "Cayley 4A1 rotated",
                   box=((-1.5, 1.5),) * 3, points=None)
    cay.expected = 4
    out.append(cay)
    by_key = {c.key: c for c in out}
    out.append(_rotated_case(by_key["togliatti"], ((-12.0, 12.0),) * 3))
    out.append(_rotated_case(by_key["kummer13"], ((-3.0, 3.0),) * 3))
    out.append(_rotated_case(by_key["chmutov6"], ((-1.5, 1.5),) * 3))
    out.append(_rotated_case(by_key["goursat12"], ((-3.5, 3.5),) * 3))
    g8 = _rotated_case(by_key["goursat8"], ((-3.5, 3.5),) * 3)
    g8.points = np.array([[a, b, c] for a in (-1, 1) for b in (-1, 1) for c in (-1, 1)], float) \
        * np.sqrt(2.5) @ _rotation(7)[0] + _rotation(7)[1]
    out.append(g8)
    # Nodes on the box's faces, edges and corners (boxes cut at symmetry planes).
    for case, box, tag in ((by_key["goursat12"], ((-3.0, 3.0), (-3.0, 3.0), (0.0, 3.0)), "z >= 0"),
                           (by_key["goursat12"], ((0.0, 3.0), (0.0, 3.0), (0.0, 3.0)), "octant"),
                           (by_key["chmutov6"], ((0.0, 1.25), (0.0, 1.25), (0.0, 1.25)), "octant")):
        out.append(Case(case.key + "cut", f"{case.name} {tag}", case.text, case.expr, box, starts=case.starts))
    c = nodes.SURFACES["cayley"]
    out.append(Case("cayleycorners", "Cayley, nodes at box corners", c.text, c.expr, ((-0.5, 0.5),) * 3,
                    points=np.array([[a, b, -2 * a * b] for a in (-0.5, 0.5) for b in (-0.5, 0.5)])))
    barth = nodes.SURFACES["barth"]
    out.append(_rotated_case(Case("barth", barth.name, barth.text, barth.expr, barth.box, expected=None,
                                  starts=32), ((-2.0, 2.0),) * 3))
    return out


def reference(case: Case) -> np.ndarray:
    if case.points is not None:
        return case.points
    return nodes.find_nodes(case.expr, case.box, starts=case.starts).reshape(-1, 3)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--only", help="comma-separated keys")
    args = p.parse_args(argv)
    todo = cases()
    if args.only:
        keys = args.only.split(",")
        todo = [c for c in todo if c.key in keys]
    print(f"| surface | true points | time s | vertices with right fans | isolated reported "
          f"| open | non-manifold | reported | worst |")
    print("|---|---|---|---|---|---|---|---|---|")
    for case in todo:
        true = reference(case)
        note = ""
        if case.expected is not None and len(true) != case.expected:
            note = f" (reference search: {len(true)}, expected {case.expected})"
        t0 = time.perf_counter()
        try:
            m = singmesh.mesh(case.text, case.box)
        except Exception as exc:  # a benchmark: report and go on
            print(f"| {case.name} | {len(true)} | error: {type(exc).__name__}: {str(exc)[:80]} |", flush=True)
            continue
        t = time.perf_counter() - t0
        size = float(np.max(np.ptp(np.array(case.box, float), axis=1)))
        f = nodes._numeric(case.expr).f
        sing = np.array([s.point for s in m.singularities]).reshape(-1, 3)
        ok = iso_ok = n_iso = 0
        worst = []
        tree = cKDTree(m.vertices) if len(m.vertices) else None
        for i, pt in enumerate(true):
            others = np.delete(true, i, axis=0)
            gap = float(np.min(np.linalg.norm(others - pt, axis=1))) if len(others) else size
            radius = min(0.02 * size, 0.3 * gap)
            want = branches_on_sphere(f, pt, radius, n_lat=360, n_lon=720, box=case.box)
            if want == 0:
                n_iso += 1
                if len(sing) and np.min(np.linalg.norm(sing - pt, axis=1)) <= TOL * size:
                    iso_ok += 1
                else:
                    worst.append(f"{np.round(pt, 4).tolist()}: isolated, not reported")
                continue
            d, idx = tree.query(pt) if tree is not None else (np.inf, -1)
            got = fans_at(m.faces, int(idx)) if d <= TOL * size else None
            if got == want:
                ok += 1
            else:
                worst.append(f"{np.round(pt, 4).tolist()}: {want} curves, "
                             + (f"vertex {d:.1e} away with {got} fans" if got is not None
                                else f"nearest vertex {d:.1e} away"))
        n_cone = len(true) - n_iso
        print(f"| {case.name}{note} | {len(true)} | {t:.2f} | {ok}/{n_cone} | {iso_ok}/{n_iso} | "
              f"{len(boundary_edges_off_box(m.vertices, m.faces, case.box))} | "
              f"{len(non_manifold_edges(m.faces))} | {len(m.singularities)} | "
              f"{'; '.join(worst[:2])} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
