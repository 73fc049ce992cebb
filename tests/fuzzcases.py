"""Random surfaces and boxes for fuzzing, and a judge of their meshes.

Used by ``tests/test_fuzz.py`` (a fast seeded sample) and by
``benchmarks/fuzz.py`` (a thousand cases, ``make fuzz``).

The generator (:func:`make_case`) is seeded and deterministic: case ``i``
of seed ``s`` is the same on every machine.  It writes equations the way
users type them (``3/7*x^2*y``, ``0.123456789012345*z``, products and
powers left unexpanded) and keeps the exact polynomial beside them as
sympy rationals (a decimal means the number it spells).

The judge (:func:`judge`) looks only at the vertices and triangles and at
F computed here from that exact polynomial (sympy, numpy): it does not
use the mesher's report, its Bernstein code or its singular points.

* no exception, no NaN, indices in range;
* no zero-area triangle (:func:`meshcheck.degenerate_triangles` and
  :func:`meshcheck.tiny_triangles`), no two vertices closer than 1e-9 of
  the box (:func:`meshcheck.close_vertex_pairs`);
* every vertex on the surface: |F| / |grad F| <= 1e-9 of the box, plus the
  rounding of evaluating F in doubles (eps times the sum of |terms|);
* topology, away from the singular points found here (Gauss-Newton on
  F = grad F = 0 from the local minima of |F|^2 + |grad F|^2 on a grid):
  no open edge inside the box, no edge with more than two triangles.  For
  a product f g the curve f = g = 0 is singular: there an edge may have
  four triangles (two sheets crossing), never one or three;
* no piece of the surface left out: roots of F on every second line of
  the fine lattice (bisected sign changes) lie within ``UNCOVERED`` fine cells of a
  triangle, or half the longest edge of the nearest triangle where the
  mesh is coarse (a chord's sag);
* a mesh with triangles exactly when F changes sign in the box: a dense
  grid plus random points decide "changes sign"; a mesh without that is
  checked again with points beside its vertices (a thin region the grid
  missed) and with Bernstein bounds on 8^3 sub-boxes (F has no zero).
"""

from __future__ import annotations

import random
import re
import time
import warnings
from dataclasses import dataclass, field
from fractions import Fraction
from math import comb

import numpy as np
import sympy as sp
from scipy import ndimage

import meshcheck as mc

X, Y, Z = sp.symbols("x y z", real=True)
XYZ = (X, Y, Z)

#: Kinds of equations, in the order the generator cycles through them.
KINDS = ("rational", "float", "product", "sphere")
#: Kinds of boxes.
BOXES = ("symmetric", "unit", "random")

#: Radius (fraction of the box's largest side) around a singular point
#: inside which the topology is not judged: the mesher's cone / star is
#: built there, checked by the singular-point tests, not by this judge.
NEAR_POINT = 0.05
#: Distance (fine cells) from the mesh beyond which a root of F on a
#: lattice line is a piece of surface left out (a sliver thinner than a
#: cell may be cut short, nothing larger).
UNCOVERED = 1.5

#: Distance (fraction of the box) from the curve f = g = 0 of a product
#: within which an edge may have four triangles.
NEAR_CURVE = 0.02


@dataclass
class Case:
    """One fuzz case: the equation as typed, its exact polynomial, a box."""

    name: str
    text: str
    poly: sp.Expr
    box: tuple
    kind: str
    factors: tuple = ()

    def box_array(self) -> np.ndarray:
        return np.array(self.box, float)


# --------------------------------------------------------------- generator

def _rational(rng: random.Random) -> Fraction:
    num = rng.choice([i for i in range(-9, 10) if i])
    return Fraction(num, rng.choice([1, 1, 2, 3, 4, 5, 7, 8]))


def _decimal(rng: random.Random) -> str:
    """A coefficient with 15 significant digits, as users paste them."""
    v = rng.uniform(-3, 3)
    return f"{v:.15g}" if abs(v) > 1e-3 else "0.5"


