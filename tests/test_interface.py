"""The surface interface (issue #10): the stages know F only through it.

1. A surface that implements :class:`singmesh.surface.Surface` by
   delegating to a :class:`PolynomialSurface`, but has no monomial or
   Bernstein tensors at all (any other attribute raises), meshes to the
   very same vertices, faces and singular points: no stage reaches past
   the interface.
2. The polynomial implementation keeps the contract, checked against
   dense samples of F and its derivatives (never against its own bounds):
   no box excluded where F changes sign, no derivative claimed of one
   sign where it changes sign, every sign change on a segment has a root,
   no box with a singular point dropped, Taylor coefficients as sympy
   expands them.
"""

from __future__ import annotations

import itertools
import math
import warnings

import numpy as np
import pytest
import sympy

import singmesh
from singmesh.surface import CHILD_OFFSETS, PolynomialSurface, Surface, X, Y, Z

from test_rounded import float_rotated

EPS = np.finfo(float).eps
#: A sample's sign is certain when |value| exceeds this many ulps of the
#: size of its terms (the rounding of evaluating it).
CERTAIN_ULPS = 64


class Leak(RuntimeError):
    """A stage asked for something outside the surface interface."""


class Delegating(Surface):
    """The surface interface and nothing else, on top of a polynomial.

    No ``coeffs``, ``gradient_coeffs``, ``hessian_coeffs``, ``jet_coeffs``
    or ``__dict__`` (caches): asking for them raises :class:`Leak`.  It
    says it is not a polynomial, so the polynomial-only square-free step
    is skipped, as it will be for non-polynomial surfaces.
    """

    __slots__ = ("_inner", "__weakref__")

    def __init__(self, inner: PolynomialSurface):
        object.__setattr__(self, "_inner", inner)

    def __getattr__(self, name):
        raise Leak(f"a stage asked the surface for {name!r}")

    coeffs = gradient_coeffs = hessian_coeffs = jet_coeffs = property(
        lambda self: (_ for _ in ()).throw(Leak("a stage asked for the monomial tensors")))

    is_polynomial = False
    text = property(lambda self: self._inner.text)
    expr = property(lambda self: self._inner.expr)
    params = property(lambda self: self._inner.params)
    rounding = property(lambda self: self._inner.rounding)
    degree = property(lambda self: self._inner.degree)
    scale = property(lambda self: self._inner.scale)

    def __str__(self):
        return str(self._inner)

    def __call__(self, points):
        return self._inner(points)

    def gradient(self, points):
        return self._inner.gradient(points)

    def value_gradient(self, points):
        return self._inner.value_gradient(points)

    def hessian(self, points):
        return self._inner.hessian(points)

    def jet(self, points):
        return self._inner.jet(points)

    def magnitude(self, points):
        return self._inner.magnitude(points)

    def gradient_magnitude(self, points):
        return self._inner.gradient_magnitude(points)

    def taylor(self, point, order=None):
        return self._inner.taylor(point, order)

    def enclose(self, box):
        return self._inner.enclose(box)

    def split(self, data):
        return self._inner.split(data)

    def excludes_zero(self, data):
        return self._inner.excludes_zero(data)

    def simple_axis(self, data):
        return self._inner.simple_axis(data)

    def face_modes(self, data, n, side, rows=None):
        return self._inner.face_modes(data, n, side, rows)

    def may_vanish(self, data, axes):
        return self._inner.may_vanish(data, axes)

    def line_roots(self, axis, fixed, s0, s1):
        return self._inner.line_roots(axis, fixed, s0, s1)


KUMMER = ("(x^2+y^2+z^2-1.69)^2 - 407/131 (1-z-sqrt(2) x)(1-z+sqrt(2) x)"
          "(1+z+sqrt(2) y)(1+z-sqrt(2) y)")


