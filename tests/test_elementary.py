"""ElementarySurface's box and line methods against dense samples (sympy's numpy code).

Each check is independent of the implementation's own numbers: sign
changes of F between dense samples on a segment, sample values on boxes
and faces, singular points known in closed form.
"""

import numpy as np
import pytest
import sympy
from sympy import Abs, Max, Rational, cos, exp, sin, sqrt

from singmesh.elementary import ElementarySurface
from singmesh.errors import SurfaceError
from singmesh.syntax import X, Y, Z

x, y, z = X, Y, Z


def _sigmoid_union():
    """Seed 001: H_k(s) = 1/(1 + exp(-k s)), k = 20; union f_k + g_k - f_k g_k - 1/2 of two spheres."""
    h = lambda s: 1 / (1 + exp(-20 * s))  # noqa: E731
    f = h(Rational(1, 4) - ((x - 0.35) ** 2 + y**2 + z**2))
    g = h(Rational(1, 4) - ((x + 0.35) ** 2 + y**2 + z**2))
    return f + g - f * g - Rational(1, 2)


SURFACES = {
    "gyroid": (sin(x) * cos(y) + sin(y) * cos(z) + sin(z) * cos(x), 3.0),
    "sqrt-torus": ((sqrt(x**2 + y**2) - 1) ** 2 + z**2 - Rational(1, 4), 1.6),
    "sigmoid-union": (_sigmoid_union(), 1.0),
    "max-sphere-plane": (Max(x**2 + y**2 + z**2 - 1, z), 1.3),
    "cube": (Max(Abs(x), Abs(y), Abs(z)) - 0.7, 1.0),
    # Seed 000's half sphere by the R-function union of F = x^2+y^2+z^2-1 and -z.
    "half-sphere-R": ((x**2 + y**2 + z**2 - 1) - z + sqrt((x**2 + y**2 + z**2 - 1)**2 + z**2), 1.3),
}


def _fn(expr):
    f = sympy.lambdify((x, y, z), expr, "numpy")

    def call(p):
        with np.errstate(all="ignore"):
            return np.broadcast_to(np.asarray(f(p[..., 0], p[..., 1], p[..., 2]), float), p.shape[:-1])
    return call


