"""mesh(size="curvature"): curvature-adaptive triangle sizes (issue #12).

The meshes are checked independently of the mesher (tests/meshcheck.py:
edges, Euler characteristic, fans at singular points; residuals of F at
the vertices) and their sizes against the curvature of the closed form.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import sympy as sp

import singmesh
from singmesh.cli import main

from meshcheck import boundary_edges_off_box, euler, fans_at, non_manifold_edges

X, Y, Z = sp.symbols("x y z")
ELLIPSOID = "x^2 + y^2 + 100 z^2 - 1"  # axes 1, 1, 0.1: the rim is 100 times as curved as the poles
BOX = ((-1.2, 1.2),) * 3


def _mesh(text, box, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return singmesh.mesh(text, box, **kw)


def _valid(m, chi):
    """A closed manifold in the box with Euler characteristic ``chi``, vertices on F = 0."""
    assert len(m.faces) > 100
    assert not boundary_edges_off_box(m.vertices, m.faces, m.box)
    assert not non_manifold_edges(m.faces)
    assert euler(m.vertices, m.faces) == chi
    _, g, _ = m.surface.jet(m.vertices)
    f = m.surface(m.vertices)
    side = float((m.box[:, 1] - m.box[:, 0]).max())
    gn = np.linalg.norm(g, axis=1)
    smooth = gn > 1e-6
    assert np.all(np.abs(f[smooth]) / gn[smooth] < 1e-10 * side)
    assert np.all(np.abs(f[~smooth]) < 1e-10)


def _edge_lengths(m):
    e = np.unique(np.sort(np.concatenate([m.faces[:, [0, 1]], m.faces[:, [1, 2]], m.faces[:, [2, 0]]]), axis=1), axis=0)
    return e, np.linalg.norm(m.vertices[e[:, 0]] - m.vertices[e[:, 1]], axis=1)


def test_ellipsoid_small_triangles_at_the_rim():
    m = _mesh(ELLIPSOID, BOX, size="curvature", chord=1e-3)
    _valid(m, 2)
    e, length = _edge_lengths(m)
    mid = m.vertices[e].mean(axis=1)
    rho = np.hypot(mid[:, 0], mid[:, 1])
    rim, poles = length[rho > 0.97], length[rho < 0.5]
    assert len(rim) > 50 and len(poles) > 20
    # The curvature is 100 at the rim and 0.1 at the poles (1/a^2 * c): the edges differ by a factor >= 4.
    assert rim.mean() < 0.25 * poles.mean()
    # The uniform mesh of the same number of boxes per axis at the poles has no such difference.
    u = _mesh(ELLIPSOID, BOX, coarse=16)
    e, length = _edge_lengths(u)
    rho = np.hypot(*u.vertices[e].mean(axis=1)[:, :2].T)
    assert length[rho > 0.97].mean() > 0.4 * length[rho < 0.5].mean()


def test_fewer_triangles_at_no_larger_deviation():
    """The thin ellipsoid: the curvature mesh beats the uniform one at 128 boxes per axis."""
    u = _mesh(ELLIPSOID, BOX, coarse=128)
    c = _mesh(ELLIPSOID, BOX, size="curvature", chord=1e-3)

    def deviation(m):
        tri = m.vertices[m.faces]
        pts = np.vstack([tri.mean(1), (tri[:, 0] + tri[:, 1]) / 2, (tri[:, 1] + tri[:, 2]) / 2])
        # Distance to the ellipsoid by Newton on the closed form, not the mesher's surface.
        f = sp.lambdify((X, Y, Z), X**2 + Y**2 + 100 * Z**2 - 1)
        g = sp.lambdify((X, Y, Z), [2 * X, 2 * Y, 200 * Z])
        p = pts.copy()
        for _ in range(30):
            gv = np.array(g(*p.T)).T
            p -= (f(*p.T) / (gv**2).sum(1))[:, None] * gv
        return np.linalg.norm(p - pts, axis=1).max() / 2.4

    assert len(c.faces) < len(u.faces)
    assert deviation(c) <= deviation(u)


def test_cayley_cubic_singular_points_keep_their_fans():
    m = _mesh("4(x^2 + y^2 + z^2) + 16 x y z - 1", ((-1.5, 1.5),) * 3, size="curvature", chord=2e-3, min_edge=1 / 64)
    assert len(m.faces) > 100
    assert not boundary_edges_off_box(m.vertices, m.faces, m.box) and not non_manifold_edges(m.faces)
    assert euler(m.vertices, m.faces) == 2
    nodes = np.array([[-0.5, -0.5, -0.5], [-0.5, 0.5, 0.5], [0.5, -0.5, 0.5], [0.5, 0.5, -0.5]])
    for p in nodes:
        d = np.linalg.norm(m.vertices - p, axis=1)
        assert d.min() < 1e-9
        assert fans_at(m.faces, int(np.argmin(d))) == 2


def test_rotated_ellipsoid_15_digits():
    """Float-rotated, shifted ellipsoid: the chord tolerance is met, and min_edge bounds the refinement."""
    rng = np.random.default_rng(5)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    t = np.array([0.0713, -0.0391, 0.0527])
    axes = np.array([0.8, 0.4, 0.12])
    u = [sum(q[i, j] * ((X, Y, Z)[i] - t[i]) for i in range(3)) for j in range(3)]
    e = sp.expand(sum((u[j] / axes[j]) ** 2 for j in range(3)) - 1)
    text = str(e.xreplace({f: sp.Float(f"{float(f):.15g}") for f in e.atoms(sp.Float)}))

    def deviation(m):
        """Largest distance of centroids and edge midpoints to the unrotated ellipsoid (Newton), / box side."""
        tri = m.vertices[m.faces]
        pts = np.vstack([tri.mean(1), (tri[:, 0] + tri[:, 1]) / 2, (tri[:, 1] + tri[:, 2]) / 2,
                         (tri[:, 2] + tri[:, 0]) / 2])
        p = (pts - t) @ q
        x, s2 = p.copy(), axes**2
        for _ in range(40):
            g = 2 * x / s2
            x -= ((x**2 / s2).sum(1) - 1)[:, None] / (g**2).sum(1)[:, None] * g
        return np.linalg.norm(x - p, axis=1).max() / 2.0

    box = ((-1, 1),) * 3
    m = _mesh(text, box, size="curvature", chord=1e-3)
    _valid(m, 2)
    assert deviation(m) <= 1e-3
    # The uniform mesh from the same largest boxes (max_edge 1/8) is far off:
    # more than 10 times the tolerance as the boxes make it, and still more
    # than 3 times once improve (on by default) has moved its vertices.
    assert deviation(_mesh(text, box, coarse=8, improve=False)) > 1e-2
    assert deviation(_mesh(text, box, coarse=8)) > 3e-3
    # A shortest edge of 1/128 stops the refinement at the rim: fewer triangles, the tolerance not met.
    capped = _mesh(text, box, size="curvature", chord=1e-3, min_edge=1 / 128)
    assert len(capped.faces) < len(m.faces) and deviation(capped) > 1e-3


@pytest.mark.parametrize("kw, words", [
    (dict(size="adaptive"), "size must be"),
    (dict(min_edge=0.01), "size='curvature'"),
    (dict(size="curvature", chord=0.0), "chord"),
    (dict(size="curvature", chord=-1e-3), "chord"),
    (dict(size="curvature", max_edge=2.0), "max_edge"),
    (dict(size="curvature", min_edge="small"), "min_edge"),
    (dict(size="curvature", min_edge=0.2, max_edge=0.1), "larger than max_edge"),
    (dict(size="curvature", min_edge=1e-4), "raise fine"),
])
def test_bad_options_one_line(kw, words):
    with pytest.raises(singmesh.SurfaceError, match=words) as info:
        singmesh.mesh("x^2 + y^2 + z^2 - 1", ((-1.5, 1.5),) * 3, **kw)
    assert "\n" not in str(info.value)


def test_cli_size_curvature(tmp_path, capsys):
    out = tmp_path / "e.vtu"
    assert main(["mesh", ELLIPSOID, "--box", "-1.2", "1.2", "-1.2", "1.2", "-1.2", "1.2", "-o", str(out),
                 "--size", "curvature", "--chord", "0.002", "--max-edge", "0.125"]) == 0
    assert "Euler characteristic 2" in capsys.readouterr().out
    assert main(["mesh", ELLIPSOID, "--size", "curvature", "--chord", "-1"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("singmesh: error:") and "chord" in err and "\n" not in err
