"""Curves of singular points, checked independently of the mesher.

The surfaces are the classical ones with a singular curve (the Whitney
umbrella, the cross-cap, Steiner's Roman surface, a sphere through a
plane, three planes through a line, cylinders over plane curve
singularities, two cylinders crossing), as typed and under random float
rotations and shifts written with 15 digits.  What is checked trusts only
the equation:

- samples of {F = grad F = 0} from Gauss-Newton at random starts (numpy
  on sympy's derivatives, not the mesher's) lie on mesh edges whose two
  ends are singular vertices, or on the exported line cells;
- edges of more than two triangles are on the curve and have an even count;
  the number of triangles at the curve's edges is the number of half-sheets
  the normal form has (4 on a double curve, 2 on a cuspidal edge, 6 on a
  triple line);
- no open edge inside the box, and the expected number of pieces;
- vertices on the surface, and every triangle near a dense marching-cubes
  sample of F = 0 (scikit-image; skipped where absent);
- special points where the literature puts them (the Roman surface's
  triple point and six pinch points, the umbrella's pinch point).
"""

from __future__ import annotations

import importlib.util
import warnings

import numpy as np
import pytest
import sympy
from scipy.spatial import cKDTree

import meshcheck as mc
import singmesh
from singmesh.surface import Surface, X, Y, Z
from test_rounded import float_rotated as rounded_float_rotated

BOX1 = ((-1.0, 1.0),) * 3


def float_rotated(text: str, seed: int) -> str:
    """``text`` under a random float rotation and shift, 15 digits (as in test_rounded)."""
    return rounded_float_rotated(text, seed)[0]


def rotated_composed(text: str, seed: int) -> sympy.Expr:
    """The F of :func:`float_rotated` (same rotation and shift) composed, not expanded.

    Equal to the 15-digit input up to its rounding, and far cheaper to
    evaluate on a marching-cubes grid than its expanded terms: for the
    oracle only, the mesher gets the 15-digit text.
    """
    rng = np.random.default_rng(seed)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    shift = rng.uniform(-0.3, 0.3, 3)
    e = Surface.parse(text).expr
    u = [sum(sympy.Float(q[i, j], 17) * ((X, Y, Z)[j] - sympy.Float(shift[j], 17)) for j in range(3))
         for i in range(3)]
    return e.subs({X: u[0], Y: u[1], Z: u[2]}, simultaneous=True)


def lambdas(text):
    """F, grad F and the Jacobian of (F, grad F) as numpy functions of (n, 3) points.

    ``text`` is the surface's text, or a sympy expression of F.
    """
    e = text if isinstance(text, sympy.Expr) else Surface.parse(text).expr
    eqs = [e] + [sympy.diff(e, v) for v in (X, Y, Z)]
    jac = [[sympy.diff(q, v) for v in (X, Y, Z)] for q in eqs]
    f = sympy.lambdify((X, Y, Z), eqs, "numpy")
    j = sympy.lambdify((X, Y, Z), jac, "numpy")

    def stack(values, n):
        return np.stack([np.broadcast_to(np.asarray(v, float), (n,)) for v in values], axis=-1)

    def F(p):
        return stack(f(*p.T), len(p))[:, 0]

    def G(p):
        return stack(f(*p.T), len(p))[:, 1:]

    def R(p):
        return stack(f(*p.T), len(p))

    def J(p):
        return np.stack([stack(row, len(p)) for row in j(*p.T)], axis=1)

    return F, G, R, J


def singular_locus(text, box, starts: int = 3000, seed: int = 5) -> np.ndarray:
    """Points of {F = grad F = 0} in the box: damped least squares from random starts, converged ones."""
    _, _, R, J = lambdas(text)
    box = np.asarray(box, float)
    rng = np.random.default_rng(seed)
    p = box[:, 0] + rng.random((starts, 3)) * (box[:, 1] - box[:, 0])
    for _ in range(80):
        r, jm = R(p), J(p)
        # Levenberg-Marquardt steps, all starts at once.
        jt = np.transpose(jm, (0, 2, 1))
        a = jt @ jm + 1e-12 * np.eye(3)
        try:
            step = np.linalg.solve(a, -(jt @ r[..., None]))[..., 0]
        except np.linalg.LinAlgError:
            # A start on a curve of singular points (beyond the box) whose
            # J^T J is singular to rounding: damping in proportion to its size.
            scale = 1.0 + np.trace(a, axis1=1, axis2=2)[:, None, None]
            step = np.linalg.solve(a + 1e-12 * scale * np.eye(3), -(jt @ r[..., None]))[..., 0]
        p = p + np.clip(step, -0.1, 0.1)
    r = np.abs(R(p)).max(axis=1)
    ok = np.isfinite(p).all(axis=1) & (r < 1e-10) & np.all((p >= box[:, 0]) & (p <= box[:, 1]), axis=1)
    p = p[ok]
    # Curves only: a point with others along a curve near it.  Many starts
    # converge to an isolated singular point (a cone's apex beside the
    # curve): one sample there, so that it has no others near it.
    size = float(np.max(box[:, 1] - box[:, 0]))
    p = np.unique(np.round(p / (1e-6 * size)), axis=0) * (1e-6 * size)
    if len(p) < 3:
        return p[:0]
    tree = cKDTree(p)
    near = np.array([len(tree.query_ball_point(q, 0.05 * size)) for q in p])
    return p[near >= 3]


