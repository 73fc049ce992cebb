"""Whole-mesh tests on smooth surfaces, checked independently of the mesher.

F is written here again as a numpy function (not taken from singmesh), and
the topology is counted by tests/meshcheck.py.
"""

import numpy as np
import pytest

import singmesh

import meshcheck as mc


def grad(f, p, h=1e-6):
    e = np.eye(3) * h
    return np.stack([(f(p + e[i]) - f(p - e[i])) / (2 * h) for i in range(3)], axis=-1)


def F(expr):
    return lambda p: eval(expr, {"x": p[..., 0], "y": p[..., 1], "z": p[..., 2], "np": np})


B2 = ((-2, 2),) * 3
CASES = [
    # name, equation, box, numpy F, Euler characteristic, components
    ("sphere", "x^2+y^2+z^2-1", B2, "x**2+y**2+z**2-1", 2, 1),
    ("torus", "(x^2+y^2+z^2+0.64-0.09)^2-2.56(x^2+y^2)", B2,
     "(x**2+y**2+z**2+0.64-0.09)**2-2.56*(x**2+y**2)", 0, 1),
    ("tanglecube", "x^4-5x^2+y^4-5y^2+z^4-5z^2+11.8", ((-3, 3),) * 3,
     "x**4-5*x**2+y**4-5*y**2+z**4-5*z**2+11.8", -8, 1),
    ("cube6", "x^6+y^6+z^6-1", B2, "x**6+y**6+z**6-1", 2, 1),
    ("two spheres", "((x-1)^2+y^2+z^2-0.5)((x+1)^2+y^2+z^2-0.5)", B2,
     "((x-1)**2+y**2+z**2-0.5)*((x+1)**2+y**2+z**2-0.5)", 4, 2),
    ("plane", "x+y+z", ((-1, 1),) * 3, "x+y+z", 1, 1),
]


@pytest.fixture(scope="module", params=CASES, ids=[c[0] for c in CASES])
def case(request):
    name, eq, box, f, chi, comps = request.param
    return singmesh.mesh(eq, box), np.array(box, float), F(f), chi, comps


def test_topology(case):
    m, box, f, chi, comps = case
    assert len(m.faces) > 100
    assert mc.euler(m.vertices, m.faces) == chi
    assert mc.components(m.faces) == comps


def test_no_defects(case):
    m, box, f, chi, comps = case
    assert mc.non_manifold_edges(m.faces) == []
    assert mc.boundary_edges_off_box(m.vertices, m.faces, box) == []
    assert mc.duplicate_vertices(m.vertices) == 0
    assert mc.degenerate_triangles(m.vertices, m.faces) == 0
    # Every vertex is used by a triangle.
    assert len(np.unique(m.faces)) == len(m.vertices)


def test_vertices_on_surface(case):
    m, box, f, chi, comps = case
    v = m.vertices
    d = np.abs(f(v)) / np.linalg.norm(grad(f, v), axis=1)
    assert d.max() <= 1e-10 * np.ptp(box, axis=1).max()


def test_orientation_follows_gradient(case):
    m, box, f, chi, comps = case
    p = m.vertices[m.faces]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    g = grad(f, p.mean(axis=1))
    assert (np.einsum("ij,ij->i", n, g) > 0).mean() == 1.0


def test_report_agrees_with_independent_counts(case):
    m, box, f, chi, comps = case
    r = m.report()
    assert r["euler_characteristic"] == mc.euler(m.vertices, m.faces)
    assert r["components"] == mc.components(m.faces)
    assert r["non_manifold_edges"] == len(mc.non_manifold_edges(m.faces))
    assert r["boundary_edges"] == len(mc.boundary_edges(m.faces))


def test_box_cuts_the_surface():
    # A sphere cut by the box: boundary only on the box faces, a disc per cap.
    box = ((-0.6, 2), (-2, 2), (-2, 2))
    m = singmesh.mesh("x^2+y^2+z^2-1", box)
    assert mc.boundary_edges(m.faces), "the cut must leave a boundary"
    assert mc.boundary_edges_off_box(m.vertices, m.faces, np.array(box)) == []
    assert mc.euler(m.vertices, m.faces) == 1
    assert mc.non_manifold_edges(m.faces) == []