def _segments(rng, reach, n):
    """Random axis-parallel segments; a quarter on lattice-like planes through 0 (kinks of the CSG forms)."""
    axis = rng.integers(0, 3, n)
    fixed = rng.uniform(-reach, reach, (n, 2))
    fixed[: n // 4] = np.round(fixed[: n // 4] * 4) / 4
    s0 = rng.uniform(-reach, 0, n)
    s1 = rng.uniform(0, reach, n)
    return axis, fixed, s0, s1


def _line_points(axis, fixed, s):
    p = np.empty(s.shape + (3,))
    p[..., axis] = s
    p[..., (axis + 1) % 3] = fixed[..., 0, None] if s.ndim > 1 else fixed[..., 0]
    p[..., (axis + 2) % 3] = fixed[..., 1, None] if s.ndim > 1 else fixed[..., 1]
    return p


@pytest.mark.parametrize("name", list(SURFACES))
def test_line_roots_find_every_sign_change(name):
    expr, reach = SURFACES[name]
    s = ElementarySurface.from_expr(expr, name)
    f = _fn(expr)
    rng = np.random.default_rng(17)
    axes, fixed, s0, s1 = _segments(rng, reach, 240)
    missed = 0
    for a in range(3):
        sel = np.nonzero(axes == a)[0]
        row, root = s.line_roots(a, fixed[sel], s0[sel], s1[sel])
        assert np.all((root >= s0[sel][row] - 1e-12) & (root <= s1[sel][row] + 1e-12))
        # Every reported root is on the surface (to rounding of F's terms).
        p = _line_points(a, fixed[sel][row], root)
        assert np.all(np.abs(f(p)) <= 1e-9 * (1 + s.magnitude(p)))
        t = np.linspace(0, 1, 4001)
        for i, line in enumerate(sel):
            ss = s0[line] + t * (s1[line] - s0[line])
            v = f(_line_points(a, np.broadcast_to(fixed[line], (len(ss), 2)), ss))
            neg = v < 0
            change = np.nonzero(neg[1:] != neg[:-1])[0]
            mine = root[row == i]
            tol = 1e-12 * (s1[line] - s0[line])
            for c in change:
                if not np.any((mine >= ss[c] - tol) & (mine <= ss[c + 1] + tol)):
                    missed += 1
    assert missed == 0


def test_line_roots_double_roots_and_poles():
    # exp(x^2 + 0.36 + 0.64) - e: a double root at x = 0 (to rounding).
    s = ElementarySurface.parse("exp(x^2+y^2+z^2) - exp(1)")
    row, r = s.line_roots(0, np.array([[0.6, 0.8]]), np.array([-1.0]), np.array([1.5]))
    assert len(r) >= 1 and np.min(np.abs(r)) < 1e-6
    # 1/x - 1: a root at 1, none at the pole x = 0 (a sign change without a zero).
    s = ElementarySurface.parse("1/x - 1 + 0*y")
    row, r = s.line_roots(0, np.array([[0.3, 0.1]]), np.array([-2.0]), np.array([2.0]))
    assert len(r) >= 1 and np.all(np.abs(r - 1) < 1e-15)
    # sqrt(x) - 0.5 on [-1, 1]: the root 0.25, none where F is undefined.
    s = ElementarySurface.parse("sqrt(x) - 0.5 + y - y")
    row, r = s.line_roots(0, np.array([[0.3, 0.1]]), np.array([-1.0]), np.array([1.0]))
    assert len(r) >= 1 and np.all(np.abs(r - 0.25) < 1e-15)
    # tan(x) - 1 on [-1, 5]: roots at pi/4 and 5 pi/4, none at the pole pi/2.
    s = ElementarySurface.parse("tan(x) - 1 + y - y")
    row, r = s.line_roots(0, np.array([[0.3, 0.1]]), np.array([-1.0]), np.array([5.0]))
    r = np.unique(np.round(r, 12))
    np.testing.assert_allclose(r, [np.pi / 4, 5 * np.pi / 4], rtol=1e-12)


def _subdivide(s, box, level, keep):
    data = s.enclose(np.asarray(box, float))
    for _ in range(level):
        data = s.split(data).reshape((-1,) + data.shape[1:])
        data = data[keep(data)]
    return data


def _box_samples(lo, hi, k=7):
    t = np.linspace(0, 1, k)
    g = np.stack(np.meshgrid(t, t, t, indexing="ij"), -1)
    return lo[:, None, None, None] + g[None] * (hi - lo)[:, None, None, None]


def _monotone(v, axis, tol):
    d = np.diff(v, axis=axis)
    inc = np.all(d > -tol, axis=tuple(range(1, v.ndim)))
    dec = np.all(d < tol, axis=tuple(range(1, v.ndim)))
    return inc | dec


@pytest.mark.parametrize("name", list(SURFACES))
def test_box_methods_never_contradict_samples(name):
    expr, reach = SURFACES[name]
    s = ElementarySurface.from_expr(expr, name)
    f = _fn(expr)
    box = np.array([[-reach, reach * 1.1]] * 3)
    # Level 3 with every box kept: excludes_zero must keep every box where samples change sign.
    data = _subdivide(s, box, 3, lambda d: np.ones(len(d), bool))
    lo, hi = s.corners(data)
    v = f(_box_samples(lo, hi))
    crossing = (v.min(axis=(1, 2, 3)) < 0) & (v.max(axis=(1, 2, 3)) > 0)
    empty = s.excludes_zero(data)
    assert not np.any(empty & crossing)
    assert empty.any()
    # Boxes near the surface at level 4 (one split more).
    data = _subdivide(s, box, 5, lambda d: ~s.excludes_zero(d))
    lo, hi = s.corners(data)
    v = f(_box_samples(lo, hi))
    tol = 1e-12 * (1 + np.abs(v).max())
    axis = s.simple_axis(data)
    assert axis.dtype == np.int64 and (axis >= 0).sum() > len(axis) // 4
    for a in range(3):
        sel = axis == a
        if not sel.any():
            continue
        assert np.all(_monotone(v[sel], 1 + a, tol))
        for side in (0, 1):
            face = np.take(v[sel], -side, axis=1 + a)  # (K, 7, 7): axes (u, v) in cyclic order? see below
            # np.take leaves the two other axes in increasing order; both
            # monotone tests are symmetric in them.
            ok = (_monotone(face, 1, tol) | _monotone(face, 2, tol)
                  | (face.min(axis=(1, 2)) >= 0) | (face.max(axis=(1, 2)) < 0))
            assert np.all(ok)
    # Face modes on every face of the boxes.
    for n in range(3):
        u, vv = (n + 1) % 3, (n + 2) % 3
        for side in (0, 1):
            mode = s.face_modes(data, n, np.full(len(data), side))
            face = np.take(v, -side, axis=1 + n)
            # face axes are the two remaining in increasing order; map u, v to them.
            rem = [b for b in range(3) if b != n]
            ax_u, ax_v = 1 + rem.index(u), 1 + rem.index(vv)
            assert np.all(_monotone(face[mode == 0], ax_v, tol))
            assert np.all(_monotone(face[mode == 1], ax_u, tol))
            assert (mode < 2).any()


def _kept_boxes_containing(s, box, level, point):
    data = _subdivide(s, box, level, lambda d: s.may_vanish(d, (0, 1, 2)))
    lo, hi = s.corners(data)
    inside = np.all((lo <= point) & (point <= hi), axis=1)
    return data, inside


@pytest.mark.parametrize("box", [[[-1.0, 1.3]] * 3, [[-1.0, 1.0]] * 3])
@pytest.mark.parametrize("shift", [(0.0, 0.0, 0.0), (0.3, 0.2, -0.1)])
def test_may_vanish_keeps_singular_point(box, shift):
    a, b, c = shift
    expr = sin(x - a) ** 2 + sin(y - b) ** 2 - sin(z - c) ** 2
    s = ElementarySurface.from_expr(expr, str(expr))
    p = np.array([a, b, c])
    data, inside = _kept_boxes_containing(s, np.array(box), 6, p)
    assert inside.any()
    # ... and the search is selective: a few boxes around the point.
    assert len(data) < 100
    # The other tests of the search: F and one or two derivatives.
    assert s.may_vanish(data[inside], (0,)).all() and s.may_vanish(data[inside], (1, 2)).all()


def test_may_vanish_keeps_a1_attached_by_cosine_bump():
    """Seed 000, Appendix A: an A1 point (n = 1, h = 1) attached to the plane x = 0 by the cosine bump."""
    n, h = 1, 1.0
    py, pz = 0.2, -0.1
    k = np.pi / (2 * np.sqrt(h ** (n + 1)))
    q = 4 * h / (np.pi * (n + 1))
    px = -h - q
    r2 = (y - py) ** 2 + (z - pz) ** 2
    f1 = (x - px) ** (n + 1) - r2
    f2 = -x - q
    f3 = f1 + f2 - sqrt(f1**2 + f2**2)
    f4 = x + q + q * cos(k * sqrt(r2))
    f5 = 4 * h ** (n + 1) - r2
    f6 = f4 + f5 - sqrt(f4**2 + f5**2)
    f7 = x
    f8 = f6 + f7 + sqrt(f6**2 + f7**2)
    f9 = x + q
    f10 = f8 + f9 - sqrt(f8**2 + f9**2)
    f11 = f10 + f3 + sqrt(f10**2 + f3**2)
    p = np.array([px, py, pz])
    # Independently (sympy's numpy code, central differences): F and grad F
    # vanish at p, and F is quadratic there (second differences of both signs).
    f = _fn(f11)
    e = 1e-4 * np.eye(3)
    assert abs(f(p)) < 1e-14
    grad = (f(p + e) - f(p - e)) / 2e-4
    assert np.abs(grad).max() < 1e-6
    second = (f(p + e) + f(p - e) - 2 * f(p)) / 1e-8
    assert second.min() < -0.5 and second.max() > 0.5
    s = ElementarySurface.from_expr(f11, "bump")
    box = np.array([[-3.0, 1.0], [-2.5, 2.5], [-2.5, 2.5]])
    data, inside = _kept_boxes_containing(s, box, 5, p)
    assert inside.any()
    # Its jet (through the bump's cos(k sqrt(r2)) at r2 = 0): an A1,
    # the Hessian nondegenerate and indefinite, as the second differences say.
    t = s.taylor(p, 2)
    assert np.all(np.isfinite(t)) and abs(t[0, 0, 0]) < 1e-14
    assert np.abs([t[1, 0, 0], t[0, 1, 0], t[0, 0, 1]]).max() < 1e-12
    ev = np.linalg.eigvalsh(s.hessian(p))
    assert np.all(np.abs(ev) > 0.1) and ev.min() < 0 < ev.max()
    np.testing.assert_allclose(np.diag(s.hessian(p)), second, rtol=1e-4)


def test_errors_and_domains():
    with pytest.raises(SurfaceError, match="unknown symbol a"):
        ElementarySurface.from_expr(sympy.sin(x) - sympy.Symbol("a"), "sin(x) - a")
    with pytest.raises(SurfaceError, match="constant"):
        ElementarySurface.from_expr(sympy.sin(sympy.Integer(1)) + 0 * x, "sin(1)")
    with pytest.raises(SurfaceError, match="unsupported function atan2"):
        ElementarySurface.from_expr(sympy.atan2(x, y) - z, "atan2(x, y) - z")
    s = ElementarySurface.parse("sqrt(x) - 0.5 + y - y")
    assert np.isnan(s(np.array([-1.0, 0, 0])))
    data = s.enclose(np.array([[-2.0, -1.0], [0, 1], [0, 1]]))
    assert s.excludes_zero(data).all()                  # wholly undefined: no surface
    data = s.enclose(np.array([[-2.0, 1.0], [0, 1], [0, 1]]))
    assert not s.excludes_zero(data).any()              # x = 0.25 is in it
    assert s.undefined_on(data)[0] == "sqrt(x)"
    with pytest.raises(SurfaceError, match="not a number|not a finite"):
        ElementarySurface.from_expr(x + sympy.log(-1 + 0 * y + sympy.Integer(0)), "log(-1)")


def test_inverse_functions_domains():
    # asin and acos are defined on [-1, 1], acosh on [1, inf), atanh on
    # (-1, 1) with poles at the ends: no surface outside.
    s = ElementarySurface.parse("asin(x) + acos(y) - z")
    assert np.isnan(s(np.array([1.5, 0, 0]))) and np.isnan(s(np.array([0, -1.01, 0])))
    assert abs(s(np.array([1.0, -1.0, 0])) - 1.5 * np.pi) < 1e-15
    assert s.excludes_zero(s.enclose(np.array([[1.1, 2.0], [0, 1], [0, 1]]))).all()
    data = s.enclose(np.array([[0.5, 2.0], [0, 1], [0, 1]]))
    assert not s.excludes_zero(data).any() and s.simple_axis(data)[0] == -1
    assert s.undefined_on(data)[0] == "asin(x)"
    assert s.undefined_on(s.enclose(np.array([[-0.5, 0.9], [0, 1], [0, 1]]))) is None
    t = ElementarySurface.parse("atanh(x) - y")
    assert t.undefined_on(t.enclose(np.array([[-1.0, 0.5], [0, 1], [0, 1]])))[0] == "atanh(x)"
    assert np.isnan(t.taylor(np.array([1.0, 0, 0]), 2)[[0, 1, 2], 0, 0]).all()
    assert np.isnan(s.taylor(np.array([1.0, 0, 0]), 2)[[0, 1, 2], 0, 0]).all()   # asin'(1) is infinite
    u = ElementarySurface.parse("acosh(x) - y")
    assert u.excludes_zero(u.enclose(np.array([[-2.0, 0.99], [-1, 1], [-1, 1]]))).all()
    row, r = u.line_roots(0, np.array([[0.5, 0.0]]), np.array([-3.0]), np.array([3.0]))
    assert len(r) == 1 and abs(r[0] - np.cosh(0.5)) < 1e-15


def test_jet_of_cosine_bump_on_its_axis():
    """cos(k sqrt(r2)) is analytic in r2: its jet on the axis r2 = 0 (where sqrt is not) is finite and right."""
    k = 1.3
    expr = x + cos(k * sqrt((y - 0.2) ** 2 + (z + 0.1) ** 2))
    s = ElementarySurface.from_expr(expr, "bump")
    t = s.taylor(np.array([0.5, 0.2, -0.1]), 4)
    # cos(k r) = 1 - k^2 r^2 / 2 + k^4 r^4 / 24 with r^2 = v^2 + w^2.
    assert t[0, 0, 0] == pytest.approx(1.5) and t[1, 0, 0] == pytest.approx(1.0)
    assert t[0, 2, 0] == pytest.approx(-k**2 / 2) and t[0, 0, 2] == pytest.approx(-k**2 / 2)
    assert t[0, 4, 0] == pytest.approx(k**4 / 24) and t[0, 2, 2] == pytest.approx(k**4 / 12)
    assert abs(t[0, 1, 1]) < 1e-15 and abs(t[0, 3, 0]) < 1e-15
    h = s.hessian(np.array([0.5, 0.2, -0.1]))
    np.testing.assert_allclose(h, np.diag([0.0, -k**2, -k**2]), atol=1e-14)


def test_may_vanish_at_kinks_tries_the_pieces():
    """A crease is no candidate unless an active piece is singular there."""
    box = np.array([[-1.0, 1.1]] * 3)
    for expr in (Max(Abs(x), Abs(y), Abs(z)) - 0.7, Max(x**2 + y**2 + z**2 - 1, z),
                 sympy.Min(x + y, 2 * z - x) - Abs(y - 0.3)):
        s = ElementarySurface.from_expr(expr, str(expr))
        data = _subdivide(s, box, 6, lambda d: s.may_vanish(d, (0, 1, 2)))
        assert len(data) == 0, expr
        # The surface is there: the boxes with F of both signs are many.
        data = _subdivide(s, box, 4, lambda d: ~s.excludes_zero(d))
        assert len(data) > 50
    # A cone's apex on the crease with the plane z = 0: both pieces active, the cone's singular.
    s = ElementarySurface.from_expr(Max(x**2 + y**2 - z**2, z), "cone")
    data, inside = _kept_boxes_containing(s, box, 6, np.zeros(3))
    assert inside.any() and len(data) < 40


@pytest.mark.parametrize("name", ["sigmoid-union", "gyroid", "sqrt-torus"])
def test_gradient_bounds_enclose_difference_quotients(name):
    """The centred gradient bounds (second-order) hold every difference quotient on small boxes."""
    expr, reach = SURFACES[name]
    s = ElementarySurface.from_expr(expr, name)
    f = _fn(expr)
    rng = np.random.default_rng(5)
    lo = rng.uniform(-reach, reach, (400, 3))
    hi = lo + 10.0 ** rng.uniform(-3, -1, (400, 1))
    r = s._gradient_bounds(lo, hi, (0, 1, 2))
    for a in range(3):
        p = lo[:, None] + rng.random((400, 30, 3)) * (hi - lo)[:, None]
        q = p.copy()
        q[..., a] = hi[:, None, a]
        step = q[..., a] - p[..., a]
        quotient = (f(q) - f(p)) / step
        err = 1e-12 / step
        ok = (step <= 0) | ((quotient >= r.lo[a][:, None] - err) & (quotient <= r.hi[a][:, None] + err))
        assert ok.all()
    # Tighter than the natural extension somewhere (the centred form is used).
    from singmesh.boxes.intervals import interval_eval
    nat = interval_eval(s._graph, s._grad, lo, hi)
    assert all(np.all(r.hi[a] - r.lo[a] <= nat.hi[a] - nat.lo[a]) for a in range(3))