def _monomials(degree: int):
    return [(i, j, k) for i in range(degree + 1) for j in range(degree + 1 - i)
            for k in range(degree + 1 - i - j)]


def _term_text(coef: str, exps) -> str:
    parts = [coef] if coef is not None else []
    for v, e in zip("xyz", exps):
        if e == 1:
            parts.append(v)
        elif e > 1:
            parts.append(f"{v}^{e}")
    return "*".join(parts) if parts else "1"


def _poly(rng: random.Random, degree: int, floats: bool, constant: bool = True):
    """A random polynomial of total degree ``degree``: (text, sympy expr)."""
    mons = _monomials(degree)
    top = [m for m in mons if sum(m) == degree]
    chosen = {rng.choice(top)}
    for _ in range(rng.randint(1, 5)):
        chosen.add(rng.choice([m for m in mons if sum(m) >= 1]))
    if constant and rng.random() < 0.75:
        chosen.add((0, 0, 0))
    texts, expr = [], sp.Integer(0)
    for m in sorted(chosen, key=lambda m: (-sum(m), m)):
        if floats:
            c = _decimal(rng)
            value = sp.Rational(c)
        else:
            f = _rational(rng)
            c = str(f)
            value = sp.Rational(f.numerator, f.denominator)
        texts.append(_term_text(c, m) if m != (0, 0, 0) else c)
        expr += value * X ** m[0] * Y ** m[1] * Z ** m[2]
    text = " + ".join(texts).replace("+ -", "- ")
    return text, sp.expand(expr)


def _box(rng: random.Random, kind: str):
    if kind == "unit":
        return ((-1.0, 1.0),) * 3
    if kind == "symmetric":
        # Symmetric about 0: the first split planes go through x, y, z = 0,
        # where the random equations have their zeros and special points.
        return tuple((-a, a) for a in (rng.choice([0.5, 1.0, 1.5, 2.0]) for _ in range(3)))
    out = []
    for _ in range(3):
        lo = rng.uniform(-2.0, 1.0)
        w = rng.uniform(0.3, 3.0)
        if rng.random() < 0.5:
            lo, w = round(lo, 2), round(w, 2)
        out.append((lo, lo + w))
    return tuple(out)


def _irreducible(poly: sp.Expr) -> bool:
    """One factor over Q, of multiplicity one: no singular curve from a
    product or a repeated factor (a random sum of monomials without a
    constant term is often x y (...)); the products are their own kind."""
    _, factors = sp.factor_list(poly, *XYZ)
    return len(factors) == 1 and factors[0][1] == 1 and sp.Poly(poly, *XYZ).total_degree() >= 1


