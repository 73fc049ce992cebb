"""Classical surfaces with singular curves under float rotations: the cases that once failed.

Each case is checked by ``test_curves.check_curve_mesh`` (independent of
the mesher: Gauss-Newton samples of the singular locus, edge counts, open
edges, pieces, vertices on the surface, a marching-cubes sample), on
copies rotated and shifted with 15-digit coefficients
(``test_curves.float_rotated``, numpy QR rotations from the seed given).
"""

from __future__ import annotations

import numpy as np
import pytest

import meshcheck as mc
from singmesh.facets.triangulate import triangulate_polygons
from singmesh.skeleton.singular_curves import singular_curves
from singmesh.surface import Surface
from test_curves import BOX1, check_curve_mesh, float_rotated, lambdas, mesh_quiet, segment_distance, singular_locus
from test_rounded import float_rotated as rounded_float_rotated

ROMAN = "x^2 y^2 + y^2 z^2 + z^2 x^2 - x y z"


def test_two_facets_do_not_share_a_diagonal():
    # The surface pierces a face of the octree in two arcs, one piece on
    # each side (a tube, near the cross-cap's pinch points): both pieces
    # are quadrilaterals u-p-w-q whose short diagonal u-w is the same
    # segment.  Both taking it pinches the tube into an edge of four
    # triangles off any singular curve; every edge must have at most two.
    u, w = np.array([0.0, 0, 0]), np.array([1.0, 0, 0])
    p1, q1 = np.array([0.5, 1.0, 0.2]), np.array([0.5, -1.0, 0.2])
    p2, q2 = np.array([0.5, 1.0, -0.2]), np.array([0.5, -1.0, -0.2])
    points = np.stack([u, w, p1, q1, p2, q2])
    # u-p1-w-q1 runs clockwise seen from +z: its normal is -z; the other
    # piece, u-q2-w-p2, faces the other way.
    normals = np.array([[0, 0, 0], [0, 0, 0], [0, 0, -1], [0, 0, -1], [0, 0, 1], [0, 0, 1]], float)
    polygons = (np.array([0, 4, 8]), np.array([0, 2, 1, 3, 0, 5, 1, 4]))
    faces, _, _ = triangulate_polygons(polygons, points, normals)
    assert len(faces) == 4
    assert max(mc.edge_counts(faces).values()) <= 2
    # ... and each piece is still a triangulation of its own quadrilateral.
    assert {frozenset(f) for f in faces[:2].tolist()} <= {frozenset(s) for s in ([0, 2, 3], [2, 1, 3], [0, 2, 1],
                                                                               [0, 1, 3])}


def test_roman_surface_tube_meets_itself_only_across_faces():
    # Seed 112 at fine 128: two leaves of the tube round the double lines
    # shared only a lattice edge, with an event on it; both rails through
    # it were zipped to the same curve vertex (an edge of four triangles
    # ten cells off the curve).
    check_curve_mesh(float_rotated(ROMAN, 112), BOX1, 1, fine=128)


SWALLOWTAIL = "16 x^4 z - 4 x^3 y^2 - 128 x^2 z^2 + 144 x y^2 z - 27 y^4 + 256 z^3"


def test_swallowtail_curve_vertices_on_the_curve():
    # The discriminant of t^4 + x t^2 + y t + z: a double curve turning
    # into an isolated line at the swallowtail point, where two cuspidal
    # edges start.  F and grad F vanish to high order there, so next to it
    # they stay below 1e-8 along a valley off the curve (z = x^2 / 12 on
    # y = 0, the isolated line being z = x^2 / 4): traced vertices and the
    # type changes placed there were off the surface.
    check_curve_mesh(float_rotated(SWALLOWTAIL, 40), BOX1, 1)


CRIXXI = "(y^2 + z^2 - 1)^2 + (x^2 + y^2 - 1)^3"