def segment_distance(x: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance from each point of x to the nearest of the segments a-b."""
    out = np.empty(len(x))
    d = b - a
    dd = np.maximum((d * d).sum(axis=1), 1e-300)
    for i in range(0, len(x), 256):
        q = x[i:i + 256, None, :]
        t = np.clip(((q - a) * d).sum(axis=2) / dd, 0, 1)
        out[i:i + 256] = np.linalg.norm(q - (a + t[..., None] * d), axis=2).min(axis=1)
    return out


def mesh_quiet(text, box, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", singmesh.SingularPointWarning)
        return singmesh.mesh(text, box, **kw)


def check_curve_mesh(text, box, components=1, half_sheets=None, oracle=None, samples=None, **kw):
    """The independent checks of the module docstring; returns the mesh and its line cells.

    ``oracle``: F as a sympy expression for the checks (default: ``text``
    parsed), e.g. a rotated F composed rather than expanded (faster);
    ``samples``: points of the singular curve known by construction (default:
    :func:`singular_locus`'s, which converges slowly onto cuspidal edges).
    """
    m = mesh_quiet(text, box, **kw)
    text = text if oracle is None else oracle
    mm = m.to_meshio()
    V = np.asarray(mm.points, float)
    T = np.concatenate([c.data for c in mm.cells if c.type == "triangle"])
    L = [c.data for c in mm.cells if c.type == "line"]
    L = np.concatenate(L) if L else np.zeros((0, 2), np.int64)
    F, G, _, _ = lambdas(text)
    box = np.asarray(box, float)
    size = float(np.max(box[:, 1] - box[:, 0]))
    g = np.linalg.norm(G(V), axis=1)
    scale = float(np.median(g[g > 0]))
    singular = g <= 1e-6 * scale
    # Vertices on the surface: regular ones to 1e-9 of the box along the
    # gradient, singular ones with F at rounding level.
    regular = ~singular
    assert (np.abs(F(V[regular])) / g[regular]).max() <= 1e-9 * size
    assert np.abs(F(V[singular])).max(initial=0.0) <= 1e-9 * scale * size
    counts = mc.edge_counts(T)
    edges = np.array(list(counts.keys()), np.int64).reshape(-1, 2)
    n = np.array(list(counts.values()))
    # No open edge inside the box.
    assert mc.boundary_edges_off_box(V, T, box) == []
    # Edges of more than two triangles lie on the curve, with an even count.
    many = n > 2
    assert singular[edges[many]].all()
    assert (n[many] % 2 == 0).all()
    # A curve traced twice zips strips across its copies: edges of hundreds
    # of triangles.  (Up to three sheets meet along these curves, 6 per
    # edge; next to special points edges of 8 to 14 still occur, issue #9.)
    assert n.max() <= 16, f"an edge of {n.max()} triangles"
    # The curve is followed by mesh edges between singular vertices, or by line cells.
    samples = singular_locus(text, box) if samples is None else np.asarray(samples, float)
    inside = np.all((samples > box[:, 0] + 0.02 * size) & (samples < box[:, 1] - 0.02 * size), axis=1)
    samples = samples[inside]
    assert len(samples) >= 20, "the oracle found no curve: the case is wrong"
    on_curve = edges[singular[edges[:, 0]] & singular[edges[:, 1]]]
    segs = np.concatenate([on_curve, L]) if len(L) else on_curve
    d = segment_distance(samples, V[segs[:, 0]], V[segs[:, 1]])
    assert d.max() <= 0.01 * size, f"{(d > 0.01 * size).sum()} curve samples far from the curve's edges"
    if components is not None:   # None: not known independently (as the judge does for Crixxi)
        assert mc.components(T) == components
    if half_sheets is not None:
        # Each edge along the curve (not at its ends) has one triangle per half-sheet.
        inner = on_curve[~mc.on_box(V[on_curve[:, 0]], box, 1e-3) & ~mc.on_box(V[on_curve[:, 1]], box, 1e-3)]
        per_edge = np.array([counts[(min(a, b), max(a, b))] for a, b in inner.tolist()])
        assert len(per_edge) and np.mean(per_edge == half_sheets) >= 0.95, np.bincount(per_edge)
    close_to_marching_cubes(F, box, V, T)
    return m, L


def close_to_marching_cubes(F, box, V, T):
    """Every triangle near a dense marching-cubes sample of F = 0 (grid off the split planes)."""
    if importlib.util.find_spec("skimage") is None:
        pytest.skip("scikit-image is not installed (pip install -e '.[bench]'): the marching-cubes oracle is skipped")
    from skimage.measure import marching_cubes

    n = 128
    h = (box[:, 1] - box[:, 0]) / n
    axes = [np.linspace(b[0] + 0.37 * s, b[1] - 0.63 * s, n) for b, s in zip(box, h)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    values = F(grid).reshape(n, n, n)
    pts, _, _, _ = marching_cubes(values, 0.0, spacing=tuple(h))
    pts = pts + np.array([a[0] for a in axes])
    a, b, c = V[T[:, 0]], V[T[:, 1]], V[T[:, 2]]
    longest = np.max([np.linalg.norm(b - a, axis=1), np.linalg.norm(c - b, axis=1), np.linalg.norm(a - c, axis=1)],
                     axis=0)
    d, _ = cKDTree(pts).query((a + b + c) / 3)
    # Thin wedges between tangent sheets are below the grid's resolution:
    # allow two grid cells besides the triangle's own size.
    far = d > 0.5 * longest + 2.0 * float(h.max())
    assert far.mean() <= 0.002, f"{far.sum()} of {len(T)} triangles away from the surface"


# ------------------------------------------------------------------ the classical surfaces
CLASSICAL = [
    # text, box, components, half-sheets on the curve (None: varies)
    ("x^2 - y^2 z", BOX1, 1, None),                                     # Whitney umbrella
    ("x^2 y^2 + y^2 z^2 + z^2 x^2 - x y z", BOX1, 1, None),             # Steiner's Roman surface
    ("(x^2 + y^2 + z^2 - 1) z", ((-1.5, 1.5),) * 3, 1, 4),              # sphere through a plane
    ("x^3 - 3 x y^2", BOX1, 1, 6),                                      # three planes through a line
    ("x^2 - y^3", BOX1, 1, 2),                                          # cuspidal edge
    ("(x^2 + y^2 - 1)(x^2 + z^2 - 1)", ((-1.5, 1.5),) * 3, 1, None),    # two cylinders: crossing double curves
    ("y^2 - x^2 (x + 1)", ((-1.5, 1.5),) * 3, 1, 4),                    # nodal cubic times a line
    ("(x^2 + y^2) z - 2 x y", ((-1.3, 1.3),) * 3, 1, None),              # Pluecker's conoid: pinch points at z = +-1
    ("x y z", BOX1, 1, None),                                           # three planes: three double lines, a triple point
    ("x^2 - y^2 z^2", BOX1, 1, None),                                   # two double lines crossing
]


@pytest.mark.parametrize("text, box, components, half", CLASSICAL)
def test_classical_surfaces_with_singular_curves(text, box, components, half):
    check_curve_mesh(text, box, components, half)


@pytest.mark.parametrize("text", ["x^2 - y^2 z", "x^2 y^2 + y^2 z^2 + z^2 x^2 - x y z", "x^2 - y^3",
                                  "x^3 - 3 x y^2", "(x^2 + y^2 + z^2 - 1) z"])
@pytest.mark.parametrize("seed", [3, 11])
def test_float_rotated_and_shifted(text, seed):
    # General position: the curve on no split plane or lattice line, and
    # coefficients rounded to 15 digits (the curve is singular only to
    # the precision of the input).
    box = ((-1.5, 1.5),) * 3 if "z^2 - 1" in text else BOX1
    check_curve_mesh(float_rotated(text, seed), box, 1)


def test_transversal_types_are_named():
    # The plane curve singularity across the curve, from the normal forms.
    cases = {"x^2 - y^2": ("A1 double curve", 2, 4), "x^2 + y^2": ("A1 isolated line", 0, 0),
             "x^2 - y^3": ("A2 cuspidal edge", 1, 2), "x^2 - y^4": ("A3 tacnode edge", 2, 4),
             "x^3 - 3 x y^2": ("D4 triple curve", 3, 6)}
    for text, (name, sheets, half) in cases.items():
        m = mesh_quiet(float_rotated(text, 1), BOX1)
        assert m.singular_curves, text
        main = max(m.singular_curves, key=lambda c: c.length)
        assert (main.type, main.sheets, main.half_sheets) == (name, sheets, half), text
        assert main.length > 1.5  # the whole line through the box


def test_isolated_real_line_is_line_cells():
    # x^2 + y^2 = 0 is the z-axis alone: no triangle, a polyline of line cells.
    m = mesh_quiet("x^2 + y^2", BOX1)
    assert len(m.faces) == 0
    pts, lines = m.curve_lines()
    assert len(lines) > 100
    assert np.abs(pts[lines.ravel()][:, :2]).max() <= 1e-12
    assert np.ptp(pts[lines.ravel()][:, 2]) == pytest.approx(2.0)


def test_whitney_umbrella_pinch_point_and_handle():
    m, lines = check_curve_mesh("x^2 - y^2 z", BOX1, 1)
    pinch = [sp for sp in m.special_points if sp.kind == "pinch point"]
    assert len(pinch) == 1 and np.linalg.norm(pinch[0].point) <= 1e-9
    assert pinch[0].vertex is not None
    # The handle (z < 0) is line cells, the double line (z > 0) is edges of 4 triangles.
    pts, _ = m.curve_lines()
    z = pts[lines.ravel()][:, 2]
    assert z.max() <= 1e-9 and z.min() == pytest.approx(-1.0)
    types = {c.type for c in m.singular_curves}
    assert types == {"A1 double curve", "A1 isolated line"}
    # The mesher's own count of curve edges short of their sheets agrees.
    assert m.curve_edges_short_of_sheets() == 0 and not any("half-sheets" in n for n in m.notes())


def test_roman_surface_triple_and_pinch_points():
    # Steiner: the three axes are double segments between the pinch points
    # at +-1/2 (for x^2y^2 + y^2z^2 + z^2x^2 - xyz), crossing at a triple point.
    m = mesh_quiet("x^2 y^2 + y^2 z^2 + z^2 x^2 - x y z", BOX1)
    triple = [sp.point for sp in m.special_points if sp.kind == "triple point"]
    pinch = np.array([sp.point for sp in m.special_points if sp.kind == "pinch point"])
    assert len(triple) == 1 and np.linalg.norm(triple[0]) <= 1e-9
    want = np.array([[s * 0.5 * (i == a) for i in range(3)] for a in range(3) for s in (1, -1)])
    assert len(pinch) == 6
    assert np.abs(np.sort(pinch, axis=0) - np.sort(want, axis=0)).max() <= 1e-9
    assert all(sp.vertex is not None for sp in m.special_points)


def test_split_plane_and_general_position_agree():
    # The same umbrella with its double line on a lattice line (box centred)
    # and off every split plane (box shifted): the same curve types.
    a = mesh_quiet("x^2 - y^2 z", BOX1)
    b = mesh_quiet("x^2 - y^2 z", ((-0.9137, 1.0711), (-1.0291, 0.9623), (-0.9871, 1.0333)))
    assert sorted(c.type for c in a.singular_curves) == sorted(c.type for c in b.singular_curves)
    assert len(b.special_points) == len(a.special_points)


def test_curves_are_written_beside_the_triangles(tmp_path):
    meshio = pytest.importorskip("meshio")
    m = mesh_quiet("x^2 - y^2 z", BOX1)
    m.write(tmp_path / "u.vtu")
    cells = {c.type: len(c.data) for c in meshio.read(tmp_path / "u.vtu").cells}
    assert cells["triangle"] == len(m.faces) and cells["line"] > 100
    m.write(tmp_path / "u.obj")  # no line cells in OBJ: a companion file
    curves = meshio.read(tmp_path / "u.curves.vtk")
    assert sum(len(c.data) for c in curves.cells if c.type == "line") == len(m.curve_graph[1])
    text = m.report_text()
    assert "A1 double curve" in text and "pinch point" in text


def test_same_bytes_every_time(tmp_path):
    paths = []
    for k in range(2):
        m = mesh_quiet("x^2 y^2 + y^2 z^2 + z^2 x^2 - x y z", BOX1, coarse=16, fine=64)
        paths.append(m.write(tmp_path / f"r{k}.vtk"))
    assert paths[0].read_bytes() == paths[1].read_bytes()


def test_repeated_factor_is_removed_and_said():
    # (x^2+y^2+z^2-1)^2 never changes sign: its sphere is all singular.
    # The square-free part is the sphere; the mesh is a closed sphere and
    # the note names the factor.
    m = mesh_quiet("(x^2 + y^2 + z^2 - 1)^2", ((-1.5, 1.5),) * 3, coarse=16, fine=64)
    assert mc.boundary_edges(m.faces) == [] and mc.euler(m.vertices, m.faces) == 2
    r = np.linalg.norm(m.vertices, axis=1)
    assert np.abs(r - 1).max() <= 1e-12
    assert any("(x**2 + y**2 + z**2 - 1)^2" in n for n in m.notes())
    # A product with a doubled factor keeps the other factor's sheet too.
    m = mesh_quiet("(x - 0.3)^3 (y + 0.2)", BOX1, coarse=16, fine=64)
    assert {round(float(v), 12) for v in m.vertices[:, 0][np.abs(m.vertices[:, 1] + 0.2) > 1e-9]} == {0.3}
    assert m.stats["repeated_factors"] == [("x - 3/10", 3)]


@pytest.mark.parametrize("seed", [7, 3])
def test_tacnode_edge_in_general_position(seed):
    # Two sheets tangent along a line (x^2 = y^4): they part only as the
    # square of the distance, yet every edge of the curve must carry two
    # triangles of each sheet, and no triangle join them.
    check_curve_mesh(float_rotated("x^2 - y^4", seed), BOX1, 1, half_sheets=4)


def test_pluecker_conoid_pinch_points():
    # z (x^2 + y^2) = 2 x y: on the z-axis the sheets are the lines
    # y = t x with z = 2t / (1 + t^2), real for |z| <= 1: a double line
    # between the pinch points (0, 0, +-1), an isolated line beyond.
    m = mesh_quiet("(x^2 + y^2) z - 2 x y", ((-1.3, 1.3),) * 3)
    pinch = np.array(sorted((sp.point.tolist() for sp in m.special_points if sp.kind == "pinch point"),
                            key=lambda p: p[2]))
    assert pinch.shape == (2, 3)
    assert np.abs(pinch - [[0, 0, -1], [0, 0, 1]]).max() <= 1e-9
    inner = [c for c in m.singular_curves if np.abs(c.points[:, 2]).max() <= 1 + 1e-9]
    assert inner and all(c.type == "A1 double curve" for c in inner)


def test_cli_lists_curves_and_names_the_companion_file(tmp_path):
    from singmesh.cli import main

    out = tmp_path / "u.obj"
    import contextlib
    import io

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(["mesh", "x^2 - y^2 z", "-o", str(out), "--box", "-1", "1", "-1", "1", "-1", "1",
                     "--coarse", "16", "--fine", "64"]) == 0
    text = buf.getvalue()
    assert "singular curves      2" in text and "pinch point" in text
    assert (tmp_path / "u.curves.vtk").is_file() and "u.curves.vtk" in text


def test_curve_leaving_near_a_box_edge_is_closed():
    # Rotated xyz: a double line leaves the box near the edge x = 1, z = -1,
    # its rail on one face and its end on the other; the strip's cap turns
    # at the box edge (no open edge inside the box).
    check_curve_mesh(float_rotated("x y z", 22), BOX1, 1)


# ------------------------------------------------------------------ cuspidal edges crossing
CRIXXI = "(y^2 + z^2 - 1)^2 + (x^2 + y^2 - 1)^3"
#: Around (0, 1, 0): F = (a + z^2)^2 + (a + x^2)^3 with a = 2 (y - 1) + (y - 1)^2,
#: so the cuspidal edges y^2 + z^2 = 1 = x^2 + y^2 (z = +-x) cross there, and
#: the two half-sheets between them are a lens as thin as the cube of the distance.
CRIXXI_BOX = ((-0.7, 0.7), (0.3, 1.7), (-0.7, 0.7))


@pytest.mark.parametrize("text, point", [
    (CRIXXI, (0.0, 1.0, 0.0)),
    # another crossing of cuspidal edges: z = +-x / sqrt(2), same point
    ("(y^2 + 2 z^2 - 1)^2 + (x^2 + y^2 - 1)^3", (0.0, 1.0, 0.0)),
])
def test_cuspidal_edges_crossing(text, point):
    m, _ = check_curve_mesh(text, CRIXXI_BOX, 1, 2, coarse=16, fine=128)
    p = np.array(point)
    # The crossing is found, typed, a vertex, and the four pieces end there.
    # It is placed to a quarter of a fine cell: (F, grad F) grows only as
    # the fourth power of the distance along the cylinders' common tangent
    # plane there, so rounding hides it within about 1e-3.
    near = [sp for sp in m.special_points if np.linalg.norm(sp.point - p) <= 0.25 * 1.4 / 128]
    assert len(near) == 1, [sp.describe() for sp in m.special_points]
    assert near[0].kind == "crossing of cuspidal edges"
    assert np.linalg.norm(m.vertices[near[0].vertex] - near[0].point) == 0.0
    i = m.special_points.index(near[0])
    assert sum(c.ends.count(i) for c in m.singular_curves) == 4
    assert {c.type for c in m.singular_curves} == {"A2 cuspidal edge"}
    # No other special point inside the box (the rest are curve ends on it).
    inner = [sp for sp in m.special_points if sp is not near[0]]
    assert all(sp.kind == "end on the box" for sp in inner), [sp.describe() for sp in inner]
    # Crixxi's cuspidal edges z = +-x leave its box through the box's edges
    # (x, z = +-0.7), where the curve is located across itself to ~1e-8
    # only: an end near a second face of the box lies on it exactly (ends
    # a few 1e-8 off it, as rounding left them, cut the box's corner: open
    # edges inside the box).
    box = np.asarray(CRIXXI_BOX, float)
    for sp in inner:
        gap = np.minimum(np.abs(sp.point - box[:, 0]), np.abs(sp.point - box[:, 1]))
        assert np.all((gap == 0.0) | (gap > 1e-6)), sp.describe()
        assert np.linalg.norm(m.vertices[sp.vertex] - sp.point) == 0.0


@pytest.mark.parametrize("seed", [3, 5])
def test_cuspidal_edges_crossing_rotated(seed):
    # Crixxi rotated and shifted (15-digit coefficients), in a box of the
    # same size round the image of the crossing (0, 1, 0).  Just outside the
    # ball that is tube round the crossing the half-sheets of each cusp are
    # 1.5 cells apart only 8 to 10 cells out: on main a lattice edge 5.7
    # cells out crossed both at seeds 3 and 5 (an edge of four triangles
    # between regular vertices).
    rng = np.random.default_rng(seed)       # the rotation float_rotated uses
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    shift = rng.uniform(-0.3, 0.3, 3)
    p = np.array([0.0, 1.0, 0.0]) @ q + shift
    box = np.stack([p - 0.7, p + 0.7], axis=1)
    m, _ = check_curve_mesh(float_rotated(CRIXXI, seed), box, 1, 2, oracle=rotated_composed(CRIXXI, seed),
                            coarse=16, fine=128)
    near = [sp for sp in m.special_points if np.linalg.norm(sp.point - p) <= 0.25 * 1.4 / 128]
    assert len(near) == 1 and near[0].kind == "crossing of cuspidal edges", [sp.describe() for sp in m.special_points]
    i = m.special_points.index(near[0])
    assert sum(c.ends.count(i) for c in m.singular_curves) == 4
    assert {c.type for c in m.singular_curves} == {"A2 cuspidal edge"}
    # No edge of more than two triangles (a cuspidal edge is a crease).
    counts = mc.edge_counts(m.faces)
    assert max(counts.values()) == 2


def test_newton_across_the_curve_reaches_rounding_level_on_rounded_input():
    # Two cylinders, rotated and shifted with 15-digit coefficients: the
    # double curve is two ellipses, known exactly from the rotation.  From
    # points a third of a trace step off it, Newton held across a direction
    # a few degrees off the tangent (a chord, as the trace has) must land on
    # the curve to the input's rounding, all along it, the tangential
    # crossings at (+-1, 0, 0) included.
    from singmesh.skeleton.centre import residual
    from singmesh.skeleton.singular import accept_residual
    from singmesh.skeleton.singular_curves import _correct

    seed = 30
    text = float_rotated("(x^2 + y^2 - 1)(x^2 + z^2 - 1)", seed)
    rng = np.random.default_rng(seed)       # the rotation float_rotated used
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    shift = rng.uniform(-0.3, 0.3, 3)
    surface = Surface.parse(text)
    th = np.linspace(0, 2 * np.pi, 64, endpoint=False)
    sign = np.where(np.arange(64) % 2, 1.0, -1.0)   # both ellipses, y = +-z
    exact = np.stack([np.cos(th), np.sin(th), sign * np.sin(th)], 1) @ q + shift
    tangent = np.stack([-np.sin(th), np.cos(th), sign * np.cos(th)], 1) @ q
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    r = np.random.default_rng(1)
    tilt = r.normal(size=tangent.shape)
    tilt -= (tilt * tangent).sum(1, keepdims=True) * tangent
    tilt /= np.linalg.norm(tilt, axis=1, keepdims=True)
    across = np.cos(0.05) * tangent + np.sin(0.05) * tilt     # ~3 degrees off
    h = 3.0 / 64
    start = exact + 0.3 * h * np.roll(tilt, 1, axis=0)
    x, ok = _correct(surface, start, across, h)
    assert ok.all()
    assert residual(surface, x).max() <= accept_residual(surface)
    # On the curve: F = G H with G, H the two cylinders, both zero there.
    u = (x - shift) @ q.T
    assert np.abs(u[:, 0] ** 2 + u[:, 1] ** 2 - 1).max() <= 1e-6
    assert np.abs(u[:, 0] ** 2 + u[:, 2] ** 2 - 1).max() <= 1e-6


def test_curve_running_just_inside_a_face_of_the_box():
    # The circle of (sphere) * (plane) comes within half a cell of the face
    # x = -1.0041 without reaching it: two half-sheets leave the tube
    # through the box there and come back onto its side further on.  The
    # box is off the lattice of the circle's plane (general position).
    check_curve_mesh("(x^2 + y^2 + z^2 - 1) z", ((-1.0041, 1.1), (-1.1, 1.1), (-1.1, 1.13)), 1, half_sheets=4)



def test_curves_tangent_at_a_point_on_split_planes():
    # y z (x^2 + y - z): three double curves, the x-axis and the parabolas
    # y = -x^2 (in z = 0) and z = x^2 (in y = 0), all on lattice planes and
    # tangent to each other at the origin, so closer than a cell over
    # |x| < 0.09.  Merged crossings there joined two vertices of one
    # parabola both by a trace and by a chord: the strips zipped to both
    # (edges of three triangles).
    check_curve_mesh("y z (x^2 + y - z)", BOX1, 1, coarse=16, fine=256)


def test_closed_curves_from_a_start_near_a_crossing_are_traced_once():
    # Two cylinders at the default lattice: the first sample lies near a
    # crossing of the two ellipses, off the curve by more than the closing
    # distance, so the trace went round its ellipse four times; strips
    # zipped across the copies into edges of a thousand triangles
    # (1.7 million triangles on 72 thousand vertices).
    # (test_classical_surfaces_with_singular_curves runs the independent
    # checks on the same mesh.)
    text, box = "(x^2 + y^2 - 1)(x^2 + z^2 - 1)", ((-1.5, 1.5),) * 3
    m = mesh_quiet(text, box)
    counts = np.array(list(mc.edge_counts(m.faces).values()))
    assert counts.max() == 4
    assert len(m.faces) < 2.2 * len(m.vertices)
    crossings = [sp for sp in m.special_points if "crossing" in sp.kind]
    assert sorted(np.round(sp.point[0], 6) for sp in crossings) == [-1.0, 1.0]


@pytest.mark.parametrize("text", [
    "(4 y/3 - 5 z + 1)(x^2 + y^2 + z^2 - 0.8)",
    "(3 x - 7 y/2 + 1/4)(x^2 - y z + z/3 - 1/5)",
    "(5 x/7 - 3 z/7 + 1/8)(x^3 - 3 x y^2 + z^2 - 1/3)",
])
def test_plane_through_lattice_lines_crossing_a_surface(text):
    # A plane with rational coefficients holds whole lattice lines of the
    # octree (4y/3 - 5z + 1 = 0 at y = 114/128, z = 56/128 for every x).
    # Along them F is rounding noise of either sign: read as signs, it
    # made r- and r+ events at random lattice points there, and the rails
    # of the tube round the double curve broke (6 to 73 open edges).
    check_curve_mesh(text, BOX1, 1, half_sheets=4)


@pytest.mark.parametrize("text, axis", [
    ("-1.3163809875646 y^6 - 0.224145358282518 z^3", 0),   # J10 across the x-axis
    ("4/7 y^5 - 1/2 x^3 y^2 - 9/2 x^4 z", 2),              # along the z-axis
])
def test_curve_vertices_of_a_type_beyond_a_k_lie_on_the_curve(text, axis):
    # Across these curves F's second derivatives vanish (to fourth order for
    # y^6 + z^3), so the Jacobian of (F, grad F) has singular values far
    # below 1e-11 near the curve: an absolute floor on them stopped Newton
    # with the curve's vertices up to 7e-4 off the axis (fuzz s1-41, s1-220).
    m = mesh_quiet(text, BOX1)
    curve = np.concatenate([c.vertices for c in m.singular_curves])
    P = m.vertices[curve]
    # The singular line is the coordinate axis (sympy: F and grad F vanish there).
    others = [v for i, v in enumerate((X, Y, Z)) if i != axis]
    e = Surface.parse(text).expr
    assert all(sympy.expand(q.subs({others[0]: 0, others[1]: 0})) == 0 for q in (e, e.diff(X), e.diff(Y), e.diff(Z)))
    off = np.linalg.norm(np.delete(P, axis, axis=1), axis=1)
    assert len(P) >= 100
    assert np.median(off) <= 1e-8
    assert np.mean(off <= 1e-6) >= 0.99, np.sort(off)[-5:]


@pytest.mark.parametrize("text, axis, box", [
    # A trace starts at a sample of the locus, which had met only a
    # sample's residual: as the curve's vertex it stayed 1.3e-7 off the
    # axis, the only one of its 68 vertices (the judge's off-surface).
    ("0.571428571428571 y^5 - 0.5 x^3 y^2 - 4.5 x^4 z", 2, BOX1),   # fuzz s1-220, 15-digit decimals
    # The pinch point where the type changes near the degenerate origin:
    # Newton stopped 1.7e-6 off the axis with a residual under the
    # vertex's (relative, F and grad F tiny there) (fuzz s1-72).
    ("7 x y z^4 + 0.5 x^3 y z^2 + x^4 z^2 - 0.375 x^5 z - 0.333333333333333 x^5 - 8 y^3 z", 2,
     ((-2.0, 2.0), (-1.0, 1.0), (-0.5, 0.5))),
])
def test_every_curve_vertex_lies_on_the_curve_the_trace_start_too(text, axis, box):
    m = mesh_quiet(text, box, coarse=8, fine=64)
    P = m.vertices[np.concatenate([c.vertices for c in m.singular_curves])]
    others = [v for i, v in enumerate((X, Y, Z)) if i != axis]
    e = Surface.parse(text).expr
    assert all(sympy.expand(q.subs({others[0]: 0, others[1]: 0})) == 0 for q in (e, e.diff(X), e.diff(Y), e.diff(Z)))
    off = np.linalg.norm(np.delete(P, axis, axis=1), axis=1)
    assert len(P) >= 15  # the axis in the box, a vertex a cell or less apart
    assert off.max() <= 1e-9, np.sort(off)[-3:]


def _lens(a: float, b: float, seed: int | None) -> tuple[str, np.ndarray]:
    """x^2 = a z^3 - b z^4 (+ a twist): a lens about a fine cell wide round a cuspidal edge along y.

    Widest at z = 3a/(4b): 0.04 across for (0.48, 2.4), 0.03 for (0.36, 2);
    the fine cell at fine 64 on [-1, 1]^3 is 0.031.  ``seed``: float-rotated
    and shifted (15 digits).  Returns the text and points of the edge.
    """
    text = f"x^2 - {a}*z^3 + {b}*z^4 + 0.3*x*y*z^2"
    t = np.linspace(-1.5, 1.5, 301)[:, None]
    if seed is None:
        return text, t * np.array([0.0, 1.0, 0.0])
    # The rotation and shift float_rotated draws: u = q (X - shift), the
    # edge u = (0, t, 0) is X = shift + t q[1].
    rng = np.random.default_rng(seed)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    shift = rng.uniform(-0.3, 0.3, 3)
    return float_rotated(text, seed), shift + t * q[1]


LENSES = [(a, b, seed) for a, b in ((0.48, 2.4), (0.36, 2.0)) for seed in (None, 3, 4)]


@pytest.mark.parametrize("a, b, seed", LENSES, ids=[f"{a}-{b}-{s}" for a, b, s in LENSES])
def test_lens_about_a_cell_wide_round_a_cuspidal_edge(a, b, seed):
    # Fuzz s3-925: all of the surface lies in the cuspidal edge's tube, its
    # strips fail, and the mesh was empty (said as "F and grad F vanish to
    # rounding on more than points and curves", which is not so).
    text, edge = _lens(a, b, seed)
    box = np.array([(-1.0, 1.0)] * 3)
    edge = edge[np.all((edge > box[:, 0]) & (edge < box[:, 1]), axis=1)]
    m, _ = check_curve_mesh(text, box, components=1, half_sheets=2, samples=edge, coarse=8, fine=64)
    assert m.stats["fine"] > 64, "meshed on a finer lattice than asked, where its sheets are apart"