def make_case(seed: int, index: int) -> Case:
    """Case ``index`` of the random stream ``seed``: the same everywhere."""
    rng = random.Random(f"singmesh-fuzz-{seed}-{index}")
    kind = KINDS[index % len(KINDS)]
    boxkind = BOXES[(index // len(KINDS)) % len(BOXES)]
    factors = ()
    if kind in ("rational", "float"):
        while True:
            text, poly = _poly(rng, rng.randint(1, 6), kind == "float")
            if _irreducible(poly):
                break
    elif kind == "product":
        while True:
            d1 = rng.randint(1, 3)
            d2 = rng.randint(1, min(3, 6 - d1))
            t1, f1 = _poly(rng, d1, rng.random() < 0.3)
            t2, f2 = _poly(rng, d2, rng.random() < 0.3)
            if (_irreducible(f1) and _irreducible(f2)
                    and sp.gcd(sp.Poly(f1, *XYZ), sp.Poly(f2, *XYZ)).total_degree() == 0):
                break
        text, poly, factors = f"({t1})*({t2})", sp.expand(f1 * f2), (f1, f2)
    else:
        while True:
            k = rng.randint(1, 3)
            t1, f1 = _poly(rng, rng.randint(1, 6 - k), rng.random() < 0.3, constant=False)
            c = _rational(rng)
            r = Fraction(rng.randint(1, 16), rng.choice([4, 8, 16]))
            sphere = "(x^2+y^2+z^2)" + (f"^{k}" if k > 1 else "")
            text = f"{t1} + {c}*{sphere} - {r}".replace("+ -", "- ")
            poly = sp.expand(f1 + sp.Rational(c.numerator, c.denominator) * (X**2 + Y**2 + Z**2) ** k
                             - sp.Rational(r.numerator, r.denominator))
            if _irreducible(poly):
                break
    box = _box(rng, boxkind)
    return Case(f"s{seed}-{index}-{kind}-{boxkind}", text, poly, box, kind, factors)


def case_from_text(name: str, text: str, box) -> Case:
    """A case from an equation as typed (``^`` powers, ``*`` products,
    decimals taken as the numbers they spell); a top-level product of
    parenthesised factors keeps its factors, for the curve they share."""
    loc = {"x": X, "y": Y, "z": Z}

    def parse(t):
        t = re.sub(r"\d+\.\d*", lambda m: f"Rational('{m.group()}')", t.replace("^", "**"))
        return sp.expand(sp.parse_expr(t, local_dict=loc | {"Rational": sp.Rational}))

    factors = ()
    if text.startswith("(") and ")*(" in text and text.endswith(")") and text.count(")*(") == 1:
        a, b = text[1:-1].split(")*(")
        factors = (parse(a), parse(b))
    kind = "product" if factors else "rational"
    return Case(name, text, parse(text), tuple(tuple(map(float, b)) for b in box), kind, factors)


def cases(seed: int, n: int):
    """The first ``n`` cases of stream ``seed``."""
    return [make_case(seed, i) for i in range(n)]


# ------------------------------------------------------------------ oracle

class Field:
    """F, grad F and the rounding scale of F, vectorised over (..., 3)."""

    def __init__(self, poly: sp.Expr):
        p = sp.Poly(poly, *XYZ)
        self.monoms = np.array(p.monoms(), dtype=np.int64).reshape(-1, 3)
        self.coeffs = np.array([float(c) for c in p.coeffs()])
        self.degree = p.total_degree()

    def _powers(self, pts):
        pts = np.asarray(pts, float)
        d = max(self.degree, 1)
        pw = pts[..., None, :] ** np.arange(d + 1)[:, None]  # (..., d+1, 3)
        return pw

    def value(self, pts):
        pw = self._powers(pts)
        m = self.monoms
        t = pw[..., m[:, 0], 0] * pw[..., m[:, 1], 1] * pw[..., m[:, 2], 2]
        return t @ self.coeffs

    def abs_terms(self, pts):
        pw = np.abs(self._powers(pts))
        m = self.monoms
        t = pw[..., m[:, 0], 0] * pw[..., m[:, 1], 1] * pw[..., m[:, 2], 2]
        return t @ np.abs(self.coeffs)

    def grad(self, pts):
        pw = self._powers(pts)
        m = self.monoms
        out = []
        for a in range(3):
            e = m.copy()
            c = self.coeffs * e[:, a]
            e[:, a] = np.maximum(e[:, a] - 1, 0)
            t = pw[..., e[:, 0], 0] * pw[..., e[:, 1], 1] * pw[..., e[:, 2], 2]
            out.append(t @ c)
        return np.stack(out, axis=-1)

    def hessian(self, pts):
        pw = self._powers(pts)
        m = self.monoms
        h = np.zeros(np.shape(pts)[:-1] + (3, 3))
        for a in range(3):
            for b in range(a, 3):
                e = m.copy()
                c = self.coeffs * e[:, a]
                e[:, a] = np.maximum(e[:, a] - 1, 0)
                c = c * e[:, b]
                e[:, b] = np.maximum(e[:, b] - 1, 0)
                t = pw[..., e[:, 0], 0] * pw[..., e[:, 1], 1] * pw[..., e[:, 2], 2]
                h[..., a, b] = h[..., b, a] = t @ c
        return h


def _grid(box, n):
    axes = [np.linspace(lo, hi, n) for lo, hi in box]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)


def sign_sample(field: Field, box, n: int = 41, extra: int = 20000, seed: int = 0):
    """(has positive, has negative) on an n^3 grid plus random points."""
    g = _grid(box, n).reshape(-1, 3)
    rng = np.random.default_rng(seed)
    r = box[:, 0] + rng.random((extra, 3)) * (box[:, 1] - box[:, 0])
    v = field.value(np.concatenate([g, r]))
    return bool((v > 0).any()), bool((v < 0).any())


def bernstein_sign(field: Field, box, split: int = 8) -> int:
    """+1 / -1 when Bernstein bounds on split^3 sub-boxes prove F > 0 / F < 0
    on the whole box (margin: the rounding of the conversion), else 0."""
    n = max(field.degree, 1)
    a = np.zeros((n + 1,) * 3)
    for (i, j, k), c in zip(field.monoms, field.coeffs):
        a[i, j, k] += c
    w = (box[:, 1] - box[:, 0]) / split
    # Power basis on each sub-box u in [0, 1]: x = lo + w u.
    los = [box[ax, 0] + w[ax] * np.arange(split) for ax in range(3)]

    def shift(lo, width):  # T[s, i, m]: x^i in powers of u on sub-box s
        T = np.zeros((len(lo), n + 1, n + 1))
        for i in range(n + 1):
            for m in range(i + 1):
                T[:, i, m] = comb(i, m) * lo ** (i - m) * width ** m
        return T

    Tx, Ty, Tz = (shift(los[ax], w[ax]) for ax in range(3))
    B = np.zeros((n + 1, n + 1))  # b_I = sum_i C(I,i)/C(n,i) a_i
    for I in range(n + 1):
        for i in range(I + 1):
            B[I, i] = comb(I, i) / comb(n, i)
    Mx, My, Mz = (np.einsum("Im,sim->siI", B, T) for T in (Tx, Ty, Tz))
    b = np.einsum("ijk,aiI,bjJ,ckK->abcIJK", a, Mx, My, Mz)
    absb = np.einsum("ijk,aiI,bjJ,ckK->abcIJK", np.abs(a), np.abs(Mx), np.abs(My), np.abs(Mz))
    margin = 1e-12 * absb
    if (b > margin).all():
        return 1
    if (b < -margin).all():
        return -1
    return 0


def _newton(field: Field, p, box, fs, gs):
    """Gauss-Newton on (F / fs, grad F / gs) = 0 from the rows of ``p``;
    the converged points inside the box."""
    size = float(np.ptp(box, axis=1).max())
    with np.errstate(all="ignore"):
        for _ in range(40):
            f, gr, h = field.value(p), field.grad(p), field.hessian(p)
            J = np.concatenate([gr[:, None, :] / fs, h / gs], axis=1)
            r = np.concatenate([f[:, None] / fs, gr / gs], axis=1)
            JT = np.swapaxes(J, 1, 2)
            A = JT @ J
            lam = 1e-12 * np.trace(A, axis1=1, axis2=2)[:, None, None] + 1e-300
            d = np.linalg.solve(A + lam * np.eye(3), JT @ r[..., None])[..., 0]
            # Short steps kept in the box: along a curve of solutions the
            # step is free in the curve's direction and may run far.
            d = np.nan_to_num(np.clip(d, -0.05 * size, 0.05 * size))
            p = np.clip(p - d, box[:, 0], box[:, 1])
        f, gr = field.value(p), field.grad(p)
    ok = (np.abs(f) <= 1e-9 * fs) & (np.linalg.norm(gr, axis=1) <= 1e-7 * gs)
    ok &= np.isfinite(p).all(axis=1)
    pad = 1e-6 * size
    ok &= ((p >= box[:, 0] - pad) & (p <= box[:, 1] + pad)).all(axis=1)
    return p[ok]


def _scales(field: Field, box, n: int):
    g = _grid(box, n)
    F, G = field.value(g), field.grad(g)
    return g, F, G, max(np.abs(F).max(), 1e-300), max(np.abs(G).max(), 1e-300)


def singular_set(field: Field, box, n: int = 25):
    """Points of the box where F = grad F = 0, and whether they make a curve.

    Gauss-Newton from the grid's local minima of |F|^2 + |grad F|^2 (each
    scaled by its grid maximum).  A point is on a curve of singular points
    when Newton started a little away along the Hessian's null direction
    comes back to another singular point (an isolated one has no null
    direction, or Newton returns to it).

    Returns
    -------
    points : (k, 3) array, curve : bool
    """
    size = float(np.ptp(box, axis=1).max())
    g, F, G, fs, gs = _scales(field, box, n)
    phi = (F / fs) ** 2 + ((G / gs) ** 2).sum(-1)
    minima = (phi == ndimage.minimum_filter(phi, size=3, mode="nearest"))
    p = g[minima]
    if len(p) > 4000:
        p = p[np.argsort(phi[minima])[:4000]]
    pts = _newton(field, p, box, fs, gs)
    keep = []
    for q in pts:
        if all(np.linalg.norm(q - k) > 1e-6 * size for k in keep):
            keep.append(q)
    pts = np.array(keep).reshape(-1, 3)
    if len(pts) == 0:
        return pts, False
    w, vec = np.linalg.eigh(field.hessian(pts))
    w_abs = np.abs(w)
    flat = w_abs.min(axis=1) <= 1e-6 * w_abs.max(axis=1)
    null = vec[np.arange(len(pts)), :, np.argmin(w_abs, axis=1)]
    t = 0.02 * size
    for sgn in (1, -1):
        seeds = pts[flat] + sgn * t * null[flat]
        if len(seeds) == 0:
            break
        back = _newton(field, seeds, box, fs, gs)
        if len(back) and np.min(np.linalg.norm(back[:, None] - pts[None], axis=2), axis=1).max() > 0.2 * t:
            return pts, True
    return pts, len(pts) > 12


def singular_points(field: Field, box, n: int = 25) -> np.ndarray:
    """The singular points of :func:`singular_set`."""
    return singular_set(field, box, n)[0]


# ------------------------------------------------------------------- judge

@dataclass
class Verdict:
    """What the judge found for one case."""

    name: str
    status: str  # "clean", "empty", "refused", "fail"
    failures: list = field(default_factory=list)  # class names
    detail: str = ""
    seconds: float = 0.0
    faces: int = 0
    singular: int = 0
    notes: list = field(default_factory=list)  # what was not judged, and why


def _near(points, centres, radius):
    if len(centres) == 0 or len(points) == 0:
        return np.zeros(len(points), bool)
    from scipy.spatial import cKDTree
    return cKDTree(centres).query(points)[0] <= radius


def judge(case: Case, coarse: int = 8, fine: int = 64) -> Verdict:
    """Mesh ``case`` and judge the mesh; see the module docstring."""
    import singmesh

    box = case.box_array()
    size = float(np.ptp(box, axis=1).max())
    t0 = time.process_time()  # CPU seconds: the machine is shared
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            m = singmesh.mesh(case.text, case.box, coarse=coarse, fine=fine)
    except singmesh.SurfaceError as e:
        return Verdict(case.name, "refused", detail=str(e), seconds=time.process_time() - t0)
    except Exception as e:  # noqa: BLE001 - any other exception is the failure judged
        return Verdict(case.name, "fail", ["exception"], f"{type(e).__name__}: {e}",
                       time.process_time() - t0)
    seconds = time.process_time() - t0
    v = np.asarray(m.vertices, float)
    f = np.asarray(m.faces)
    fails: list[str] = []
    details: list[str] = []
    notes: list[str] = []

    def fail(cls, msg):
        if cls not in fails:
            fails.append(cls)
            details.append(f"{cls}: {msg}")

    if not np.isfinite(v).all():
        fail("nan", "non-finite vertex")
    if len(f) and (f.min() < 0 or f.max() >= len(v)):
        fail("index", "face index out of range")
    if fails:
        return Verdict(case.name, "fail", fails, "; ".join(details), seconds)
    used = np.unique(f) if len(f) else np.zeros(0, int)
    field_ = Field(case.poly)

    # Shape: zero-area triangles and coincident vertices.
    n_deg = mc.degenerate_triangles(v, f)
    n_tiny = mc.tiny_triangles(v, f, box)
    if n_deg or n_tiny:
        fail("zero-area", f"{n_deg} degenerate, {n_tiny} tiny")
    n_close = mc.close_vertex_pairs(v[used], box)
    if n_close:
        fail("close-vertices", f"{n_close} pairs")

    # On the surface.
    if len(used):
        p = v[used]
        val = np.abs(field_.value(p))
        gn = np.linalg.norm(field_.grad(p), axis=1)
        allowed = 1e-9 * size * gn + 64 * np.finfo(float).eps * field_.abs_terms(p)
        off = val > allowed
        if off.any():
            # |F| / |grad F| overestimates the distance where grad F nearly
            # vanishes (at a degenerate singular point): there F taking
            # both signs within the distance allowed puts the vertex on F = 0.
            off[off] = ~_sign_change_near(field_, p[off], 1e-9 * size)
        if off.any():
            worst = float(np.max(val[off] / np.maximum(gn[off], 1e-300))) / size
            fail("off-surface", f"{int(off.sum())} vertices, worst |F|/|grad F| = {worst:.2g} box")
        inside = ((v >= box[:, 0]) & (v <= box[:, 1])).all(axis=1)
        pad = 1e-9 * size
        inside |= ((v >= box[:, 0] - pad) & (v <= box[:, 1] + pad)).all(axis=1)
        if not inside[used].all():
            fail("outside-box", f"{int((~inside[used]).sum())} vertices")

    # Nothing left out: the roots of F on the fine lattice's lines.
    if len(f):
        # Every second line of the fine lattice: a piece left out that is
        # two cells across or more meets one.
        roots = lattice_roots(field_, box, fine // 2 + 1)
        cell = size / fine

        def off_mesh(pts, exact):
            d, tri = mc.distance_to_mesh(pts, v, f, return_triangle=True, exact=exact)
            t = v[f[tri]]
            longest = np.linalg.norm(t - np.roll(t, 1, axis=1), axis=2).max(axis=1)
            return d, (d > UNCOVERED * cell) & (d > 0.5 * longest)

        # An upper bound first, exact distances where it is not near enough.
        _, far = off_mesh(roots, exact=False)
        if far.any():
            roots = roots[far]
            d, far = off_mesh(roots, exact=True)
            if far.any():
                i = int(np.argmax(np.where(far, d, -1)))
                fail("uncovered", f"{int(far.sum())} lattice roots off the mesh, worst "
                                  f"{d[i] / cell:.3g} cells at {np.round(roots[i], 4).tolist()}")

    # Empty exactly when F keeps its sign.
    pos, neg = sign_sample(field_, box)
    changes = pos and neg
    if len(f) == 0 and changes:
        fail("empty-with-sign-change", "the sample shows both signs")
    if len(f) and not changes:
        if bernstein_sign(field_, box) != 0:
            fail("nonempty-without-zero", "Bernstein bounds prove F has one sign")
        else:
            # A region thinner than the grid: look beside the vertices.
            n = field_.grad(v[used])
            n = n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
            h = 1e-4 * size
            side = np.concatenate([v[used] + h * n, v[used] - h * n])
            vals = field_.value(side)
            if not ((vals > 0).any() and (vals < 0).any()):
                fail("nonempty-without-sign-change", "no sign change on the grid nor beside vertices")

    # Topology away from singular points and curves.
    sing, on_curve = singular_set(field_, box)
    near_curve = None
    if case.factors:
        f1, f2 = (Field(q) for q in case.factors)

        def near_curve(pts):
            d1 = np.abs(f1.value(pts)) / np.maximum(np.linalg.norm(f1.grad(pts), axis=1), 1e-300)
            d2 = np.abs(f2.value(pts)) / np.maximum(np.linalg.norm(f2.grad(pts), axis=1), 1e-300)
            return (d1 <= NEAR_CURVE * size) & (d2 <= NEAR_CURVE * size)

        # Isolated special points of a product: singular points of each
        # factor on the surface, and where the two sheets are tangent.
        (s1, c1), (s2, c2) = singular_set(f1, box), singular_set(f2, box)
        extra = [s1, s2, _tangencies(f1, f2, box)]
        sing = np.concatenate([q for q in extra if len(q)] or [np.zeros((0, 3))])
        if c1 or c2:
            # A factor with a curve of singular points (z^3 + 12 x^3: a
            # plane and an isolated real line in it).
            notes.append("topology not judged: a singular curve")
            details.append("a factor has a curve of singular points: topology not judged")
    elif on_curve:
        # A curve of singular points in an irreducible F (a cuspidal
        # cylinder, a double line): its sheets are not modelled here.
        notes.append("topology not judged: a singular curve")
        details.append(f"{len(sing)} singular points found (a curve): topology not judged")
    if len(f) and not notes:
        counts = mc.edge_counts(f)
        edges = np.array(list(counts.keys()), dtype=np.int64).reshape(-1, 2)
        k = np.array(list(counts.values()))
        mid = 0.5 * (v[edges[:, 0]] + v[edges[:, 1]])
        exempt = _near(v[edges[:, 0]], sing, NEAR_POINT * size) | _near(v[edges[:, 1]], sing, NEAR_POINT * size)
        open_ = k == 1
        for i in np.flatnonzero(open_):
            open_[i] = not mc._same_box_face(v[edges[i, 0]], v[edges[i, 1]], box)
        bad_nm = k > 2
        if near_curve is not None:
            nc = near_curve(mid)
            bad_nm = bad_nm & ~(nc & (k == 4))
        bad_open = open_ & ~exempt
        bad_nm = bad_nm & ~exempt
        if bad_open.any():
            i = np.flatnonzero(bad_open)[0]
            where = "near the curve" if near_curve is not None and near_curve(mid[i:i + 1])[0] else "on a sheet"
            fail("open-edge", f"{int(bad_open.sum())} edges, first at {np.round(mid[i], 4).tolist()} ({where})")
        if bad_nm.any():
            i = np.flatnonzero(bad_nm)[0]
            fail("non-manifold", f"{int(bad_nm.sum())} edges, first with {k[i]} triangles at "
                                 f"{np.round(mid[i], 4).tolist()}")
    status = "fail" if fails else ("clean" if len(f) else "empty")
    return Verdict(case.name, status, fails, "; ".join(details), seconds, len(f), len(sing), notes)


def lattice_roots(field: Field, box, n: int, steps: int = 32) -> np.ndarray:
    """Roots of F on the lines of an n^3 grid of the box: each sign change
    between two grid points bisected ``steps`` times (one root per segment)."""
    g = _grid(box, n)
    vals = field.value(g.reshape(-1, 3)).reshape(g.shape[:3])
    out = []
    for ax in range(3):
        a = np.moveaxis(g, ax, 0)
        w = np.moveaxis(vals, ax, 0)
        m = (w[:-1] * w[1:]) < 0
        lo, hi, flo = a[:-1][m], a[1:][m], w[:-1][m]
        for _ in range(steps):
            mid = 0.5 * (lo + hi)
            fm = field.value(mid)
            same = fm * flo > 0
            lo = np.where(same[:, None], mid, lo)
            flo = np.where(same, fm, flo)
            hi = np.where(same[:, None], hi, mid)
        out.append(0.5 * (lo + hi))
    return np.concatenate(out)


def _sign_change_near(field: Field, pts, radius, n: int = 400) -> np.ndarray:
    """Per point: F is zero at it or takes both signs within ``radius``."""
    rng = np.random.default_rng(0)
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    d = np.concatenate([d, np.eye(3), -np.eye(3)])
    g = field.grad(pts)
    # Scaled first: at a vertex on a curve of singular points grad F may be
    # 1e-196, whose square underflows (a zero norm made g 1e104 long).
    g = g / np.maximum(np.abs(g).max(axis=1, keepdims=True), 1e-300)
    g = g / np.maximum(np.linalg.norm(g, axis=1, keepdims=True), 1e-300)
    q = pts[:, None, :] + radius * np.concatenate([d[None].repeat(len(pts), 0), g[:, None], -g[:, None]], axis=1)
    v = field.value(q)
    v0 = field.value(pts)
    return (v0 == 0) | ((v > 0).any(axis=1) & (v < 0).any(axis=1))


def _tangencies(f1: Field, f2: Field, box, n: int = 25) -> np.ndarray:
    """Points of f1 = f2 = 0 where grad f1 and grad f2 are parallel."""
    g = _grid(box, n).reshape(-1, 3)

    def res(p):
        a, b = f1.grad(p), f2.grad(p)
        na = np.maximum(np.linalg.norm(a, axis=1, keepdims=True), 1e-300)
        nb = np.maximum(np.linalg.norm(b, axis=1, keepdims=True), 1e-300)
        return np.concatenate([f1.value(p)[:, None] / na, f2.value(p)[:, None] / nb,
                               np.cross(a / na, b / nb)], axis=1)

    with np.errstate(all="ignore"):
        r = res(g)
    r = np.nan_to_num(r, nan=1e300, posinf=1e300, neginf=1e300)
    score = (np.minimum(np.abs(r), 1e100) ** 2).sum(1)
    p = g[np.argsort(score)[:200]]
    size = float(np.ptp(box, axis=1).max())
    h = 1e-7 * size
    with np.errstate(all="ignore"):
        for _ in range(30):
            r0 = res(p)
            J = np.stack([(res(p + h * e) - r0) / h for e in np.eye(3)], axis=-1)
            JT = np.swapaxes(J, 1, 2)
            d = _solve_each(JT @ J + 1e-12 * np.eye(3), JT @ r0[..., None])[..., 0]
            p = p - np.nan_to_num(np.clip(d, -0.1 * size, 0.1 * size))
        ok = (np.abs(res(p)) < 1e-6).all(axis=1)
    ok &= ((p >= box[:, 0] - 1e-6 * size) & (p <= box[:, 1] + 1e-6 * size)).all(axis=1)
    keep = []
    for q in p[ok]:
        if all(np.linalg.norm(q - k) > 1e-5 * size for k in keep):
            keep.append(q)
    return np.array(keep) if keep else np.zeros((0, 3))


def _solve_each(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``np.linalg.solve(a, b)`` for a stack, with a zero step for the systems that are singular to
    rounding rather than an exception for all (fuzz s6-666: normal equations with entries 1e4 to 1e18
    at starts where the plane 3 y + 3/5 x and the quadric's gradient nearly line up; the judge raised
    LinAlgError)."""
    try:
        return np.linalg.solve(a, b)
    except np.linalg.LinAlgError:
        out = np.zeros(b.shape)
        for i in range(len(a)):
            try:
                out[i] = np.linalg.solve(a[i], b[i])
            except np.linalg.LinAlgError:
                pass
        return out