@pytest.mark.parametrize("seed", [4, 8])
def test_rotated_crixxi_is_cuspidal_edges_crossing_twice(seed):
    # Crixxi's singular curve is where the cylinders y^2 + z^2 = 1 and
    # x^2 + y^2 = 1 meet: two ellipses (z = +-x), cuspidal edges all along
    # (F = G^2 + H^3), crossing at (0, +-1, 0).  Rotated, vertices Newton
    # leaves a little off a cuspidal edge (linear convergence) read a
    # Hessian of rank two: pieces of "double curve" or "isolated line"
    # between changes of type that are not there (seed 4); a trace held to
    # a curve vertex's residual stopped short of it there and was lost
    # (seed 8: ends of the trace in mid-curve).
    text = float_rotated(CRIXXI, seed)
    box = np.array([[-1.6, 1.6]] * 3)
    curves = singular_curves(Surface.parse(text), box, step=3.2 / 256)
    assert {c.type for c in curves.pieces} == {"A2 cuspidal edge"}
    kinds = sorted(sp.kind for sp in curves.special if sp.kind != "end on the box")
    assert kinds == ["crossing of cuspidal edges"] * 2
    # ... where the rotation puts (0, +-1, 0) (as float_rotated draws it).
    rng = np.random.default_rng(seed)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    shift = rng.uniform(-0.3, 0.3, 3)
    want = np.array([[0, 1.0, 0], [0, -1.0, 0]]) @ q + shift
    got = np.array([sp.point for sp in curves.special if sp.kind == "crossing of cuspidal edges"])
    d = np.linalg.norm(got[:, None] - want[None], axis=2)
    assert d.min(axis=1).max() <= 0.25 * 3.2 / 256 and len(set(d.argmin(axis=1).tolist())) == 2


CROSSCAP = "4 x^2 (x^2 + y^2 + z^2 + z) + y^2 (y^2 + z^2 - 1)"


def test_crosscap_sheets_near_a_pinch_point_stay_apart():
    # Seed 4: 13.5 cells from a pinch point the two sheets are still a
    # cell apart, round a lattice node between them; non-simple leaves
    # there, outside the tube's ball, paired one sheet's events with the
    # other's: a closed bubble of 8 triangles (two pieces).
    check_curve_mesh(float_rotated(CROSSCAP, 4), ((-1.2, 1.2),) * 3, 1, coarse=16)


def test_two_cylinders_sheets_near_a_tangential_crossing_stay_apart():
    # Seed 11: where the double curves cross the cylinders are tangent;
    # 14 cells out a lattice edge still meets both within one cell, and
    # the leaves round it (non-simple, outside the ball) joined its two
    # events by an edge of four triangles.
    check_curve_mesh(float_rotated("(x^2 + y^2 - 1)(x^2 + z^2 - 1)", 11), ((-1.5, 1.5),) * 3, 1, coarse=16)


def test_cuspidal_edge_with_degenerating_cusp_has_no_bubbles():
    # x^2 = y^2 z^3: along the y-axis a cuspidal edge x^2 = c z^3 whose
    # coefficient c = y^2 goes to 0 at the crossing of curves (the origin).
    # Where c is small the two half-sheets stay within a cell of each other
    # 20 cells out: the usual tube ended where they were not yet apart, and
    # each stretch of the thin wedge outside it closed on a strip to the
    # curve (closed bubbles of 8 to 24 triangles, 2 pieces; x^2 = y^3 z^3
    # had 34).  The piece's median measure (6 cells) hid it: the tube is
    # wide wherever the half-sheets need it.
    check_curve_mesh(float_rotated("x^2 - y^2 z^3", 5), BOX1, 1)


TUELLE = "y z (x^2 + y - z)"


def test_tuelle_curves_tangent_at_their_triple_point_are_followed_once():
    # The x-axis and the parabolas z = x^2 (y = 0) and y = -x^2 (z = 0)
    # meet tangentially at the origin: for about ten steps each way they
    # are closer than a step.  Seed 18: merging crossings there left two
    # paths between the same two crossings, one on the line and one on a
    # parabola 0.8 steps beside it; the strips zipped to both (edges of
    # three triangles).
    check_curve_mesh(float_rotated(TUELLE, 18), BOX1, 1)


