"""Interval bounds of elementary functions (boxes/intervals.py) against dense samples.

The samples are sympy's own numpy code (lambdify), independent of the
graph evaluator: every finite sample in a box must lie in the bounds,
and every difference quotient along an axis in the derivative's bounds
(the mean value theorem, which also holds across kinks for the hull of
the pieces' derivatives).
"""

import zlib

import numpy as np
import pytest
import sympy
from sympy import (Abs, Max, Min, Rational, acos, acosh, asin, asinh, atan, atanh, cos, cosh, exp, log, sin, sinh,
                   sqrt, tan, tanh)

from singmesh.boxes.intervals import Graph, interval_eval
from singmesh.syntax import X, Y, Z

x, y, z = X, Y, Z

EXPRESSIONS = [
    x + y - z, x * y, x * y * z - 2 * x, x**2, x**3, x**4 - y**5, 1 / x, x**-2, y / x,
    x ** Rational(1, 3), x ** Rational(3, 2), x ** Rational(-1, 2), x**0.7, sqrt(x), sqrt(x**2 + y**2) - 1,
    Abs(x), Abs(x - y) - Abs(z), Min(x, y, z), Max(x, y**2, -z), Max(x**2 + y**2 + z**2 - 1, z),
    exp(x), exp(-20 * x) / (1 + exp(-20 * y)), log(x), log(x**2 + y), sin(x), cos(x), sin(3 * x + y),
    cos(x * y), tan(x), tan(x + y), sinh(x), cosh(x), tanh(x), tanh(5 * x - y),
    # R-functions (seed 000's CSG): intersection and union, nested.
    x + y - sqrt(x**2 + y**2), (x**2 - 1) + z + sqrt((x**2 - 1)**2 + z**2),
    (x - y + z - sqrt((x - y)**2 + z**2)) + y + sqrt((x - y + z - sqrt((x - y)**2 + z**2))**2 + y**2),
    sin(x) * cos(y) + sin(y) * cos(z) + sin(z) * cos(x), sin(1 / x), Rational(1, 3) * x - sympy.pi * y,
    # Inverse functions: monotone, with domain ends at +-1 (boxes centred there).
    asin(x), acos(x), atan(x), asinh(x), acosh(x), atanh(x / 5), atanh(y - 1 + x**2), asin(x * y / 25) - acos(z / 5), atan(3 * x - y) * z,
    asin(x**2 + y**2 - 1), acosh(1 + x**2) + atanh(y / 2), asinh(x * y) + atan(1 / z),
]

_EPS = np.finfo(float).eps


def _boxes(rng, n):
    """Random boxes: centres near the kinks, poles and period ends, widths from 1e-12 to 20."""
    specials = np.array([0.0, np.pi / 2, -np.pi / 2, np.pi, 1.0, -1.0, 3 * np.pi / 2, 2 * np.pi])
    c = rng.uniform(-5, 5, (n, 3))
    pick = rng.random((n, 3)) < 0.4
    c = np.where(pick, rng.choice(specials, (n, 3)) + rng.normal(0, 1e-3, (n, 3)) * rng.integers(0, 2, (n, 3)), c)
    w = 10.0 ** rng.uniform(-12, 1.3, (n, 3))
    lo = c - w * rng.random((n, 3))
    hi = lo + w
    # A few huge boxes and boxes with huge coordinates.
    lo[:5], hi[:5] = -1e3, 1e3
    lo[5:10], hi[5:10] = 1e6, 1e6 + 3.0
    return lo, hi


def _samples(rng, lo, hi, k):
    t = rng.random((len(lo), k, 3))
    t[:, :8] = np.array(np.meshgrid([0, 1], [0, 1], [0, 1], indexing="ij")).reshape(3, -1).T
    return lo[:, None] + t * (hi - lo)[:, None]


def _check_enclosed(values, lo, hi, what, terms=1.0):
    # The samples' own rounding: a few ulps of the values, and of the terms
    # that cancel (R-functions: x - y + z - sqrt(...) with x, y, z ~ 5 is
    # off by ~1e-15 in numpy's evaluation; x^2 - 1 + ...: of 1).
    slack = 4 * _EPS * (np.abs(np.stack([lo, hi])).max(axis=0) + 1.0 + terms)[:, None]
    ok = np.isnan(values) | ((values >= lo[:, None] - slack) & (values <= hi[:, None] + slack))
    bad = np.argwhere(~ok)
    assert len(bad) == 0, f"{what}: sample {values[tuple(bad[0])]} outside [{lo[bad[0][0]]}, {hi[bad[0][0]]}]"