@pytest.mark.parametrize("box", [((-1, 1),) * 3, ((-2, 2),) * 3, ((-1.5, 1.5),) * 3])
def test_symmetric_boxes_zeros_on_split_planes(box):
    # x^2+y^2+z^2 = 1 touches the split planes x, y, z = +-1 at lattice
    # points; the mesh must still be a clean sphere.
    m = singmesh.mesh("x^2+y^2+z^2-1", box, coarse=16)
    assert mc.euler(m.vertices, m.faces) == 2
    assert mc.non_manifold_edges(m.faces) == []
    assert mc.boundary_edges(m.faces) == []
    assert mc.duplicate_vertices(m.vertices) == 0
    assert mc.degenerate_triangles(m.vertices, m.faces) == 0


def test_surface_containing_split_planes():
    # xy(x+y+z-0.3)... keep it smooth: the plane z = 0 itself, exactly a split plane.
    m = singmesh.mesh("z", ((-1, 1),) * 3, coarse=8)
    assert mc.euler(m.vertices, m.faces) == 1
    assert np.abs(m.vertices[:, 2]).max() == 0
    assert mc.non_manifold_edges(m.faces) == []
    assert mc.duplicate_vertices(m.vertices) == 0
    assert np.isclose(np.sum(0.5 * np.linalg.norm(np.cross(
        m.vertices[m.faces[:, 1]] - m.vertices[m.faces[:, 0]],
        m.vertices[m.faces[:, 2]] - m.vertices[m.faces[:, 0]]), axis=1)), 4.0)


@pytest.mark.parametrize("offset", ["0.00000125", "0.0000015525", "0.0000018", "0.0000025"])
def test_sheet_grazing_a_lattice_point_leaves_no_zero_area_triangle(offset):
    # A sphere of radius ~1 passing 1e-7 to 4e-7 of the box from the lattice
    # point at the origin, cutting the three axes at different distances:
    # the roots on the three lattice lines through the point span a
    # triangle of about 1e-14 of the box squared unless they share a vertex.
    text = f"6.75 x + 6.21 y + 5.75 z + 0.5 (x^2+y^2+z^2) - {offset}"
    box = ((-1, 1),) * 3
    m = singmesh.mesh(text, box)
    assert mc.tiny_triangles(m.vertices, m.faces, box) == 0
    assert mc.close_vertex_pairs(m.vertices, box) == 0
    assert mc.boundary_edges_off_box(m.vertices, m.faces, box) == []
    assert mc.non_manifold_edges(m.faces) == []
    f = F(f"6.75*x + 6.21*y + 5.75*z + 0.5*(x**2+y**2+z**2) - {offset}")
    assert np.abs(f(m.vertices)).max() < 1e-9   # |grad F| is about 11 here


def test_deterministic():
    a = singmesh.mesh("x^4-5x^2+y^4-5y^2+z^4-5z^2+11.8", ((-3, 3),) * 3, coarse=16)
    b = singmesh.mesh("x^4-5x^2+y^4-5y^2+z^4-5z^2+11.8", ((-3, 3),) * 3, coarse=16)
    assert np.array_equal(a.vertices, b.vertices) and np.array_equal(a.faces, b.faces)


@pytest.mark.parametrize("coarse", [8, 16, 64])
def test_resolutions(coarse):
    m = singmesh.mesh("(x^2+y^2+z^2+0.64-0.09)^2-2.56(x^2+y^2)", coarse=coarse, fine=max(coarse, 128))
    assert mc.euler(m.vertices, m.faces) == 0
    assert mc.non_manifold_edges(m.faces) == []
    assert mc.boundary_edges(m.faces) == []


@pytest.mark.parametrize("kwargs, words", [
    (dict(box=((1, 0), (0, 1), (0, 1))), "inverted"),
    (dict(box=((0, 0), (0, 1), (0, 1))), "empty"),
    (dict(box=((0, 1), (0, 1))), "three"),
    (dict(box=((0, np.inf), (0, 1), (0, 1))), "non-finite"),
    (dict(coarse=12), "power of two"),
    (dict(coarse=64, fine=32), "at least"),
])
def test_bad_arguments(kwargs, words):
    with pytest.raises(singmesh.SurfaceError, match=words):
        singmesh.mesh("x^2+y^2+z^2-1", **kwargs)


