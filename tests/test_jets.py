"""Taylor jets (singmesh/jets.py through ElementarySurface.taylor) against sympy's derivatives."""

from math import factorial

import numpy as np
import pytest
import sympy
from sympy import (Abs, Max, Min, Rational, acos, acosh, asin, asinh, atan, atanh, cos, cosh, exp, log, sin, sinh,
                   sqrt, tan, tanh)

from singmesh.elementary import ElementarySurface
from singmesh.syntax import X, Y, Z

x, y, z = X, Y, Z

FUNCTIONS = [
    exp(x - 2 * y) - z, log(x**2 + y**2 + 1) - z, sin(x * y) + z, cos(x + z) - y, tan(0.3 * x + y) - z,
    sinh(x) - y * z, cosh(y - z) - 2 + x, tanh(3 * x) + y**2 - z, sqrt(x**2 + y**2 + 2) - z,
    (x**2 + 1) ** Rational(1, 3) - y, 1 / (1 + x**2 + y**2) - z, Abs(x - 3) + y**3 - z,
    Max(x**2 + y**2 + z**2 - 1, z - 5), Min(x, y - 7) + z, x**-3 * y - z + 2,
    1 / (1 + exp(-20 * (x**2 + y**2 + z**2 - 1))) - Rational(1, 2),
    (x**2 - 1) + z + sqrt((x**2 - 1)**2 + z**2) - y, sqrt(x**2 + y**2) - 1 + z**2,
    asin(0.3 * x + 0.2 * y) - z, acos(0.4 * x - 0.3 * z) + y, atan(x * y) - z + atan(2 * z),
    asinh(x - y) + z, acosh(2 + x**2 - y) - z, atanh(0.4 * x + 0.1 * z) - y,
]


def _sympy_taylor(expr, p, n):
    """T[i, j, k] = d^(i+j+k) F / dx^i dy^j dz^k (p) / (i! j! k!), by sympy."""
    t = np.zeros((n + 1, n + 1, n + 1))
    subs = {x: sympy.Float(p[0], 30), y: sympy.Float(p[1], 30), z: sympy.Float(p[2], 30)}
    dx = expr
    for i in range(n + 1):
        dy = dx
        for j in range(n + 1 - i):
            dz = dy
            for k in range(n + 1 - i - j):
                t[i, j, k] = float(dz.evalf(30, subs=subs)) / (factorial(i) * factorial(j) * factorial(k))
                dz = sympy.diff(dz, z)
            dy = sympy.diff(dy, y)
        dx = sympy.diff(dx, x)
    return t


@pytest.mark.parametrize("expr", FUNCTIONS, ids=[str(f) for f in FUNCTIONS])
def test_taylor_matches_sympy(expr):
    rng = np.random.default_rng(7)
    s = ElementarySurface.from_expr(expr, str(expr))
    for _ in range(2):
        p = rng.uniform(-1.2, 1.2, 3)
        n = 4
        want = _sympy_taylor(expr, p, n)
        got = s.taylor(p, n)
        assert got.shape == (n + 1,) * 3
        scale = np.abs(want).max()
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-11 * scale)
        # Order None is the surface's degree; zero above total degree n.
        assert s.taylor(p).shape == (s.degree + 1,) * 3
        deg = np.add.outer(np.add.outer(np.arange(n + 1), np.arange(n + 1)), np.arange(n + 1))
        assert np.all(got[deg > n] == 0)


def test_points_match_sympy():
    """Values, gradients and Hessians at many points against sympy's diff."""
    rng = np.random.default_rng(3)
    p = rng.uniform(-1.2, 1.2, (50, 3))
    for expr in FUNCTIONS:
        s = ElementarySurface.from_expr(expr, str(expr))
        args = (x, y, z)
        f = sympy.lambdify(args, expr, "numpy")
        grad = [sympy.lambdify(args, sympy.diff(expr, v), "numpy") for v in args]
        # Away from kinks: DiracDelta (Abs'') is 0 there.
        hess = [[sympy.lambdify(args, sympy.diff(expr, v, w).replace(
            lambda e: isinstance(e, sympy.DiracDelta), lambda e: sympy.S.Zero), "numpy")
            for w in args] for v in args]
        want_f = np.broadcast_to(f(*p.T), (50,))
        want_g = np.stack([np.broadcast_to(g(*p.T), (50,)) for g in grad], -1)
        want_h = np.stack([np.stack([np.broadcast_to(h(*p.T), (50,)) for h in row], -1) for row in hess], -2)
        v, g, h = s.jet(p)
        mag = s.magnitude(p)
        np.testing.assert_allclose(v, want_f, rtol=0, atol=1e-13 * (1 + mag).max())
        np.testing.assert_allclose(s(p), want_f, rtol=0, atol=1e-13 * (1 + mag).max())
        np.testing.assert_allclose(g, want_g, rtol=1e-12, atol=1e-12 * np.abs(want_g).max())
        np.testing.assert_allclose(s.gradient(p), want_g, rtol=1e-12, atol=1e-12 * np.abs(want_g).max())
        np.testing.assert_allclose(h, want_h, rtol=1e-11, atol=1e-11 * np.abs(want_h).max())
        np.testing.assert_allclose(s.hessian(p), want_h, rtol=1e-11, atol=1e-11 * np.abs(want_h).max())
        # Taylor's second-order terms are the Hessian / 2 (off-diagonal: the Hessian).
        t = s.taylor(p[0], 2)
        assert abs(t[2, 0, 0] - want_h[0, 0, 0] / 2) <= 1e-11 * (1 + np.abs(want_h[0]).max())
        assert abs(t[0, 1, 1] - want_h[0, 1, 2]) <= 1e-11 * (1 + np.abs(want_h[0]).max())