def test_roman_surface_rails_zip_each_curve_edge_once_per_half_sheet():
    # Seed 11: round the balls at the triple and pinch points the tube's
    # wall is not straight, and rails ran back along a double line and
    # forward again: the strips zipped the same curve edges twice from one
    # side (four edges of 8 triangles).  At most three sheets pass through
    # any point of the Roman surface, so no edge has more than 6.  (The
    # rest of check_curve_mesh runs on this copy in
    # test_curves.test_float_rotated_and_shifted.)
    m = mesh_quiet(float_rotated(ROMAN, 11), BOX1)
    counts = mc.edge_counts(m.faces)
    assert max(counts.values()) <= 6, sorted(counts.values())[-6:]
    assert all(n % 2 == 0 for n in counts.values() if n > 2)


@pytest.mark.parametrize("degrees, seed", [(7, 3), (5, 2), (8, 4), (4, 17)])
def test_planes_crossing_at_a_small_angle(degrees, seed):
    # Two sheets crossing at a few degrees are less than a cell apart for
    # many cells along the bisector (2 r tan(angle / 2) at r): a tube of
    # the usual width left them in one leaf, and strips jumped between
    # them (27 curve edges with other than 4 triangles at 7 degrees, 19
    # pieces at 5).  With the wide tube reaching a face of the box near
    # the curve's end (seeds 4 and 17), a half-sheet's trace on the tube
    # ran along the face and came back as a stub of a few links, whose
    # two ends were both fanned to the curve's end: a strip made twice
    # (edges of 6 triangles) or with a gap (open edges).
    s = np.tan(np.radians(degrees))
    check_curve_mesh(float_rotated(f"z (z - {s:.15g} x)", seed), BOX1, 1, half_sheets=4)


@pytest.mark.parametrize("degrees, seed", [(6, 4), (5, 4)])
def test_planes_at_a_small_angle_stubs_on_a_face_zip_once(degrees, seed):
    # Where the wide tube meets the face y = -1 (or y = 1) near the curve's
    # end, each sheet's trace on the tube's side leaves stubs of a few
    # links along the face.  At 6 degrees one stub's ends were 3.2 cells
    # apart (16 curve edges with 6 triangles: its two ends both fanned to
    # the curve's end); at 5 degrees the two sheets' stubs interleave along
    # the face and one was joined to the other sheet's rail (45 edges).
    s = np.tan(np.radians(degrees))
    m, _ = check_curve_mesh(float_rotated(f"z (z - {s:.15g} x)", seed), BOX1, 1, half_sheets=4)
    assert _every_curve_edge_has(m, 4) == []


def test_large_sphere_cut_by_a_plane_at_a_small_angle():
    # A sphere of radius 6 meets z = 0 at 7 degrees along a circle of
    # radius 0.73: the cap between them is 5 cells high at the default
    # fine level.
    t = np.radians(7.0)
    text = float_rotated(f"(x^2 + y^2 + (z + {6 * np.cos(t):.15g})^2 - 36) z", 5)
    check_curve_mesh(text, BOX1, 1, half_sheets=4)


def test_wide_cylinder_cut_by_a_plane_at_a_small_angle():
    # A cylinder of radius 4 (axis x = -4 cos 6deg, y = 0) cut by the plane
    # x = 0 along the lines y = +-4 sin 6deg = +-0.418, the sheets at 6
    # degrees (float rotation, seed 3); both lines run from face to face
    # of the box, where the wide tubes meet it.  On main: edges of more
    # than two triangles off the curve.
    t = np.radians(6.0)
    text = float_rotated(f"((x + {4 * np.cos(t):.15g})^2 + y^2 - 16) x", 3)
    m, _ = check_curve_mesh(text, BOX1, 1, half_sheets=4)
    assert _every_curve_edge_has(m, 4) == []


