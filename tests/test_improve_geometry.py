"""The shaping pass's shared triangle geometry against the separate computations it replaces.

``_geometry`` / ``_shape_of`` / ``_big_of`` / ``_lean_of`` (one set of edge vectors and
products per triangle, for the flip test, the lean test and the stored cotangents)
must give the bits of the formulas computed apart (main before the eleventh speed
pass), on random, float-shifted, sliver, needle, zero-area and repeated-corner
triangles and single columns.
"""

import numpy as np
import pytest

from singmesh import tolerances as tol
from singmesh.facets.improve import _big_of, _cross, _dot, _geometry, _lean_of, _shape_of


def _old_lean(p, q, r, ref):
    n = _cross(q - p, r - p)
    ln = _dot(n, n)
    longest = np.maximum(np.maximum(_dot(q - p, q - p), _dot(r - q, r - q)), _dot(p - r, p - r))
    c = _dot(n, ref) / np.sqrt(np.maximum(ln * _dot(ref, ref), 1e-300))
    return np.where(np.sqrt(ln) > tol.ZERO_AREA * longest, c, -1.0)


def _old_max_cos(p, q, r):
    u, w, x = q - p, r - q, p - r
    lu, lw, lx = _dot(u, u), _dot(w, w), _dot(x, x)
    c0 = -_dot(x, u) / np.sqrt(np.maximum(lx * lu, 1e-300))
    c1 = -_dot(u, w) / np.sqrt(np.maximum(lu * lw, 1e-300))
    c2 = -_dot(w, x) / np.sqrt(np.maximum(lw * lx, 1e-300))
    return np.maximum(np.maximum(c0, c1), c2)


def _old_faces(q0, q1, q2):
    e0, e1, e2 = q1 - q0, q2 - q1, q0 - q2
    l0, l1, l2 = _dot(e0, e0), _dot(e1, e1), _dot(e2, e2)
    d0, d1, d2 = -_dot(e0, e2), -_dot(e0, e1), -_dot(e1, e2)
    return l0, l1, l2, d0, d1, d2


def _triangles(rng, n):
    shift = np.array([[0.123456789012345], [-7.65432109876543], [3.14159265358979]])
    p = rng.standard_normal((3, n)) + shift
    q = p + rng.standard_normal((3, n)) * 10.0 ** rng.integers(-8, 2, n)
    r = p + rng.standard_normal((3, n)) * 10.0 ** rng.integers(-8, 2, n)
    k = n // 8
    r[:, :k] = p[:, :k] + 0.5 * (q[:, :k] - p[:, :k])  # zero-area (collinear) triangles
    q[:, k:2 * k] = p[:, k:2 * k]  # repeated corners
    r[:, 2 * k:3 * k] = q[:, 2 * k:3 * k] + 1e-13 * rng.standard_normal((3, k))  # needles
    return p, q, r


@pytest.mark.parametrize("n", [1, 2, 3, 64, 5000])
def test_shared_geometry_is_bit_for_bit_the_separate_formulas(n):
    rng = np.random.default_rng(n)
    p, q, r = _triangles(rng, n)
    ref = rng.standard_normal((3, n))
    geo = _geometry(p, q, r)
    assert _lean_of(geo, ref).tobytes() == _old_lean(p, q, r, ref).tobytes()
    shape = _shape_of(geo)
    for new, old in zip(shape, _old_faces(p, q, r)):
        _same(new, old)
    _same(_big_of(*shape), _old_max_cos(p, q, r))
    # Column views of a wider stack (the flip pass's new triangles are the first
    # half of its four) give the same bits.
    wide = _geometry(*(np.concatenate([x, x], axis=1) for x in (p, q, r)))
    half = _shape_of(tuple(g[..., :n] for g in wide))
    for new, old in zip(half, shape):
        assert np.asarray(new).tobytes() == np.asarray(old).tobytes()


def _same(new, old):
    """The same values bit for bit, but for the sign of a zero (a dot product of an edge
    of length 0 comes out -0.0 one way and +0.0 the other; only compared, never signed)."""
    new, old = np.asarray(new), np.asarray(old)
    assert np.array_equal(new, old)
    nonzero = new != 0
    assert new[nonzero].tobytes() == old[nonzero].tobytes()


def test_shape_of_known_triangles():
    # An equilateral triangle: all cosines 1/2; a right isosceles one: the largest is
    # that of its 45-degree angles; a degenerate one: cosine 1 and no lean.
    s = np.sqrt(3.0) / 2
    p, q, r = (np.array(c, float).reshape(3, 1) for c in ([0, 0, 0], [1, 0, 0], [0.5, s, 0]))
    assert np.allclose(_big_of(*_shape_of(_geometry(p, q, r))), 0.5, atol=1e-15)
    p, q, r = (np.array(c, float).reshape(3, 1) for c in ([0, 0, 0], [1, 0, 0], [0, 1, 0]))
    assert np.allclose(_big_of(*_shape_of(_geometry(p, q, r))), np.sqrt(0.5), atol=1e-15)
    assert _lean_of(_geometry(p, q, r), np.array([[0.0], [0.0], [2.0]]))[0] == pytest.approx(1.0)
    p, q, r = (np.array(c, float).reshape(3, 1) for c in ([0, 0, 0], [1, 0, 0], [2, 0, 0]))
    assert _lean_of(_geometry(p, q, r), np.array([[0.0], [0.0], [1.0]]))[0] == -1.0