@pytest.mark.parametrize("text, box, points", [
    ("x^2+y^2+z^2-1", None, 0),
    (KUMMER, ((-2.5, 2.5),) * 3, 16),
    ("x^2 - y^2 z", None, 0),          # Whitney's umbrella: a curve of singular points
])
def test_stages_use_only_the_interface(text, box, points):
    """The meshes through the bare interface are those of the polynomial, bit for bit."""
    kw = {} if box is None else {"box": box}
    poly = Surface.parse(text)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        want = singmesh.mesh(Surface.parse(text), **kw)
        got = singmesh.mesh(Delegating(poly), **kw)
    with pytest.raises(Leak):
        Delegating(poly).coeffs
    with pytest.raises(Leak):
        Delegating(poly).__dict__
    assert len(want.faces) > 0 and len(want.singularities) == points
    assert np.array_equal(got.vertices, want.vertices)
    assert np.array_equal(got.faces, want.faces)
    assert [s.point.tolist() for s in got.singularities] == [s.point.tolist() for s in want.singularities]
    assert np.array_equal(got.curve_graph[0], want.curve_graph[0])


# ------------------------------------------------------------------ contract of the polynomial
def random_polynomial(rng, degree: int) -> PolynomialSurface:
    """Float coefficients on every monomial of total degree <= ``degree``, some of them zero."""
    terms = [sympy.Float(rng.normal(), 15) * X**i * Y**j * Z**k
             for i in range(degree + 1) for j in range(degree + 1 - i) for k in range(degree + 1 - i - j)
             if rng.random() < 0.7]
    return Surface.parse(sympy.Add(*terms))


def surfaces():
    rng = np.random.default_rng(2026)
    return [Surface.parse(KUMMER), Surface.parse("x^4-5x^2+y^4-5y^2+z^4-5z^2+11.8"),
            Surface.parse(float_rotated("y x^2 + y^4 - z^2", 5)[0]),
            random_polynomial(rng, 3), random_polynomial(rng, 4)]


def boxes_of(surface, rng, roots: int = 4, depth: int = 2):
    """Stacks of ``data`` and their boxes (lo, hi): random roots and their children to ``depth``."""
    data, lo, hi = [], [], []
    for _ in range(roots):
        centre = rng.uniform(-1.5, 1.5, 3)
        half = rng.uniform(0.1, 1.0, 3)
        d = surface.enclose(np.stack([centre - half, centre + half], axis=1))
        l, h = (centre - half)[None], (centre + half)[None]
        for _ in range(depth + 1):
            data.append(d)
            lo.append(l)
            hi.append(h)
            kids = surface.split(d)
            assert kids.shape[:2] == (len(d), 8)
            d = kids.reshape((-1,) + kids.shape[2:])
            size = (h - l) / 2
            l = (l[:, None, :] + CHILD_OFFSETS[None] * size[:, None, :]).reshape(-1, 3)
            h = l + np.repeat(size, 8, axis=0)
    return np.concatenate(data), np.concatenate(lo), np.concatenate(hi)


def grid(lo, hi, n, face=None):
    """(N, n, n, n, 3) points of an n^3 grid in each box, faces included;
    with ``face`` = (axis, side) only that face's n^2 points, (N, n, n, 3)."""
    t = [np.linspace(0.0, 1.0, n)] * 3
    if face is not None:
        t[face[0]] = np.array([float(face[1])])
    u = np.stack(np.meshgrid(*t, indexing="ij"), axis=-1)
    pts = lo[:, None, None, None, :] + u[None] * (hi - lo)[:, None, None, None, :]
    return pts if face is None else np.take(pts, 0, axis=1 + face[0])


def sign_changes(values, sizes, axes):
    """Whether certain samples (|v| above rounding) of both signs occur over ``axes``."""
    certain = np.abs(values) > CERTAIN_ULPS * EPS * sizes
    return (((values > 0) & certain).any(axis=axes)) & (((values < 0) & certain).any(axis=axes))