def test_polynomial_agrees_with_sympy_to_rounding():
    """A polynomial with float coefficients (a rotated Cayley cubic): values, jets, taylor."""
    q, _ = np.linalg.qr(np.random.default_rng(5).normal(size=(3, 3)))
    u = [sum(sympy.Float(q[i, j], 15) * v for j, v in enumerate((x, y, z))) for i in range(3)]
    expr = 4 * (u[0]**2 + u[1]**2 + u[2]**2) + 16 * u[0] * u[1] * u[2] - 1
    s = ElementarySurface.from_expr(expr, str(expr))
    poly = sympy.Poly(sympy.expand(expr), x, y, z)
    rng = np.random.default_rng(11)
    for p in rng.uniform(-1, 1, (5, 3)):
        want = _sympy_taylor(expr, p, 3)
        got = s.taylor(p, 5)
        np.testing.assert_allclose(got[:4, :4, :4] * (np.add.outer(np.add.outer(np.arange(4), np.arange(4)), np.arange(4)) <= 3),
                                   want, rtol=0, atol=1e-13 * np.abs(want).max())
        assert np.abs(got[np.add.outer(np.add.outer(np.arange(6), np.arange(6)), np.arange(6)) > 3]).max() <= 1e-13 * np.abs(want).max()
        val = float(poly.eval({x: p[0], y: p[1], z: p[2]}))
        assert abs(s(p) - val) <= 64 * np.finfo(float).eps * s.magnitude(p)
        grad = np.array([want[1, 0, 0], want[0, 1, 0], want[0, 0, 1]])
        hess = np.array([[2 * want[2, 0, 0], want[1, 1, 0], want[1, 0, 1]],
                         [want[1, 1, 0], 2 * want[0, 2, 0], want[0, 1, 1]],
                         [want[1, 0, 1], want[0, 1, 1], 2 * want[0, 0, 2]]])
        size = np.abs(want).max()
        np.testing.assert_allclose(s.gradient(p), grad, rtol=0, atol=1e-13 * size)
        np.testing.assert_allclose(s.value_gradient(p)[1], grad, rtol=0, atol=1e-13 * size)
        np.testing.assert_allclose(s.hessian(p), hess, rtol=0, atol=1e-13 * size)
        assert np.all(s.gradient_magnitude(p) >= np.abs(grad) * (1 - 1e-12))


R = sqrt((y - Rational(1, 10))**2 + (z + Rational(1, 5))**2)


@pytest.mark.parametrize("expr, value, dx, curvature", [
    (cos(sympy.pi / 2 * R) + x, 1.7, 1.0, -(np.pi / 2) ** 2),
    (cos(sympy.pi / 2 * Min(2, R)) + x, 1.7, 1.0, -(np.pi / 2) ** 2),
    (cosh(3 * Max(R, -1)) - x, 0.3, -1.0, 9.0),
], ids=["cos", "cos-min", "cosh-max"])
def test_cosine_bump_on_its_axis(expr, value, dx, curvature):
    """Seed 000's cosine bump cos(k r) on its axis r = 0, also cut by Min/Max:
    analytic there (1 -+ k^2 r^2 / 2 + ..., a series in r^2) although sqrt
    is not.  The jet at the axis point (0.7, 0.1, -0.2) is that series'
    and the magnitudes (rounding scales) are finite."""
    s = ElementarySurface.from_expr(expr, str(expr))
    p = np.array([[0.7, 0.1, -0.2]])
    v, g, h = s.jet(p)
    np.testing.assert_allclose(v, [value], rtol=1e-14)
    np.testing.assert_allclose(g, [[dx, 0, 0]], atol=1e-15)
    np.testing.assert_allclose(h[0], np.diag([0.0, curvature, curvature]), rtol=1e-13, atol=1e-15)
    assert np.isfinite(s.magnitude(p)).all() and np.isfinite(s.gradient_magnitude(p)).all()