@pytest.mark.parametrize("box", [BOX1, ((-1.03, 0.97), (-0.98, 1.01), (-1.011, 0.993))])
def test_plane_tangent_to_a_hyperboloid_along_two_lines(box):
    # The tangent plane of a hyperboloid of one sheet at (1/2, 1/2, -1/2)
    # cuts it in the two rulings through the point; the angle between the
    # sheets grows from 0 at the point along each line.  The point is on
    # split planes of the first box (10 open edges there, around it), in
    # general position in the second (a piece cut off, 19 curve edges
    # with other than 4 triangles).
    check_curve_mesh("(x + y + z - 1/2) (x^2 + y^2 - z^2 - 1/4)", box, 1)


def _rotated_circle(seed: int, radius: float, height: float) -> np.ndarray:
    """The circle x^2 + y^2 = radius^2, z = height, moved as ``float_rotated(text, seed)`` moves the surface.

    ``float_rotated`` composes F with u = Q (p - shift) (test_rounded: the
    same generator draws Q, then the shift), so a point u of the circle
    is at p = Q^T u + shift.
    """
    rng = np.random.default_rng(seed)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    shift = rng.uniform(-0.3, 0.3, 3)
    t = np.linspace(0.0, 2.0 * np.pi, 4000)
    u = np.stack([radius * np.cos(t), radius * np.sin(t), np.full_like(t, height)], axis=1)
    return u @ q + shift


def _every_curve_edge_has(m, n: int) -> list[int]:
    """The triangle counts of the mesh's curve edges that are not ``n``."""
    counts = mc.edge_counts(m.faces)
    return [counts.get((min(a, b), max(a, b)), 0) for c in m.singular_curves
            for a, b in zip(c.vertices[:-1], c.vertices[1:]) if counts.get((min(a, b), max(a, b)), 0) != n]


def test_sphere_times_thin_cylinder_arc_from_a_face_back_to_it():
    # A sphere times a cylinder of radius 1/4 through it: two double
    # circles at z = +-sqrt(15)/4, the sheets at 75.5 degrees (float
    # rotation, seed 5).  The box is a slab 0.6 thick across the top
    # circle, its face 3.5 of its (thin) cells inside the circle's top:
    # the double curve is an arc from that face back to it, a few cells
    # deep, the half-sheet of the cylinder between the arc and the face
    # all inside the tube (the class of fuzz s1-374).
    text = float_rotated("(x^2 + y^2 + z^2 - 1) (x^2 + y^2 - 1/16)", 5)
    circle = _rotated_circle(5, 0.25, np.sqrt(15.0) / 4.0)
    # The circle is the rotated surface's double curve: F = grad F = 0 (sympy).
    assert np.abs(lambdas(text)[2](circle)).max() <= 1e-9
    top = circle[:, 0].max()
    box = ((top - 0.6, top - 3.5 * 0.6 / 64), (-1.16, 1.34), (-1.41, 1.09))
    m, _ = check_curve_mesh(text, box, 1, half_sheets=4)
    assert _every_curve_edge_has(m, 4) == []


def test_cone_times_sphere_circle_along_an_edge_of_the_box():
    # A cone times the unit sphere: double circles of radius 1/sqrt(2) at
    # z = +-1/sqrt(2), the sheets at right angles (float rotation, seed 6).
    # The box's edge along y runs beside the upper circle where it is
    # nearly parallel to that edge, 3 cells inside the face x = x0 and 6
    # inside z = z1: the circle crosses the box's corner over many cells
    # within the tube's reach of both faces (the class of fuzz s1-462).
    s = 1.0 / np.sqrt(2.0)
    text = float_rotated("(x^2 + y^2 - z^2) (x^2 + y^2 + z^2 - 1)", 6)
    circle = _rotated_circle(6, s, s)
    assert np.abs(lambdas(text)[2](circle)).max() <= 1e-9
    tangent = np.gradient(circle, axis=0)
    tangent /= np.linalg.norm(tangent, axis=1)[:, None]
    p = circle[np.argmax(tangent @ np.array([0.25, 0.75, 0.25]))]
    cell = 2.5 / 64
    box = ((p[0] - 3 * cell, p[0] - 3 * cell + 2.5), (p[1] - 1.25, p[1] + 1.25), (p[2] + 6 * cell - 2.5, p[2] + 6 * cell))
    m, _ = check_curve_mesh(text, box, 1, half_sheets=4)
    assert _every_curve_edge_has(m, 4) == []