@pytest.mark.parametrize("expr", EXPRESSIONS, ids=[str(e) for e in EXPRESSIONS])
def test_bounds_enclose_samples(expr):
    rng = np.random.default_rng(zlib.crc32(str(expr).encode()))
    g = Graph()
    node = g.from_sympy(expr)
    lo, hi = _boxes(rng, 300)
    r = interval_eval(g, [node], lo, hi)
    blo, bhi = r.lo[0], r.hi[0]
    p = _samples(rng, lo, hi, 60)
    fn = sympy.lambdify((x, y, z), expr, "numpy")
    with np.errstate(all="ignore"):
        v = np.broadcast_to(np.asarray(fn(p[..., 0], p[..., 1], p[..., 2]), float), p.shape[:2])
    v = np.where(np.isfinite(v), v, np.nan)
    # A box with a finite sample must not be declared undefined.
    assert not (np.isnan(blo) & np.isfinite(v).any(axis=1)).any()
    _check_enclosed(v, blo, bhi, str(expr), np.abs(p).max(axis=(1, 2)))
    # The bounds are not trivially wide on small boxes where F is tame.
    small = ((hi - lo).max(axis=1) < 1e-6) & np.isfinite(v).all(axis=1)
    small[small] &= np.ptp(v[small], axis=1) < 1e-4
    assert small.sum() >= 3
    assert np.all((bhi - blo)[small] < 1e-3)


@pytest.mark.parametrize("expr", EXPRESSIONS, ids=[str(e) for e in EXPRESSIONS])
def test_derivative_bounds_enclose_difference_quotients(expr):
    rng = np.random.default_rng(1 + zlib.crc32(str(expr).encode()))
    g = Graph()
    node = g.from_sympy(expr)
    grads = [g.diff(node, a) for a in range(3)]
    lo, hi = _boxes(rng, 200)
    lo, hi = lo[10:], hi[10:]
    # Difference quotients need steps well above rounding, and F continuous
    # on the box (no pole inside).
    wide = (hi - lo).min(axis=1) > 1e-3
    f = interval_eval(g, [node], lo, hi)
    wide &= np.isfinite(f.lo[0]) & np.isfinite(f.hi[0])
    lo, hi = lo[wide], hi[wide]
    r = interval_eval(g, grads, lo, hi)
    fn = sympy.lambdify((x, y, z), expr, "numpy")
    for a in range(3):
        p = _samples(rng, lo, hi, 40)
        q = p.copy()
        h = (hi - lo)[:, a] * rng.uniform(0.05, 1.0, (len(lo), 40)).T
        q[..., a] = np.minimum(p[..., a] + h.T, hi[:, None, a])
        step = q[..., a] - p[..., a]
        with np.errstate(all="ignore"):
            fp = np.broadcast_to(np.asarray(fn(p[..., 0], p[..., 1], p[..., 2]), float), p.shape[:2])
            fq = np.broadcast_to(np.asarray(fn(q[..., 0], q[..., 1], q[..., 2]), float), p.shape[:2])
            quotient = (fq - fp) / step
            # Rounding of the two values, divided by the step.
            err = 1e-10 * (np.abs(fp) + np.abs(fq) + 1.0) / step
        quotient = np.where(np.isfinite(quotient) & (step > 0) & (err < 1e-3), quotient, np.nan)
        dlo, dhi = r.lo[a], r.hi[a]
        ok = np.isnan(quotient) | ((quotient >= dlo[:, None] - err - 1e-9 * np.abs(dlo[:, None]))
                                   & (quotient <= dhi[:, None] + err + 1e-9 * np.abs(dhi[:, None])))
        bad = np.argwhere(~ok)
        assert len(bad) == 0, (expr, a, quotient[tuple(bad[0])], dlo[bad[0][0]], dhi[bad[0][0]],
                               lo[bad[0][0]], hi[bad[0][0]])


def test_kinks_enclose_both_sides():
    """Derivative bounds across a kink hold both one-sided derivatives."""
    g = Graph()
    n = g.from_sympy(Abs(x) + Max(y, 2 * y) + Min(z, -z))
    d = [g.diff(n, a) for a in range(3)]
    lo = np.array([[-1e-3, -1e-3, -1e-3]])
    r = interval_eval(g, d, lo, -lo)
    assert r.lo[0][0] <= -1 and r.hi[0][0] >= 1
    assert r.lo[1][0] <= 1 and r.hi[1][0] >= 2
    assert r.lo[2][0] <= -1 and r.hi[2][0] >= 1
    # Away from the kink: the one piece's derivative only.
    r = interval_eval(g, d, lo + 1.0, -lo + 1.0)
    assert r.lo[0][0] > 0.99 and r.hi[0][0] < 1.01
    assert r.lo[1][0] > 1.99 and r.hi[1][0] < 2.01