@pytest.mark.parametrize("k", range(5))
def test_box_tests_agree_with_dense_samples(k):
    s = surfaces()[k]
    rng = np.random.default_rng(k)
    data, lo, hi = boxes_of(s, rng)
    pts = grid(lo, hi, 8)
    f = s(pts)
    mag = s.magnitude(pts)
    _, g = s.value_gradient(pts)
    gmag = s.gradient_magnitude(pts)

    # excludes_zero: never where F changes sign.
    changes = sign_changes(f, mag, (1, 2, 3))
    excluded = s.excludes_zero(data)
    assert not (excluded & changes).any()
    assert changes.any() and excluded.any()   # both kinds of box are here

    # simple_axis: F_a of one sign, and on both end faces a tangential
    # derivative of one sign or F of one sign.
    axis = s.simple_axis(data)
    assert (axis >= 0).any()
    for a in range(3):
        sel = axis == a
        assert not sign_changes(g[sel][..., a], gmag[sel][..., a], (1, 2, 3)).any(), (k, a)
        u, v = (a + 1) % 3, (a + 2) % 3
        for end in (0, -1):
            gf, gm = np.take(g[sel], end, axis=1 + a), np.take(gmag[sel], end, axis=1 + a)
            ff, fm = np.take(f[sel], end, axis=1 + a), np.take(mag[sel], end, axis=1 + a)
            ok = (~sign_changes(gf[..., u], gm[..., u], (1, 2)) | ~sign_changes(gf[..., v], gm[..., v], (1, 2))
                  | ~sign_changes(ff, fm, (1, 2)))
            assert ok.all(), (k, a, end)

    # face_modes: 0 claims F_v of one sign on the face, 1 claims F_u.
    claimed = 0
    for n, side in itertools.product(range(3), (0, 1)):
        modes = s.face_modes(data, n, np.full(len(data), side))
        face = grid(lo, hi, 12, (n, side))
        gface, mface = s.gradient(face), s.gradient_magnitude(face)
        u, v = (n + 1) % 3, (n + 2) % 3
        for mode, d in ((0, v), (1, u)):
            sel = modes == mode
            claimed += int(sel.sum())
            assert not sign_changes(gface[sel][..., d], mface[sel][..., d], (1, 2)).any(), (k, n, side, mode)
    assert claimed > 0


@pytest.mark.parametrize("k", range(5))
def test_line_roots_find_every_sign_change(k):
    s = surfaces()[k]
    rng = np.random.default_rng(100 + k)
    n_lines = 60
    found_changes = 0
    for axis in range(3):
        fixed = rng.uniform(-2.0, 2.0, (n_lines, 2))
        s0 = rng.uniform(-2.5, 0.0, n_lines)
        s1 = s0 + rng.uniform(0.3, 2.5, n_lines)
        row, root = s.line_roots(axis, fixed, s0, s1)
        assert row.dtype == np.int64 and root.shape == row.shape
        assert np.all((root >= s0[row]) & (root <= s1[row]))
        t = np.linspace(0.0, 1.0, 2001)
        along = s0[:, None] + t[None] * (s1 - s0)[:, None]
        pts = np.zeros(along.shape + (3,))
        pts[..., axis] = along
        pts[..., (axis + 1) % 3] = fixed[:, None, 0]
        pts[..., (axis + 2) % 3] = fixed[:, None, 1]
        f, mag = s(pts), s.magnitude(pts)
        certain = np.abs(f) > CERTAIN_ULPS * EPS * mag
        for l in range(n_lines):
            idx = np.nonzero(certain[l])[0]
            sign = np.sign(f[l, idx])
            for a, b in zip(idx[:-1][sign[:-1] != sign[1:]], idx[1:][sign[:-1] != sign[1:]]):
                found_changes += 1
                r = root[row == l]
                assert np.any((r >= along[l, a]) & (r <= along[l, b])), (k, axis, l, along[l, a], along[l, b])
        # The roots are zeros of F to rounding, not just places near one.
        on = np.zeros((len(root), 3))
        on[:, axis] = root
        on[:, (axis + 1) % 3] = fixed[row, 0]
        on[:, (axis + 2) % 3] = fixed[row, 1]
        grad = np.abs(s.gradient(on)[:, axis])
        assert np.all(np.abs(s(on)) <= 1e-9 * s.magnitude(on) + 1e-6 * grad), k
    assert found_changes > 20