@pytest.mark.parametrize("cells, seed", [(13, 0), (13, 1), (12, 0), (12, 1), (11, 0), (11, 2)])
def test_plane_cutting_a_thin_cylinder_in_two_close_lines(cells, seed):
    # The plane z = r/2 cuts the cylinder x^2 + z^2 = r^2 along the lines
    # x = +-r sin 60deg, 13 fine cells apart at coarse 8 / fine 64 (float
    # rotation and shift); the sheets cross at 60 degrees.  The two tubes'
    # walls nearly touch between the lines, and a rail along one line came
    # nearer the other for an event or two: its strip stepped from one
    # line to the other, a triangle across the gap (the class of fuzz
    # s1-614 and s1-302).  On main: 16 and 6 open edges inside the box.
    # At 12 and 11 cells the tubes merged (the half-sheets between the
    # lines had no rail: triangles from one line to the other, open edges
    # inside the box); the fine level is doubled for curves closer than
    # CREASE_MIN_GAP cells now (api._fine_for_curves), where that parts them.
    r = cells / 32.0 / np.sqrt(3.0)
    text = float_rotated(f"(z - {r / 2:.15g}) (x^2 + z^2 - {r * r:.15g})", seed)
    m, _ = check_curve_mesh(text, BOX1, 1, half_sheets=4, coarse=8, fine=64)
    assert _every_curve_edge_has(m, 4) == []


def test_sphere_and_plane_circle_leaving_a_face_at_a_small_angle():
    # The unit sphere times the plane z = 0 (float rotation, seed 1): the
    # double circle, cut by the face x = x1 0.003 inside its farthest point,
    # leaves the box at 4.4 degrees to the face.  The trace's last chord
    # runs nearly along the face, and the rounds of Newton and slides onto
    # the face wandered along it: the curve's end was placed off the
    # curve, its edges of 4 triangles not between singular vertices (the
    # class of fuzz s1-394; skeleton/singular_curves.py _bisect_exit).
    text = float_rotated("(x^2 + y^2 + z^2 - 1) z", 1)
    circle = _rotated_circle(1, 1.0, 0.0)
    assert np.abs(lambdas(text)[2](circle)).max() <= 1e-9
    p = circle[np.argmax(circle[:, 0])]
    box = ((p[0] - 1.6, p[0] - 0.003), (p[1] - 1.03, p[1] + 0.97), (p[2] - 0.98, p[2] + 1.02))
    check_curve_mesh(text, box, 1, half_sheets=4, coarse=8, fine=64)


TOBEL = "x^3 z + x^2 + y z^3 + z^4 - 3 x y z"   # Hauser's Tobel


def test_tobel_sheets_touching_on_a_double_line_are_not_bridged():
    # The y-axis is a double line: across it x^2 - 3 y x z + ..., two
    # sheets for y != 0, which touch at the origin (x^2 + z^4 there) and
    # part on both sides with the same type.  No change of type was seen
    # and the tube was not widened there: an edge of four triangles off
    # the curve joined the two sheets 3 cells from it.
    check_curve_mesh(TOBEL, ((-1.5, 1.5),) * 3, None)