def test_special_ranges():
    """Exact ranges: sin over its maximum, tan over a pole, even and odd powers, 1/[0, 1]."""
    g = Graph()
    nodes = [g.from_sympy(e) for e in (sin(x), tan(x), x**2, x**3, 1 / x, x ** Rational(1, 2), log(x))]
    lo = np.array([[1.5, 0, 0], [-0.5, 0, 0], [0.0, 0, 0], [-2.0, 0, 0]])
    hi = np.array([[1.6, 0, 0], [0.5, 0, 0], [1.0, 0, 0], [-1.0, 0, 0]])
    r = interval_eval(g, nodes, lo, hi)
    assert r.hi[0][0] == 1.0 and r.lo[0][0] < np.sin(1.5) < r.lo[0][0] + 1e-12  # sin: max pi/2 inside
    assert np.isfinite(r.lo[1][1]) and r.hi[1][1] < 0.55                          # tan: no pole in [-0.5, 0.5]
    assert r.lo[1][0] == -np.inf and r.hi[1][0] == np.inf                          # tan: pole pi/2 in [1.5, 1.6]
    assert r.lo[2][1] <= 0 and r.lo[2][1] > -1e-300 and r.hi[2][1] >= 0.25         # x^2 on [-0.5, 0.5]: [0, 0.25]
    assert r.lo[3][3] <= -8 and r.hi[3][3] >= -1 and r.hi[3][3] < -0.999           # x^3 on [-2, -1]
    assert r.hi[4][2] == np.inf and 0.99 < r.lo[4][2] <= 1                         # 1/[0, 1] = [1, inf]
    assert r.lo[4][1] == -np.inf and r.hi[4][1] == np.inf                          # 1/[-0.5, 0.5]
    assert np.isnan(r.lo[5][3]) and np.isnan(r.lo[6][3])                           # sqrt, log of [-2, -1]: undefined
    assert r.clipped[1] and not r.clipped[0]                                      # sqrt of [-0.5, 0.5] clipped


def test_product_with_an_exact_zero_is_exactly_zero():
    """x y, y + z and y^2 with y = z = [0, 0] are [0, 0], not +-5e-324: under a sqrt that rounding
    became 2e-162, and a lattice line on which sqrt(x y) - z is 0 throughout
    (y = z = 0) looked like no flat piece to the root finder (issue #10's
    run that did not finish)."""
    g = Graph()
    c = 1.23456789012345
    nodes = [g.from_sympy(e) for e in (x * y, sqrt(x * y) - z, sqrt(c * x * y) - z, (x * y) ** Rational(1, 3) - z,
                                       sqrt(y + z) - z, sqrt(y**2 + c * z) - y)]
    lo = np.array([[-1.0, 0.0, 0.0], [0.3, 0.0, 0.0], [-0.7, -0.0, 0.0]])
    hi = np.array([[1.0, 0.0, 0.0], [0.7, 0.0, 0.0], [-0.1, 0.0, 0.0]])
    r = interval_eval(g, nodes, lo, hi)
    assert (r.lo[0] == 0).all() and (r.hi[0] == 0).all()
    for k in (1, 2, 3, 4, 5):
        assert (np.abs(r.lo[k]) <= 1e-250).all() and (np.abs(r.hi[k]) <= 1e-250).all()
    # Operands that are not exactly 0 still round outwards: 1e-200 * 1e-200
    # and (1e-170)^2 underflow to 0, but are > 0.
    sq = g.from_sympy(y**2)
    r = interval_eval(g, [nodes[0], sq], np.array([[1e-200, 1e-200, 0.0]]), np.array([[2e-200, 2e-200, 0.0]]))
    assert r.lo[0][0] <= 0 < r.hi[0][0] and r.hi[1][0] > 0


def test_rfunction_bounds_are_tight():
    """f + g - sqrt(f^2 + g^2) is increasing in f and g: its bounds are its corner values."""
    g = Graph()
    n = g.from_sympy(x + y - sqrt(x**2 + y**2))
    assert g.ops[n] == "rfun"
    lo = np.array([[-0.5, -0.4, 0.0]])
    hi = np.array([[0.3, 0.2, 0.0]])
    r = interval_eval(g, [n], lo, hi)
    want_lo = -0.9 - np.hypot(0.5, 0.4)
    want_hi = 0.5 - np.hypot(0.3, 0.2)
    assert want_lo - 1e-15 <= r.lo[0][0] <= want_lo and want_hi <= r.hi[0][0] <= want_hi + 1e-15


def test_rfunction_derivative_bounds_with_huge_values():
    """The ratio f / sqrt(f^2 + g^2) keeps its bounds where the squares overflow."""
    g = Graph()
    n = g.from_sympy(x + y - sqrt(x**2 + y**2))
    dx = g.diff(n, 0)
    lo = np.array([[-1e200, 1e199, 0.0]])
    hi = np.array([[-1e199, 1e200, 0.0]])
    r = interval_eval(g, [dx], lo, hi)
    # F_x = 1 - x / sqrt(x^2 + y^2): from 1 + 1/sqrt(1.01) to 1 + 1/sqrt(101).
    want_lo, want_hi = 1 + 1 / np.sqrt(101), 1 + 1 / np.sqrt(1.01)
    assert want_lo - 1e-12 <= r.lo[0][0] <= want_lo and want_hi <= r.hi[0][0] <= want_hi + 1e-12
