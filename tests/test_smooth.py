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


#: Smooth surfaces containing a line that is a lattice line (on the split
#: planes of the box, or in a face or on an edge of the box), where the
#: octree is finer on one side of the line than on the other: the coarse
#: box's facet carries the finer boxes' vertices on the line (fuzz s4-36:
#: the y-axis and the line x = 0, y = 1/4 lie on the quadric, crossing at a
#: lattice point where its tangent plane is the split plane x = 0).
#: name, equation, box, numpy F (written apart), whether the line is inside
#: the box (then chi and components are those of marching cubes).
QUADRIC_Y_AXIS = "-4*y*z + 3*x*z - 0.2*x*y + z"
LATTICE_LINES = [
    ("s4-36", "-4*y*z + 3*x*z - 1/5*x*y + 1*z", ((-0.5, 0.5), (-1, 1), (-1.5, 1.5)), QUADRIC_Y_AXIS, True),
    ("axes permuted", "-4*x*y + 3*z*y - 1/5*z*x + 1*y", ((-1, 1), (-1.5, 1.5), (-0.5, 0.5)),
     "-4*x*y + 3*z*y - 0.2*z*x + y", True),
    ("cubic terms", "-4*y*z + 3*x*z - 1/5*x*y + z + 2*x*z^2 - x^2*y", ((-0.5, 0.5), (-1, 1), (-1.5, 1.5)),
     QUADRIC_Y_AXIS + " + 2*x*z**2 - x**2*y", True),
    # Moved by (0.1, 0.2, 0.3), box and all: decimal coefficients, a box
    # whose lattice points are the line's only to rounding.
    ("shifted", "-0.2*x*y + 3*x*z - 0.86*x - 4*y*z + 1.22*y + 1.5*z - 0.454",
     ((-0.4, 0.6), (-0.8, 1.2), (-1.2, 1.8)),
     "-4*(y-0.2)*(z-0.3) + 3*(x-0.1)*(z-0.3) - 0.2*(x-0.1)*(y-0.2) + (z-0.3)", True),
    ("shifted by 1/4", "-0.2*x*y + 3*x*z - 0.2125*x - 4*y*z + 0.3*y - 0.25*z + 0.021875",
     ((-0.25, 0.75), (-1.125, 0.875), (-1.4375, 1.5625)),
     "-4*(y+0.125)*(z-0.0625) + 3*(x-0.25)*(z-0.0625) - 0.2*(x-0.25)*(y+0.125) + (z-0.0625)", True),
    # 15-digit coefficients (c, 4c, 3c, c / 5 of c = 0.123456789012345; clean on main too).
    ("15 digits", "-0.49382715604938*y*z + 0.370370367037035*x*z - 0.024691357802469*x*y + 0.123456789012345*z",
     ((-0.5, 0.5), (-1, 1), (-1.5, 1.5)), f"0.123456789012345*({QUADRIC_Y_AXIS})", True),
    # The two lines in the face x = 0 of the box (a crack in that face on main).
    ("in a face", "-4*y*z + 3*x*z - 1/5*x*y + 1*z", ((0, 0.5), (-1, 1), (-1.5, 1.5)), QUADRIC_Y_AXIS, False),
    ("on an edge", "-4*y*z + 3*x*z - 1/5*x*y + 1*z", ((0, 0.5), (-1, 1), (-1.5, 0)), QUADRIC_Y_AXIS, False),
]


def _marching_cubes_topology(f, box, n=128):
    """(chi, components) of the marching-cubes mesh of ``f`` on a grid shifted off every split plane."""
    from skimage.measure import marching_cubes

    h = (box[:, 1] - box[:, 0]) / n
    axes = [np.linspace(b[0] + 0.37 * s, b[1] - 0.63 * s, n) for b, s in zip(box, h)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)
    v, t = marching_cubes(f(grid), 0.0, spacing=tuple(h))[:2]
    return mc.euler(v, t), mc.components(t)


@pytest.mark.parametrize("coarse, fine", [(8, 64), (16, 128)])
@pytest.mark.parametrize("name, text, box, expr, inside", LATTICE_LINES, ids=[c[0] for c in LATTICE_LINES])
def test_line_of_the_surface_on_a_lattice_line_beside_finer_boxes(name, text, box, expr, inside, coarse, fine):
    box = np.array(box, float)
    f = F(expr)
    m = singmesh.mesh(text, box, coarse=coarse, fine=fine)
    assert len(m.faces) > 100
    assert mc.non_manifold_edges(m.faces) == []
    assert mc.boundary_edges_off_box(m.vertices, m.faces, box) == []
    # No crack along the line, in the box or in its faces: no boundary edge
    # with a vertex of the mesh inside it.
    assert mc.boundary_t_junctions(m.vertices, m.faces) == 0
    assert mc.degenerate_triangles(m.vertices, m.faces) == 0
    v = m.vertices
    d = np.abs(f(v)) / np.linalg.norm(grad(f, v), axis=1)
    assert d.max() <= 1e-10 * np.ptp(box, axis=1).max()
    if inside:
        pytest.importorskip("skimage")
        assert (mc.euler(m.vertices, m.faces), mc.components(m.faces)) == _marching_cubes_topology(f, box)