@pytest.mark.parametrize("seed", [3, 11, 30])
def test_tobel_tangency_of_sheets_is_a_special_point_under_float_rotation(seed):
    # The same point in general position (15-digit float rotation and
    # shift): a special point of the curve, where the typed surface's
    # origin went (the normal Hessian diag(2, 0) there: rank one), and
    # the line cut there into two double curves.
    text, shift = rounded_float_rotated(TOBEL, seed)
    m = mesh_quiet(text, ((-1.5, 1.5),) * 3)
    near = [sp for sp in m.special_points if np.linalg.norm(sp.point - shift) <= 1e-4]
    assert [sp.kind for sp in near] == ["change of type"]
    assert sorted(c.type for c in m.singular_curves) == ["A1 double curve"] * 2
    # ... and no edge of more than two triangles off the curve.
    mm = m.to_meshio()
    V = np.asarray(mm.points, float)
    T = np.concatenate([c.data for c in mm.cells if c.type == "triangle"])
    counts = mc.edge_counts(T)
    edges = np.array([e for e, n in counts.items() if n > 2], np.int64).reshape(-1, 2)
    _, G, _, _ = lambdas(text)
    g = np.linalg.norm(G(V), axis=1)
    singular = g <= 1e-6 * float(np.median(g[g > 0]))
    assert singular[edges].all()


SPITZ = "(y^3 - x^2 - z^2)^3 - 27 x^2 y^3 z^2"   # Hauser's Spitz


def test_spitz_cuspidal_edge_in_a_coordinate_plane_is_traced_to_the_box():
    # Spitz's singular locus holds the cusp x^2 = y^3 in the plane z = 0
    # (sympy: y^2 (x^2 +- 3 x z - y^3 + z^2) in its Groebner basis).
    # Newton left z at ~1e-57 instead of 0 there; every term of F_z has a
    # factor z, so F_z over its terms was 1 and each trace step was
    # refused as "off the curve": the branch x < 0 ended 0.33 short of the
    # box ("end of the trace"), an open edge in the mesh.
    curves = singular_curves(Surface.parse(SPITZ), ((-2.0, 2.0),) * 3, step=4.0 / 128)
    kinds = [sp.kind for sp in curves.special]
    assert "end of the trace" not in kinds
    ends = np.array([sp.point for sp in curves.special if sp.kind == "end on the box"])
    y = 4.0 ** (1.0 / 3.0)   # x^2 = y^3 at x = +-2, and z^2 = y^3 at z = +-2
    for p in ([-2.0, y, 0.0], [2.0, y, 0.0], [0.0, y, -2.0], [0.0, y, 2.0]):
        # (an end on a cuspidal edge: a multiple root across it, placed to ~1e-9)
        assert np.linalg.norm(ends - np.array(p), axis=1).min() <= 1e-7


def test_curve_vertex_a_hair_off_a_coordinate_plane_is_at_rounding_level():
    # A trace step's vertex on Spitz's cusp x^2 = y^3, z = 0, as Newton
    # left it (z = 8.5e-57): F and grad F at rounding level, measured
    # against the terms of F and F_i and what rounding the point moves
    # them by; F_z's terms alone (each with a factor z) made it 1.
    from singmesh.skeleton.singular import accept_residual
    from singmesh.skeleton.singular_curves import _local_residual

    surface = Surface.parse(SPITZ)
    for z in (0.0, 8.467410322771511e-57, 1e-30):
        x = np.array([[-1.589629021049267, 1.362062975441674, z]])
        # F ~ (y^3 - x^2)^3 across the cusp: rounding level up to |y^3 - x^2| ~ eps^(1/3).
        assert abs(x[0, 0] ** 2 - x[0, 1] ** 3) <= 1e-6
        assert _local_residual(surface, x, True)[0] <= accept_residual(surface), z


def test_seepferdchen_closes_round_the_cusp_of_its_cuspidal_edge():
    # Hauser's Seepferdchen: the cuspidal edge z = 0, x^2 = y^3 has a cusp
    # of its own at the origin.  In [-0.9, 0.9]^3 one open edge,
    # (-0.0106, 0.0481, 0) - (-0.0046, 0.0278, 0), was left beside it
    # (an xfail until trace9's tracing: steps along the Hessian's kernel,
    # joins and crossings checked).
    box = ((-0.9, 0.9),) * 3
    m = mesh_quiet("(x^2 - y^3)^2 - (x + y^2) z^3", box)
    mm = m.to_meshio()
    V = np.asarray(mm.points, float)
    T = np.concatenate([c.data for c in mm.cells if c.type == "triangle"])
    assert mc.boundary_edges_off_box(V, T, box) == []