def search(surface, box, level, axes):
    """Boxes (lo, hi) at ``level`` that ``may_vanish`` keeps, by the interface alone."""
    data = surface.enclose(box)
    corner = np.zeros((1, 3), np.int64)
    for lvl in range(level + 1):
        keep = surface.may_vanish(data, axes)
        data, corner = data[keep], corner[keep]
        if lvl < level:
            kids = surface.split(data)
            data = kids.reshape((-1,) + kids.shape[2:])
            corner = (2 * corner[:, None, :] + CHILD_OFFSETS[None]).reshape(-1, 3)
    h = (box[:, 1] - box[:, 0]) / (1 << level)
    return box[:, 0] + corner * h, box[:, 0] + (corner + 1) * h


@pytest.mark.parametrize("name, box, axes", [
    ("kummer", ((-2.5, 2.5),) * 3, (0, 1, 2)),
    ("kummer", ((-2.5, 2.5),) * 3, (0, 2)),
    ("cayley", ((-2.0, 2.0),) * 3, (0, 1, 2)),   # nodes at +-1/2: on split planes from level 3
])
def test_may_vanish_keeps_the_nodes(name, box, axes):
    from benchmarks.nodes import SURFACES, true_nodes

    s = Surface.parse(SURFACES[name].text)
    box = np.array(box, float)
    nodes = true_nodes(name)
    level = 6
    lo, hi = search(s, box, level, axes)
    assert len(lo) < 0.02 * 8 ** level   # a search, not everything
    for p in nodes:
        assert np.any(np.all((lo <= p + 1e-12) & (p - 1e-12 <= hi), axis=1)), p


def sympy_taylor(surface, p, n):
    """Exact Taylor coefficients of the surface's expression at the float point p, to total degree n."""
    u, v, w = sympy.symbols("u v w")
    q = [sympy.Rational(float(c)) for c in p]
    e = sympy.expand(surface.expr.subs({X: q[0] + u, Y: q[1] + v, Z: q[2] + w}, simultaneous=True))
    out = np.zeros((n + 1,) * 3)
    for (i, j, k), c in sympy.Poly(e, u, v, w).terms():
        if i + j + k <= n:
            out[i, j, k] = float(c)
    return out


@pytest.mark.parametrize("text", [KUMMER, float_rotated("x^3 + x y^3 - z^2", 8)[0],
                                  "x^2 y^2 + y^2 z^2 + z^2 x^2 - x y z"])
def test_taylor_matches_sympy(text):
    s = Surface.parse(text)
    rng = np.random.default_rng(len(text))
    p = rng.uniform(-1.2, 1.2, 3)
    d = s.degree
    exact = sympy_taylor(s, p, d)
    tol = 1e-13 * float(s.magnitude(p)) * (1 + np.abs(p).max()) ** d
    T = s.taylor(p)
    assert T.shape == (d + 1,) * 3
    assert np.abs(T - exact).max() <= tol
    assert np.abs(exact).max() > 1e3 * tol   # the comparison means something
    padded = s.taylor(p, d + 3)
    assert padded.shape == (d + 4,) * 3
    assert np.abs(padded[: d + 1, : d + 1, : d + 1] - exact).max() <= tol
    assert not padded[d + 1:].any() and not padded[:, d + 1:].any() and not padded[..., d + 1:].any()
    for n in (1, 2, 3):
        low = s.taylor(p, n)
        assert low.shape == (n + 1,) * 3
        assert np.abs(low - sympy_taylor(s, p, n)).max() <= tol
    # Third derivatives from the order-3 jet (the default every surface
    # has) and the polynomial's own tensors agree with sympy's.
    q = [sympy.Rational(float(c)) for c in p]
    want = np.array([[[float(sympy.diff(s.expr, a, b, c).subs({X: q[0], Y: q[1], Z: q[2]}))
                       for c in (X, Y, Z)] for b in (X, Y, Z)] for a in (X, Y, Z)])
    assert np.abs(Surface.third_derivatives(s, p) - want).max() <= 6 * tol
    assert np.abs(s.third_derivatives(p) - want).max() <= 6 * tol
    assert math.isfinite(s.scale) and s.scale == float(np.abs(s.coeffs).max())
