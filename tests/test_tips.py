"""Tips: points of F = 0 where F is continuous but not differentiable (skeleton/tips.py).

The apex of a cone written with a distance, sqrt(u^2 + v^2) = |w|, and the
cusped tips of (u^2 + v^2)^(1/3) + w^2 = 1/2: grad F is infinite there, not
zero, so the singular-point search does not see them, and a mesher that does
not place them loses the cone's apex (two separate nappes) or pinches a tip
off.  (u, v, w) is (x, y, z) rotated by a float matrix written with 15
digits and shifted, so no tip is on a split plane.  The checks do not use
singmesh: F again in numpy, the tips solved from the construction, the
link's curves on a small sphere counted by the oracle.
"""

import importlib.util

import numpy as np
import pytest
from scipy.spatial import cKDTree

import singmesh

import meshcheck as mc
import oracles


def _frame(seed):
    q = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))[0]
    q = np.array([[float(f"{c:.15f}") for c in row] for row in q])
    shift = np.random.default_rng(seed + 1).uniform(-0.08, 0.08, 3).round(10)
    rows = [" + ".join(f"({q[i, j]:.15f})*{c}" for j, c in enumerate("xyz")) + f" + ({shift[i]:.10f})"
            for i in range(3)]
    return q, shift, f"u = {rows[0]}; v = {rows[1]}; w = {rows[2]};"


def _uvw(q, shift, p):
    return np.einsum("ij,...j->...i", q, p) + shift


CASES = [
    # name, F(u, v, w) typed, numpy F(u, v, w), tips in (u, v, w), fans at each, Euler, box
    ("double cone", "sqrt(u^2 + v^2) - abs(w)", lambda u, v, w: np.sqrt(u * u + v * v) - np.abs(w),
     [(0.0, 0.0, 0.0)], [2], 1, 1.0),
    ("cone", "sqrt(u^2 + v^2) - w", lambda u, v, w: np.sqrt(u * u + v * v) - w, [(0.0, 0.0, 0.0)], [1], 1, 1.0),
    ("cusped tips", "(u^2 + v^2)^(1/3) + w^2 - 1/2", lambda u, v, w: np.cbrt(u * u + v * v) + w * w - 0.5,
     [(0.0, 0.0, -np.sqrt(0.5)), (0.0, 0.0, np.sqrt(0.5))], [1, 1], 2, 1.5),
]


@pytest.mark.parametrize("seed", [4, 9])
@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_tips_are_vertices_with_their_fans(case, seed):
    name, text, f, tips, fans, chi, half = case
    q, shift, frame = _frame(seed)
    box = np.array([[-half, half]] * 3)
    m = singmesh.mesh(f"{text}; {frame}", box)

    def F(p):
        return f(*np.moveaxis(_uvw(q, shift, p), -1, 0))

    want = np.linalg.solve(q, (np.array(tips) - shift).T).T
    assert len(m.singularities) == len(want)
    size = 2 * half
    for p, n in zip(want, fans):
        sp = min(m.singularities, key=lambda s: np.linalg.norm(s.point - p))
        assert np.linalg.norm(sp.point - p) <= 1e-9 * size
        assert sp.classification.name == "non-differentiable"
        assert sp.vertex is not None and np.linalg.norm(m.vertices[sp.vertex] - p) <= 1e-9 * size
        assert oracles.branches_on_sphere(F, p, 0.04) == n
        assert sp.branches == n and mc.fans_at(m.faces, sp.vertex) == n
    V, T = m.vertices, m.faces
    assert mc.boundary_edges_off_box(V, T, box) == []
    assert mc.non_manifold_edges(T) == []
    assert mc.degenerate_triangles(V, T) == 0
    assert mc.components(T) == 1 and mc.euler(V, T) == chi
    # Vertices on the surface: |F| against the (bounded) gradient's size.
    assert np.abs(F(V)).max() <= 1e-10 * size
    _close_to_marching_cubes(V, T, F, box)


def _close_to_marching_cubes(V, T, F, box, n=128):
    """Triangles near a dense marching-cubes sample of F = 0, and every sample near the mesh."""
    if importlib.util.find_spec("skimage") is None:
        pytest.skip("scikit-image is not installed (pip install -e '.[bench]'): the marching-cubes oracle is skipped")
    from skimage.measure import marching_cubes

    h = (box[:, 1] - box[:, 0]) / n
    axes = [np.linspace(b[0] + 0.37 * s, b[1] - 0.63 * s, n) for b, s in zip(box, h)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)
    pts = marching_cubes(F(grid), 0.0, spacing=tuple(h))[0] + np.array([a[0] for a in axes])
    a, b, c = V[T[:, 0]], V[T[:, 1]], V[T[:, 2]]
    longest = np.max([np.linalg.norm(b - a, axis=1), np.linalg.norm(c - b, axis=1),
                      np.linalg.norm(a - c, axis=1)], axis=0)
    d = cKDTree(pts).query((a + b + c) / 3)[0]
    assert (d > 0.5 * longest + 2.0 * h.max()).sum() == 0
    d = cKDTree(V).query(pts)[0]
    assert (d > 2 * float(np.median(longest)) + 2 * h.max()).sum() == 0


