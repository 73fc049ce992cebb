"""True singular points of the benchmark surfaces, found without singmesh.

The benchmark (and tests) measure how close a mesher gets to the nodes of
Cayley's cubic, Kummer's quartic and the Barth sextic.  The reference
points must not come from singmesh's own singular point finder, nor from
its parser: a bug there would otherwise be measured against itself.  So
the polynomials are written here directly as sympy expressions and the
nodes are computed from them:

* Cayley: the four points (+-1/2, +-1/2, +-1/2) with an odd number of
  minus signs, checked exactly (rational arithmetic) to satisfy
  F = grad F = 0.
* Kummer, Barth: the system F = grad F = 0 (four equations, three
  unknowns) is solved numerically from a grid of starting points by a
  vectorised Levenberg-Marquardt iteration, the results are polished by
  Newton's method on grad F = 0, kept when the residuals are at rounding
  level, de-duplicated and clipped to the box.  The counts are checked
  against the known ones (16 real nodes for this Kummer surface, 50 real
  affine nodes of the Barth sextic inside [-2, 2]^3).

Nothing is cached on disk: everything is recomputed on each call (about two
seconds for all three surfaces).

Examples
--------
>>> from nodes import SURFACES, true_nodes
>>> true_nodes("barth").shape
(50, 3)
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import sympy

x, y, z = sympy.symbols("x y z", real=True)
VARIABLES = (x, y, z)

_sqrt2 = sympy.sqrt(2)
_phi = (1 + sympy.sqrt(5)) / 2


@dataclass(frozen=True)
class NodalSurface:
    """A benchmark surface with a known number of real nodes in its box.

    Attributes
    ----------
    name : str
    text : str
        The equation in SingSurf syntax, as given to singmesh.
    expr : sympy.Expr
        The same polynomial written independently as a sympy expression
        (the reference; it does not go through singmesh's parser).
    box : tuple of three (lo, hi) pairs
    expected : int
        Number of real nodes inside the box.
    """

    name: str
    text: str
    expr: sympy.Expr
    box: tuple
    expected: int


SURFACES = {
    "cayley": NodalSurface(
        name="Cayley cubic",
        # "16 x y z", not "16xyz": the parser reads "xyz" as one name.
        text="4(x^2+y^2+z^2) + 16 x y z - 1",
        expr=4 * (x**2 + y**2 + z**2) + 16 * x * y * z - 1,
        box=((-1.5, 1.5),) * 3,
        expected=4,
    ),
    "kummer": NodalSurface(
        name="Kummer quartic",
        text="(x^2+y^2+z^2-1.69)^2 - 407/131 (1-z-sqrt(2) x)(1-z+sqrt(2) x)"
             "(1+z+sqrt(2) y)(1+z-sqrt(2) y)",
        expr=(x**2 + y**2 + z**2 - sympy.Rational(169, 100)) ** 2
        - sympy.Rational(407, 131)
        * (1 - z - _sqrt2 * x) * (1 - z + _sqrt2 * x)
        * (1 + z + _sqrt2 * y) * (1 + z - _sqrt2 * y),
        box=((-2.5, 2.5),) * 3,
        expected=16,
    ),
    "barth": NodalSurface(
        name="Barth sextic",
        text="4(t^2 x^2-y^2)(t^2 y^2-z^2)(t^2 z^2-x^2) - (1+2t)(x^2+y^2+z^2-1)^2;"
             " t = (1+sqrt(5))/2;",
        expr=4 * (_phi**2 * x**2 - y**2) * (_phi**2 * y**2 - z**2) * (_phi**2 * z**2 - x**2)
        - (1 + 2 * _phi) * (x**2 + y**2 + z**2 - 1) ** 2,
        box=((-2.0, 2.0),) * 3,
        expected=50,
    ),
}


#: Surfaces with hundreds of nodes (benchmarks/bench_many_nodes.py), written
#: from the literature; their node counts inside the box are what
#: :func:`find_nodes` finds with ``starts`` starting points per axis (the
#: Barth decic has 345 nodes, 300 of them real in [-2, 2]^3; the Endrass
#: octic has 168 nodes, all real: 144 affine, all in [-3, 3]^3 (no other
#: in [-12, 12]^3), and 24 at infinity (w = 0, in the chart z = 1 at
#: (x, y) = (+-1, +-1), (+-1, +-0.414214), (+-0.414214, +-1), (+-1.414214, 0),
#: (0, +-1.414214), (+-0.91018, 0), (0, +-0.91018), (+-0.643594, +-0.643594)),
#: which no box holds).
LARGE = {
    "barth10": NodalSurface(
        name="Barth decic",
        text="8 (x^2-t^4 y^2)(y^2-t^4 z^2)(z^2-t^4 x^2)(x^4+y^4+z^4-2 x^2 y^2-2 x^2 z^2-2 y^2 z^2)"
             " + (3+5t)(x^2+y^2+z^2-1)^2 (x^2+y^2+z^2-(2-t))^2; t = (1+sqrt(5))/2;",
        expr=8 * (x**2 - _phi**4 * y**2) * (y**2 - _phi**4 * z**2) * (z**2 - _phi**4 * x**2)
        * (x**4 + y**4 + z**4 - 2 * x**2 * y**2 - 2 * x**2 * z**2 - 2 * y**2 * z**2)
        + (3 + 5 * _phi) * (x**2 + y**2 + z**2 - 1) ** 2 * (x**2 + y**2 + z**2 - (2 - _phi)) ** 2,
        box=((-2.0, 2.0),) * 3,
        expected=300,
    ),
    "endrass": NodalSurface(
        name="Endrass octic",
        text="64(x^2-1)(y^2-1)((x+y)^2-2)((x-y)^2-2)"
             " - (a (x^2+y^2)^2 + (b z^2 + c)(x^2+y^2) - 16 z^4 + d z^2 + f)^2;"
             " a = -4(1+sqrt(2)); b = 8(2+sqrt(2)); c = 2(2+7sqrt(2)); d = 8(1-2sqrt(2)); f = -(1+12sqrt(2));",
        expr=64 * (x**2 - 1) * (y**2 - 1) * ((x + y) ** 2 - 2) * ((x - y) ** 2 - 2)
        - (-4 * (1 + _sqrt2) * (x**2 + y**2) ** 2 + (8 * (2 + _sqrt2) * z**2 + 2 * (2 + 7 * _sqrt2)) * (x**2 + y**2)
           - 16 * z**4 + 8 * (1 - 2 * _sqrt2) * z**2 - (1 + 12 * _sqrt2)) ** 2,
        box=((-3.0, 3.0),) * 3,
        expected=144,
    ),
}


def _labs_septic() -> NodalSurface:
    """Labs' septic with 99 real nodes (O. Labs, "A septic with 99 real
    nodes", Rend. Sem. Mat. Univ. Padova 116 (2006)), in the chart w = 1.

    P - (z + a5) ((z + 1)(x^2 + y^2) + a1 z^3 + a2 z^2 + a3 z + a4)^2, P the
    product of seven planes through the z-axis (D7 symmetry) written out,
    the a_i polynomials in the real root al ~ -0.1401 of 7 al^3 + 7 al + 1.
    The text gives al by Cardano's formula; the reference takes the root
    from sympy to 50 digits.  The nodes: one on the axis at (0, 0, -1) and
    14 orbits of 7; the outermost orbit lies at radius 11.75 and height
    10.52 (all 99 inside [-12, 12]^3; [-6, 6]^3 holds 92).  Nodes of
    neighbouring orbits near z = -0.5 are 0.11 to 0.21 apart: in [-12, 12]^3
    that is 1.2 to 2.3 boxes of the point search (level 8), and five nodes
    of the orbit at radius 0.498, z = -0.5598, are not found there (Newton
    from their boxes lands on a neighbour; level 9 finds all 99, and
    singmesh's search now goes a level deeper where points crowd).
    """
    a = sympy.Symbol("a")
    al = sympy.Float(sympy.CRootOf(7 * a**3 + 7 * a + 1, 0).evalf(50), 50)
    a1 = -sympy.Rational(12, 7) * al**2 - sympy.Rational(384, 49) * al - sympy.Rational(8, 7)
    a2 = -sympy.Rational(32, 7) * al**2 + sympy.Rational(24, 49) * al - 4
    a3 = -4 * al**2 + sympy.Rational(24, 49) * al - 4
    a4 = -sympy.Rational(8, 7) * al**2 + sympy.Rational(8, 49) * al - sympy.Rational(8, 7)
    a5 = 49 * al**2 - 7 * al + 50
    r2 = x**2 + y**2
    p = (x * (x**6 - 21 * x**4 * y**2 + 35 * x**2 * y**4 - 7 * y**6)
         + 7 * z * (r2**3 - 8 * z**2 * r2**2 + 16 * z**4 * r2) - 64 * z**7)
    return NodalSurface(
        name="Labs septic",
        text="x (x^6 - 21 x^4 y^2 + 35 x^2 y^4 - 7 y^6)"
             " + 7 z ((x^2+y^2)^3 - 8 z^2 (x^2+y^2)^2 + 16 z^4 (x^2+y^2)) - 64 z^7"
             " - (z + a5) ((z + 1)(x^2+y^2) + a1 z^3 + a2 z^2 + a3 z + a4)^2;"
             " s = sqrt(1/196 + 1/27); al = (s - 1/14)^(1/3) - (s + 1/14)^(1/3);"
             " a1 = -12/7 al^2 - 384/49 al - 8/7; a2 = -32/7 al^2 + 24/49 al - 4;"
             " a3 = -4 al^2 + 24/49 al - 4; a4 = -8/7 al^2 + 8/49 al - 8/7; a5 = 49 al^2 - 7 al + 50;",
        expr=p - (z + a5) * ((z + 1) * r2 + a1 * z**3 + a2 * z**2 + a3 * z + a4) ** 2,
        box=((-12.0, 12.0),) * 3,
        expected=99,
    )


LARGE["labs7"] = _labs_septic()


def _chebyshev_text(d: int, v: str) -> str:
    """T_d(v) written out, its integer coefficients from the recurrence
    T_{k+1} = 2 v T_k - T_{k-1} (not from sympy, which gives the reference)."""
    prev, cur = [1], [0, 1]
    for _ in range(d - 1):
        nxt = [0] + [2 * c for c in cur]
        for i, c in enumerate(prev):
            nxt[i] -= c
        prev, cur = cur, nxt
    cur = cur if d > 0 else prev
    terms = [f"{'-' if c < 0 else '+'} {abs(c)} {v}^{e}" for e, c in enumerate(cur) if c]
    return "(" + " ".join(reversed(terms)) + ")"


def _chmutov(d: int) -> NodalSurface:
    """Chmutov's surface T_d(x) + T_d(y) + T_d(z) + 1 = 0 (T_d Chebyshev).

    Its singular points are the critical points of the T_d where two of
    them are -1 and one is +1: for even d, 3 (d/2)^2 (d/2 - 1) nodes; for
    odd d, 3 ((d-1)/2)^3; all in (-1, 1)^3, some on the planes x, y or z = 0.
    """
    h = d // 2
    count = 3 * h * h * (h - 1) if d % 2 == 0 else 3 * h ** 3
    return NodalSurface(
        name=f"Chmutov {d}",
        text=" + ".join(_chebyshev_text(d, v) for v in "xyz") + " + 1",
        expr=sympy.chebyshevt(d, x) + sympy.chebyshevt(d, y) + sympy.chebyshevt(d, z) + 1,
        box=((-1.25, 1.25),) * 3,
        expected=count,
    )


#: Chmutov's surfaces (benchmarks/bench_many_nodes.py): 81 nodes at degree
#: 7, 144 at 8, 192 at 9 (counts checked by :func:`find_nodes` with 32
#: starts per axis), 300 at 10.
LARGE.update({f"chmutov{d}": _chmutov(d) for d in (7, 8, 9, 10)})


# ---------------------------------------------------------------- evaluation
class _Numeric:
    """Vectorised F, grad F and Hessian of a polynomial given by sympy.

    The polynomial is turned into a list of terms (coefficient, exponents)
    and evaluated from tables of powers; derivatives act on the term list.
    This is its own small evaluator (no singmesh code) and, unlike
    ``sympy.lambdify`` of the expanded expression, costs a few array
    products per term.
    """

    def __init__(self, expr: sympy.Expr):
        poly = sympy.Poly(sympy.expand(expr), *VARIABLES)
        terms = poly.terms()
        self.exps = np.array([m for m, _ in terms], dtype=int).reshape(-1, 3)
        # 30 digits before rounding: sqrt(5), 407/131 etc. round once.
        self.coeffs = np.array([float(sympy.N(c, 30)) for _, c in terms], dtype=float)
        self.degree = int(self.exps.max()) if len(self.exps) else 0

    def _terms(self, p, coeffs, exps):
        """sum_t coeffs[t] * x^e0 y^e1 z^e2 at every point of ``p``."""
        powers = np.ones(p.shape + (self.degree + 1,))
        for k in range(1, self.degree + 1):
            powers[..., k] = powers[..., k - 1] * p
        mono = powers[..., 0, exps[:, 0]] * powers[..., 1, exps[:, 1]] * powers[..., 2, exps[:, 2]]
        return mono @ coeffs

    def _derivative(self, coeffs, exps, axis):
        c = coeffs * exps[:, axis]
        e = exps.copy()
        e[:, axis] = np.maximum(e[:, axis] - 1, 0)
        keep = c != 0
        return c[keep], e[keep]

    def f(self, p):
        return self._terms(p, self.coeffs, self.exps)

    def grad(self, p):
        cols = []
        for a in range(3):
            c, e = self._derivative(self.coeffs, self.exps, a)
            cols.append(self._terms(p, c, e))
        return np.stack(cols, axis=-1)

    def hessian(self, p):
        h = np.empty(p.shape[:-1] + (3, 3))
        for a in range(3):
            ca, ea = self._derivative(self.coeffs, self.exps, a)
            for b in range(a, 3):
                cb, eb = self._derivative(ca, ea, b)
                h[..., a, b] = h[..., b, a] = self._terms(p, cb, eb)
        return h

    def magnitude(self, p):
        """Sum of |terms| of F: the scale of F's rounding error."""
        return self._terms(np.abs(p), np.abs(self.coeffs), self.exps)

    def grad_magnitude(self, p):
        """Norm of the sums of |terms| of the three partial derivatives."""
        cols = []
        for a in range(3):
            c, e = self._derivative(self.coeffs, self.exps, a)
            cols.append(self._terms(np.abs(p), np.abs(c), e))
        return np.linalg.norm(np.stack(cols, axis=-1), axis=-1)


@lru_cache(maxsize=None)
def _numeric(expr: sympy.Expr) -> _Numeric:
    return _Numeric(expr)


# ---------------------------------------------------------------- solving
def _levenberg_marquardt(num: _Numeric, p: np.ndarray, iterations: int) -> np.ndarray:
    """Minimise F^2 + |grad F|^2 from every row of ``p`` at once.

    Each start has its own damping: doubled when a step fails to lower
    the residual (the step is then rejected), divided by three otherwise.
    """
    lam = np.full(len(p), 1e-3)

    def residual(q):
        return np.concatenate([num.f(q)[:, None], num.grad(q)], axis=1)

    r = residual(p)
    cost = np.einsum("ij,ij->i", r, r)
    eye = np.eye(3)
    for _ in range(iterations):
        jac = np.concatenate([num.grad(p)[:, None, :], num.hessian(p)], axis=1)  # (n, 4, 3)
        jtj = np.einsum("nki,nkj->nij", jac, jac)
        jtr = np.einsum("nki,nk->ni", jac, r)
        # Damping scaled by the diagonal keeps the step size-invariant.
        diag = np.einsum("nii->ni", jtj)
        a = jtj + lam[:, None, None] * (eye * (diag[:, None, :] + 1e-30))
        try:
            step = np.linalg.solve(a, -jtr[..., None])[..., 0]
        except np.linalg.LinAlgError:  # a singular start: damp harder
            step = np.zeros_like(p)
        q = p + step
        rq = residual(q)
        cq = np.einsum("ij,ij->i", rq, rq)
        better = np.isfinite(cq) & (cq < cost)
        p = np.where(better[:, None], q, p)
        r = np.where(better[:, None], rq, r)
        cost = np.where(better, cq, cost)
        lam = np.where(better, lam / 3, lam * 2)
        lam = np.clip(lam, 1e-12, 1e12)
    return p


def _newton_on_gradient(num: _Numeric, p: np.ndarray, iterations: int = 12) -> np.ndarray:
    """Polish critical points by Newton's method on grad F = 0.

    At an ordinary node the Hessian is invertible, so this converges
    quadratically to full precision where LM only crawls.  Twelve steps:
    after six, four of Labs' septic's nodes were still 1e-8 to 2e-7 off
    (gradient 5e-10 of its terms, inside ``rtol``) and counted as missed.
    """
    for _ in range(iterations):
        h = num.hessian(p)
        g = num.grad(p)
        ok = np.abs(np.linalg.det(h)) > 1e-300
        step = np.zeros_like(p)
        if ok.any():
            step[ok] = np.linalg.solve(h[ok], -g[ok][..., None])[..., 0]
        p = p + step
    return p


def _dedupe(points: np.ndarray, radius: float) -> np.ndarray:
    """One representative per cluster of points closer than ``radius``."""
    kept: list[np.ndarray] = []
    for q in points:
        if not kept or np.min(np.linalg.norm(np.asarray(kept) - q, axis=1)) > radius:
            kept.append(q)
    return np.asarray(kept, dtype=float).reshape(-1, 3)


def find_nodes(expr: sympy.Expr, box, starts: int = 16, iterations: int = 40,
               rtol: float = 1e-9) -> np.ndarray:
    """Real solutions of F = grad F = 0 inside ``box``, by many local solves.

    Parameters
    ----------
    expr : sympy.Expr
        The polynomial F in the symbols ``x, y, z`` of this module
        (``real=True``); others with the same names are matched by name.
    box : three (lo, hi) pairs
    starts : int
        Starting points per axis (cell centres of a uniform grid, plus a
        margin of one cell outside the box so that points near its faces
        are reached from both sides).
    iterations : int
        Levenberg-Marquardt iterations before the Newton polish.
    rtol : float
        A point is a solution when ``|F| <= rtol * sum|terms of F|`` and
        ``|grad F| <= rtol * sum|terms of grad F|`` there (rounding level
        for these degrees is about 1e-14; 1e-9 leaves room).

    Returns
    -------
    (k, 3) ndarray
        Sorted lexicographically.
    """
    by_name = {s.name: s for s in expr.free_symbols}
    expr = expr.subs({by_name[v.name]: v for v in VARIABLES if v.name in by_name})
    num = _numeric(expr)
    b = np.asarray(box, dtype=float).reshape(3, 2)
    size = float(np.max(b[:, 1] - b[:, 0]))
    axes = []
    for lo, hi in b:
        h = (hi - lo) / starts
        axes.append(np.linspace(lo - h / 2, hi + h / 2, starts + 2))
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)

    p = _levenberg_marquardt(num, grid, iterations)
    p = _newton_on_gradient(num, p)
    finite = np.isfinite(p).all(axis=1)
    p = p[finite]

    # Residuals relative to the size of the terms summed: scale-free.
    f = np.abs(num.f(p))
    g = np.linalg.norm(num.grad(p), axis=1)
    mag_f = num.magnitude(p)
    mag_g = num.grad_magnitude(p)
    good = (f <= rtol * np.maximum(mag_f, 1e-300)) & (g <= rtol * np.maximum(mag_g, 1e-300))
    inside = np.all((p >= b[:, 0] - 1e-9 * size) & (p <= b[:, 1] + 1e-9 * size), axis=1)
    # The best polished start of each cluster stands for it: the first one
    # may have stopped 2e-8 off (two of Labs' septic's nodes at radius 5,
    # gradient 5e-4 there against 2e-10 at the node).
    keep = good & inside
    rank = np.argsort(g[keep] / np.maximum(mag_g[keep], 1e-300), kind="stable")
    nodes = _dedupe(p[keep][rank], 1e-6 * size)
    order = np.lexsort(nodes.T[::-1])
    return nodes[order]


# ---------------------------------------------------------------- the three
def cayley_nodes() -> np.ndarray:
    """The four nodes of Cayley's cubic, checked exactly.

    Returns
    -------
    (4, 3) ndarray
        (+-1/2, +-1/2, +-1/2) with an odd number of minus signs.

    Raises
    ------
    AssertionError
        If one of them is not a singular point (exact rational check).
    """
    expr = SURFACES["cayley"].expr
    half = sympy.Rational(1, 2)
    pts = []
    for sx in (1, -1):
        for sy in (1, -1):
            for sz in (1, -1):
                if sx * sy * sz < 0:  # odd number of minus signs
                    pts.append((sx * half, sy * half, sz * half))
    for pt in pts:
        at = dict(zip(VARIABLES, pt))
        values = [expr.subs(at)] + [sympy.diff(expr, v).subs(at) for v in VARIABLES]
        assert all(v == 0 for v in values), f"{pt} is not a singular point: {values}"
    return np.array(pts, dtype=float)


def true_nodes(key: str, check: bool = True) -> np.ndarray:
    """The real nodes of ``SURFACES[key]`` inside its box.

    Parameters
    ----------
    key : {"cayley", "kummer", "barth"}
    check : bool
        Raise if the number found differs from the known one.

    Returns
    -------
    (k, 3) ndarray

    Raises
    ------
    RuntimeError
        If ``check`` and the count is wrong.
    """
    s = SURFACES[key]
    nodes = cayley_nodes() if key == "cayley" else find_nodes(s.expr, s.box)
    if check and len(nodes) != s.expected:
        raise RuntimeError(f"{s.name}: found {len(nodes)} real nodes in the box, "
                           f"expected {s.expected}")
    return nodes


def residuals(key: str, points) -> tuple[np.ndarray, np.ndarray]:
    """|F| and |grad F| at ``points``, each relative to the sum of |terms|.

    Used to check points (from any source) against the reference
    polynomial of ``SURFACES[key]``.
    """
    num = _numeric(SURFACES[key].expr)
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    f = np.abs(num.f(p)) / np.maximum(num.magnitude(p), 1e-300)
    mag_g = num.grad_magnitude(p)
    g = np.linalg.norm(num.grad(p), axis=1) / np.maximum(mag_g, 1e-300)
    return f, g


def hessian_eigenvalues(key: str, points) -> np.ndarray:
    """Eigenvalues of the Hessian of F at ``points``, shape (k, 3).

    An ordinary node (A1) has three nonzero ones of mixed sign.
    """
    num = _numeric(SURFACES[key].expr)
    return np.linalg.eigvalsh(num.hessian(np.asarray(points, dtype=float).reshape(-1, 3)))


if __name__ == "__main__":
    import time

    for key, s in SURFACES.items():
        t0 = time.perf_counter()
        n = true_nodes(key, check=False)
        dt = time.perf_counter() - t0
        f, g = residuals(key, n)
        ev = hessian_eigenvalues(key, n) if len(n) else np.zeros((0, 3))
        ordinary = int(np.sum((np.abs(ev).min(axis=1) > 1e-8) & (ev.min(axis=1) < 0) & (ev.max(axis=1) > 0)))
        print(f"{s.name:15s} {len(n):3d} nodes (expected {s.expected:2d}), "
              f"{ordinary} ordinary, max rel |F| {f.max():.1e}, |grad F| {g.max():.1e}, {dt:.2f} s")