@pytest.mark.parametrize("suffix", [".obj", ".ply", ".stl", ".vtk", ".vtu", ".off"])
def test_write_round_trip(tmp_path, suffix):
    import meshio

    m = singmesh.mesh("x^2+y^2+z^2-1", coarse=8)
    path = m.write(tmp_path / f"sphere{suffix}")
    back = meshio.read(path)
    assert len(back.points) == len(m.vertices)
    tri = [c.data for c in back.cells if c.type == "triangle"]
    assert sum(len(t) for t in tri) == len(m.faces)
    # Formats may reorder points (STL) and store float32: match point sets.
    from scipy.spatial import cKDTree

    assert cKDTree(m.vertices).query(back.points)[0].max() < 1e-6
    assert cKDTree(back.points).query(m.vertices)[0].max() < 1e-6


def test_write_unknown_format(tmp_path):
    m = singmesh.mesh("x^2+y^2+z^2-1", coarse=8)
    with pytest.raises(ValueError, match="unknown mesh format"):
        m.write(tmp_path / "a.xyz")


def test_box_graph_is_a_union_of_cycles():
    # The networkx graph of a box's links: every crossing has one link in
    # and one out, and its cycles are the facets the mesher triangulated.
    import networkx as nx

    from singmesh.boxes.edges import compute_events
    from singmesh.boxes.faces import face_links
    from singmesh.boxes.octree import subdivide
    from singmesh.facets.cycles import box_graph, box_links, find_cycles

    s = singmesh.Surface.parse("(x^2+y^2+z^2+0.64-0.09)^2-2.56(x^2+y^2)")
    tree = subdivide(s, np.array(B2, float), 3, 6)
    events = compute_events(s, tree)
    links = box_links(face_links(s, tree, events))
    cycles = find_cycles(*links, n_events=len(events.key))
    for box in np.unique(links[0])[:50]:
        g = box_graph(links, int(box))
        assert all(d == 1 for _, d in g.in_degree()) and all(d == 1 for _, d in g.out_degree())
        expected = sorted(sorted(cycles.events[cycles.offsets[c]:cycles.offsets[c + 1]].tolist())
                          for c in np.nonzero(cycles.box == box)[0])
        assert sorted(sorted(c) for c in nx.simple_cycles(g)) == expected


@pytest.mark.parametrize("few, dense", [(16, 1 << 22), (2, 1 << 22), (0, 0)])
def test_events_on_segments_by_brute_force(monkeypatch, few, dense):
    # Every event of every lattice segment of the leaves, and no other:
    # checked against each event's own line and position (floor of its
    # place along the line, a snapped one a thousandth to its side), on
    # the stacked look-up, on the binary-search one (few = 0, dense = 0) and
    # on both at once (few = 2: lines with more events by binary search).
    import singmesh.boxes.edges as edges
    from singmesh.boxes.octree import subdivide

    monkeypatch.setattr(edges, "_FEW_EVENTS", few)
    monkeypatch.setattr(edges, "_DENSE_LINES", dense)
    s = singmesh.Surface.parse("x^4 - 5 x^2 + y^4 - 5 y^2 + z^4 - 5 z^2 + 11.8")
    tree = subdivide(s, np.array([[-3, 3]] * 3, float), 3, 5)
    events = edges.compute_events(s, tree)
    seg = edges.leaf_edges(tree)
    seg = np.concatenate([seg, [[0, 5, 7, 3, 9], [2, 40, 40, 0, 32]]])  # one more, and one off the lattice
    got_seg, got_ev = events.on_segments(seg[:, 0], seg[:, 1], seg[:, 2], seg[:, 3], seg[:, 4])
    got = set(zip(got_seg.tolist(), got_ev.tolist()))
    cell = np.floor(events.pos + np.where(events.snapped, 1e-3 * events.side, 0.0)).astype(np.int64)
    line = events.lines[events.line]
    by_line = {}
    for e, row in enumerate(line.tolist()):
        by_line.setdefault(tuple(row), []).append(e)
    cell = cell.tolist()
    expected = {(k, e) for k, (a, u, v, lo, hi) in enumerate(seg.tolist())
                for e in by_line.get((a, u, v), ()) if lo <= cell[e] < hi}
    assert len(events.key) > 100 and len(got) > len(events.key) and got == expected
