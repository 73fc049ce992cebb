"""The acceptance audit of issue #10 (non-polynomial surfaces), as a user types them.

Each case is checked independently of the mesher: counts of the work
done (a hang is a count that grows without bound, measured here instead
of a wall-clock budget), the mesh's edges counted from its faces,
residuals of F written again in numpy, and the one line the user is told.
"""

import re
import warnings

import numpy as np
import pytest

import singmesh
from singmesh.elementary import ElementarySurface

import meshcheck as mc


def _rotated(seed):
    """Three rotated, shifted coordinates as text (15-digit floats) and as numpy code."""
    q = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))[0]
    shift = np.array([0.0123456789, -0.0345678901, 0.0234567891])
    rows = ["(" + " + ".join(f"({q[i, j]:.15f})*{v}" for j, v in enumerate("xyz")) + f" + ({shift[i]:.10f}))"
            for i in range(3)]
    qr = np.array([[float(f"{q[i, j]:.15f}") for j in range(3)] for i in range(3)])
    return rows, lambda x, y, z: qr @ np.stack([x, y, z]) + shift[:, None]


class _Count:
    """Points at which ElementarySurface.jet was asked (Newton's work), while in the context."""

    def __init__(self, monkeypatch):
        self.points = 0
        jet = ElementarySurface.jet

        def counted(surface, points):
            self.points += int(np.asarray(points).size // 3)
            return jet(surface, points)

        monkeypatch.setattr(ElementarySurface, "jet", counted)


def _mesh(text, **kw):
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        m = singmesh.mesh(text, **kw)
    return m, [str(x.message) for x in w]


def _named_point(message):
    said = re.search(r"e\.g\. at \(([-0-9.e]+), ([-0-9.e]+), ([-0-9.e]+)\)", message)
    return np.array([float(v) for v in said.groups()])


# ------------------------------------------------------------ 2: F touching 0 along a sheet
@pytest.mark.parametrize("rotated", [False, True])
def test_touching_half_plane_is_said_fast(monkeypatch, rotated):
    # sqrt(v^2 + w^2) - w >= 0 vanishes on the half-plane v = 0, w >= 0:
    # F and grad F vanish on a sheet.  On main Newton ran from each of the
    # 65536 candidate boxes of that sheet (millions of jets, 39 s at the
    # default settings) and tips were found all along the half-plane's
    # edge; the answer was "only isolated point(s) and line(s)".
    if rotated:
        (u, v, w), rot = _rotated(3)
        text = f"sqrt({v}^2 + {w}^2) - {w}"

        def f(x, y, z):
            _, b, c = rot(x, y, z)
            return np.sqrt(b * b + c * c) - c
        kw = dict(coarse=16, fine=64)
    else:
        text = "sqrt(y^2 + z^2) - z"

        def f(x, y, z):
            return np.sqrt(y * y + z * z) - z
        kw = {}
    count = _Count(monkeypatch)
    m, said = _mesh(text, **kw)
    assert count.points < 300_000
    assert len(m.faces) == 0 and m.singularities == []
    assert len(said) == 1 and re.search(r">= 0 in the box .* only touches 0 .*without changing sign", said[0])
    assert [n for n in m.notes() if "touches 0" in n] and not [n for n in m.notes() if "isolated" in n]
    p = _named_point(said[0])
    assert abs(f(*p[:, None])[0]) <= 1e-5 and np.all(np.abs(p) <= 2.0)
    # F is >= 0 (to rounding) on a sample of the box: nothing was left out.
    g = np.random.default_rng(1).uniform(-2, 2, size=(3, 20000))
    assert f(*g).min() >= -1e-12
