"""Singular points on a face of the box (issue #13): a box cut at a symmetry
plane through nodes, as users draw half of a symmetric surface.

A node whose cone axis crosses the face has one nappe inside the box: one
fan of triangles, not two.  The count is checked against an independent
oracle (``oracles.branches_on_sphere`` on the part of a small sphere inside
the box), with float (15-digit) coefficients.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import singmesh
from meshcheck import boundary_edges_off_box, fans_at, non_manifold_edges
from oracles import branches_on_sphere

A = np.sqrt(2.5)

CASES = [
    # A cone x'^2 + y'^2 = z^2 with its apex on the face z = 0, off the lattice.
    ("cone", "(x - 0.300000000000001)^2 + (y - 0.412345678901234)^2 - z^2",
     lambda p: (p[..., 0] - 0.300000000000001) ** 2 + (p[..., 1] - 0.412345678901234) ** 2 - p[..., 2] ** 2,
     ((-1.0, 1.0), (-1.0, 1.0), (0.0, 1.0)), [(0.300000000000001, 0.412345678901234, 0.0)]),
    # Goursat's quartic with 12 nodes (two coordinates +-sqrt(5/2), one 0), the
    # half z >= 0 of its box: four nodes on the face, four inside.
    ("goursat", "x^4 + y^4 + z^4 - 5 (x^2 + y^2 + z^2) + 12.5",
     lambda p: (p ** 4).sum(axis=-1) - 5 * (p ** 2).sum(axis=-1) + 12.5,
     ((-3.0, 3.0), (-3.0, 3.0), (0.0, 3.0)),
     [(sx * A, sy * A, 0.0) for sx in (-1, 1) for sy in (-1, 1)]
     + [(s * A, 0.0, A) for s in (-1, 1)] + [(0.0, s * A, A) for s in (-1, 1)]),
]


@pytest.mark.parametrize("name,text,f,box,nodes", CASES, ids=[c[0] for c in CASES])
def test_nodes_on_a_box_face_have_the_fans_inside_the_box(name, text, f, box, nodes):
    with warnings.catch_warnings():
        warnings.simplefilter("error", singmesh.SingularPointWarning)
        m = singmesh.mesh(text, box)
    size = float(np.max(np.ptp(np.array(box), axis=1)))
    assert not boundary_edges_off_box(m.vertices, m.faces, box)
    assert not non_manifold_edges(m.faces)
    for p in np.array(nodes):
        d = np.linalg.norm(m.vertices - p, axis=1)
        i = int(np.argmin(d))
        assert d[i] <= 1e-9 * size, (p, d[i])
        want = branches_on_sphere(f, p, 0.05 * size, n_lat=360, n_lon=720, box=box)
        assert want == (1 if p[2] == 0.0 else 2)
        assert fans_at(m.faces, i) == want, p


def test_node_on_a_box_edge_is_one_vertex_with_closed_fans():
    box = ((0.0, 1.25),) * 3
    m = singmesh.mesh("36 x^2 + 36 y^2 - 48 (z - 0.5)^2", box)
    size = 1.25
    apex = np.array([0.0, 0.0, 0.5])
    d = np.linalg.norm(m.vertices - apex, axis=1)
    assert int((d <= 1e-9 * size).sum()) == 1
    assert not boundary_edges_off_box(m.vertices, m.faces, box)
    f = lambda p: 36 * p[..., 0] ** 2 + 36 * p[..., 1] ** 2 - 48 * (p[..., 2] - 0.5) ** 2  # noqa: E731
    assert fans_at(m.faces, int(np.argmin(d))) == branches_on_sphere(f, apex, 0.05, 360, 720, box=box) == 2


# The cone with its apex on a box edge, its axis along the edge, across it,
# and tilted: one vertex at the apex and the fans the sphere oracle counts.
EDGE_CONES = [
    "36 x^2 + 36 y^2 - 48 (z - 0.5)^2",
    "36 y^2 + 36 (z - 0.5)^2 - 48 x^2",
    "30 x^2 - 36 y^2 + 40 (z - 0.5)^2 + 12 x y",
    pytest.param("-36 x^2 - 36 y^2 + 48 (z - 0.5)^2 + 20 x (z - 0.5)", marks=pytest.mark.xfail(strict=True, reason=(
        "both nappes in the quadrant, F >= 0 along the box edge: no root event at the apex there, so "
        "the links on the faces x = 0 and y = 0 pass by the apex from one nappe to the other and the "
        "star has one cycle, one fan (the sphere counts 2)"))),
]


@pytest.mark.parametrize("text", EDGE_CONES)
def test_cones_with_the_apex_on_a_box_edge(text):
    import sympy

    from singmesh.surface import Surface, X, Y, Z

    box = ((0.0, 1.25),) * 3
    m = singmesh.mesh(text, box)
    f = sympy.lambdify((X, Y, Z), Surface.parse(text).expr, "numpy")
    apex = np.array([0.0, 0.0, 0.5])
    d = np.linalg.norm(m.vertices - apex, axis=1)
    assert int((d <= 1e-9 * 1.25).sum()) == 1
    assert not boundary_edges_off_box(m.vertices, m.faces, box)
    assert not non_manifold_edges(m.faces)
    want = branches_on_sphere(lambda p: f(p[..., 0], p[..., 1], p[..., 2]), apex, 0.05, 360, 720, box=box)
    assert want >= 1
    assert fans_at(m.faces, int(np.argmin(d))) == want


def test_chmutov_sextic_octant():
    # T6(x) + T6(y) + T6(z) + 1 on [0, 1.25]^3 (a user's octant of a symmetric
    # surface): three of its nodes lie on the box's edges, e.g. (0, 0, 1/2).
    import sympy

    from benchmarks.nodes import find_nodes
    from singmesh.surface import Surface, X, Y, Z

    t6 = "(32 {v}^6 - 48 {v}^4 + 18 {v}^2 - 1)"
    text = " + ".join(t6.format(v=v) for v in "xyz") + " + 1"
    box = ((0.0, 1.25),) * 3
    expr = Surface.parse(text).expr
    truth = find_nodes(expr, box, starts=12)
    on_edges = (np.abs(truth) <= 1e-12).sum(axis=1) >= 2
    assert on_edges.sum() == 3
    m = singmesh.mesh(text, box)
    f = sympy.lambdify((X, Y, Z), expr, "numpy")
    assert not boundary_edges_off_box(m.vertices, m.faces, box)
    assert not non_manifold_edges(m.faces)
    for p in truth:
        d = np.linalg.norm(m.vertices - p, axis=1)
        assert int((d <= 1e-9 * 1.25).sum()) == 1, p
        want = branches_on_sphere(lambda q: f(q[..., 0], q[..., 1], q[..., 2]), p, 0.02, 240, 480, box=box)
        assert fans_at(m.faces, int(np.argmin(d))) == want, p


def test_three_symmetric_candidates_give_no_cluster_warning():
    # (0, a, a), (a, 0, a), (a, a, 0) as a 3x3 array is symmetric with a
    # zero diagonal: scipy's linkage warned that the points look like a
    # distance matrix (seen by users of the Goursat quartic's octant).
    from singmesh.skeleton.singular import _dedupe

    a = 0.3
    x = np.array([[0.0, a, a], [a, 0.0, a], [a, a, 0.0]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        reps = _dedupe(x, 0.1)
    assert len(reps) == 3  # three points 0.42 apart: three clusters