@pytest.mark.xfail(strict=True, reason="issue #9: a hole of 4 open edges 5 cells from Spitz's triple point (where its "
                                       "cuspidal edges and isolated lines meet) under the float rotation of seed 30; "
                                       "not fixed (on main too)")
def test_rotated_spitz_closes_near_its_triple_point():
    box = ((-1.5, 1.5),) * 3
    m = mesh_quiet(float_rotated(SPITZ, 30), box)
    mm = m.to_meshio()
    V = np.asarray(mm.points, float)
    T = np.concatenate([c.data for c in mm.cells if c.type == "triangle"])
    assert mc.boundary_edges_off_box(V, T, box) == []


#: A sphere crossing two planes 0.4 apart (a band of sphere 13 fine cells
#: across between two circles, double curves) and, 0.45 above, two
#: cylinders tangent along a line (a tacnode edge: the wide tube).
BAND_BESIDE_TACNODE = "(x^2 + y^2 + z^2 - 0.1225)*(z^2 - 0.04)*((z - 0.8)^2 - 0.04*y^4)"


@pytest.mark.parametrize("seed", [None, 1, 2])
def test_wide_tube_goes_round_the_wide_curve_only(seed):
    # The wide tube (10 cells, for the tacnode edge's tangent sheets) went
    # round every curve vertex, the circles too: the band and the caps
    # between them, all within 12.5 cells of a circle, were all tube, with
    # no rail and no strip on them, and were left out (on main 12 to 104
    # lattice roots 9.5 to 10.3 cells from the mesh, 96 to 224 open edges).
    import fuzzcases as fc
    import sympy

    text = BAND_BESIDE_TACNODE if seed is None else float_rotated(BAND_BESIDE_TACNODE, seed)
    m = mesh_quiet(text, BOX1, coarse=8, fine=64)
    V, T = np.asarray(m.vertices), np.asarray(m.faces)
    box = np.asarray(BOX1, float)
    assert mc.boundary_edges_off_box(V, T, box) == []
    assert max(mc.edge_counts(T).values()) <= 4
    # No piece left out: roots of F on every second line of the fine lattice
    # (F from the text, not from the mesher) near a triangle, as the fuzz
    # judge checks (1.5 cells, or half the nearest triangle's longest edge).
    roots = fc.lattice_roots(fc.Field(sympy.expand(Surface.parse(text).expr)), box, 33)
    d, tri = mc.distance_to_mesh(roots, V, T, return_triangle=True)
    t = V[T[tri]]
    longest = np.linalg.norm(t - np.roll(t, 1, axis=1), axis=2).max(axis=1)
    cell = 2.0 / m.stats["fine"]
    far = (d > 1.5 * cell) & (d > 0.5 * longest)
    assert len(roots) > 500 and not far.any(), f"{far.sum()} roots, worst {d.max() / cell:.1f} cells off the mesh"
    # The double circles and the tacnode line are followed by mesh edges:
    # Newton samples of the singular locus (F = grad F = 0) on edges
    # between singular vertices.
    F, G, _, _ = lambdas(text)
    g = np.linalg.norm(G(V), axis=1)
    singular = g <= 1e-6 * float(np.median(g[g > 0]))
    counts = mc.edge_counts(T)
    edges = np.array(list(counts.keys()), np.int64).reshape(-1, 2)
    on_curve = edges[singular[edges[:, 0]] & singular[edges[:, 1]]]
    samples = singular_locus(text, BOX1, starts=1000)
    samples = samples[np.all(np.abs(samples) < 0.96, axis=1)]
    assert len(samples) >= 20
    assert segment_distance(samples, V[on_curve[:, 0]], V[on_curve[:, 1]]).max() <= 0.01 * 2.0