def test_no_tip_where_the_root_does_not_vanish_on_the_surface():
    # The torus (sqrt(x^2 + y^2) - 0.8)^2 + z^2 = 0.09: the axis does not meet it.
    s = singmesh.Surface.parse("(sqrt(x^2+y^2)-0.8)^2 + z^2 - 0.09")
    assert len(s.tip_systems()) == 1
    m = singmesh.mesh(s, [[-1.5, 1.5]] * 3)
    assert m.singularities == [] and mc.euler(m.vertices, m.faces) == 0
    assert singmesh.Surface.parse("x^2 + y^2 - z^2").tip_systems() == []


def test_classifying_a_tip_says_it_has_no_jet():
    from singmesh.errors import SurfaceError
    from singmesh.skeleton.classify import classify

    with pytest.raises(SurfaceError, match="not differentiable at"):
        classify("sqrt(x^2 + y^2) - abs(z - 0.1)", (0.0, 0.0, 0.1))


@pytest.mark.parametrize("text, count", [
    ("abs(x)^0.5 + abs(y)^0.5 + abs(z)^0.5 - 1", 3),   # the star superquadric: 3 planes of cusps
])
def test_a_root_vanishing_along_a_curve_is_refused_where_the_mesh_is_open(text, count):
    # |u|^p (p < 1) vanishing along a curve of the surface makes a cuspidal
    # crease that is not traced: the mesh had open edges all along it (432
    # on the star superquadric, with a warning).  Refused in one line that
    # names the problem and a point of the crease.
    import re

    with pytest.raises(singmesh.SurfaceError) as e:
        singmesh.mesh(text, [[-1.2, 1.2]] * 3, coarse=16, fine=64)
    msg = str(e.value)
    assert "\n" not in msg and "cuspidal crease" in msg and "not differentiable" in msg
    assert f"along {count} curve(s)" in msg
    p = np.array([float(c) for c in re.search(r"through \(([^)]*)\)", msg).group(1).split(",")])
    # The point is on the surface (to the 6 digits printed) and on a plane
    # where the root's argument vanishes (one coordinate 0, or x = 0.1).
    assert abs(float(singmesh.Surface.parse(text)(p[None])[0])) <= 1e-5
    assert np.min(np.abs(np.concatenate([p, [p[0] - 0.1]]))) < 1e-5


@pytest.mark.parametrize("text, count", [
    ("abs(x)^(2/3) + abs(y)^(2/3) + abs(z)^(2/3) - 1", 3),   # star superquadrics, p = 2/3 and 0.8
    ("abs(x)^0.8 + abs(y)^0.8 + abs(z)^0.8 - 1", 3),
    ("sqrt(abs(x - 0.1)) + y^2 + z^2 - 0.5", 1),
])
def test_a_root_vanishing_along_a_curve_is_said_where_the_mesh_closes(text, count):
    # The same creases, where the lattice's mesh closes across them: kept
    # (a sphere, closed, chi 2, counted here from the faces), with the warning.
    with pytest.warns(singmesh.CreaseWarning, match="not differentiable along .* curve"):
        m = singmesh.mesh(text, [[-1.2, 1.2]] * 3, coarse=16, fine=64)
    assert len(m.stats["unfollowed_creases"]) == count
    counts = np.array(list(mc.edge_counts(m.faces).values()))
    assert len(m.faces) and (counts == 2).all()
    assert len(m.vertices) - len(counts) + len(m.faces) == 2


@pytest.mark.parametrize("text", ["abs(x)^2.5 + abs(y)^2.5 + abs(z)^3 - 1", "sqrt(x) + y - 0.5",
                                  "sqrt(x^2 + y^2) - abs(z)"])
def test_no_crease_warning_where_the_surface_is_smooth_or_followed(text):
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error", singmesh.CreaseWarning)
        m = singmesh.mesh(text, [[-1.2, 1.2]] * 3, coarse=16, fine=64)
    assert m.stats["unfollowed_creases"] == []
