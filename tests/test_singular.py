"""Singular points meshed right: found, placed as a vertex, branches meeting there.

Expected facts come from outside the mesher: branch counts derived from the
normal forms (and confirmed by counting the curves F = 0 cuts on a small
sphere, tests/oracles.py), node locations from sympy's solver (Cayley) or
from an independent Newton search with the literature counts (Kummer 16,
Barth 50 real affine nodes), and the mesh topology from tests/meshcheck.py.
"""

import itertools

import numpy as np
import pytest
import sympy

import singmesh
from singmesh.skeleton.directions import FIXED_DIRECTIONS, delta, skeleton_directions
from singmesh.skeleton.singular import singular_points
from singmesh.surface import X, Y, Z, Surface

import meshcheck as mc
from oracles import branches_on_sphere

BOX1 = ((-1, 1),) * 3

FORMS = {f"A{n}": "x^%d {} y^2 {} z^2" % (n + 1) for n in range(1, 6)}
FORMS.update({f"D{n}": "y x^2 {} y^%d {} z^2" % (n - 1) for n in range(4, 7)})
FORMS.update({"E6": "x^3 {} y^4 {} z^2", "E7": "x^3 {} x y^3 {} z^2", "E8": "x^3 {} y^5 {} z^2"})
CASES = [(name + a + b, f.format(a, b)) for name, f in FORMS.items() for a, b in itertools.product("+-", repeat=2)]


def expected_branches(label: str) -> int:
    """Branches of the real normal forms (seed 000, section 3.2).

    A_k: k even -> one sheet (half-cone or plane); k odd -> a cone (2)
    unless both signs are + (x^(k+1) + y^2 + z^2: an isolated point, 0).
    D_k: k odd -> a cone (2); k even -> a plane (1) when y^(k-1) has sign +,
    three half-cones (3) when it has sign -.  E6, E8: F is monotone in x,
    one sheet; E7: a cone (2).
    """
    name, a, b = label[:-2], label[-2], label[-1]
    k = int(name[1:])
    if name[0] == "A":
        return 1 if k % 2 == 0 else (0 if a + b == "++" else 2)
    if name[0] == "D":
        return 2 if k % 2 else (1 if a == "+" else 3)
    return {"E6": 1, "E7": 2, "E8": 1}[name]


def numpy_f(expr):
    """F and (as attribute ``grad``) its exact gradient, as numpy functions."""
    f = sympy.lambdify((X, Y, Z), expr, "numpy")
    g = sympy.lambdify((X, Y, Z), [sympy.diff(expr, v) for v in (X, Y, Z)], "numpy")

    def call(p):
        return f(p[..., 0], p[..., 1], p[..., 2]) + 0 * p[..., 0]

    call.grad = lambda p: np.stack(np.broadcast_arrays(*g(p[..., 0], p[..., 1], p[..., 2])), axis=-1)
    return call


def rational_rotation(seed: int) -> sympy.Matrix:
    """An exact rotation (Cayley transform of a rational skew matrix)."""
    rng = np.random.default_rng(seed)
    a, b, c = (sympy.Rational(int(v), 7) for v in rng.integers(-6, 7, 3))
    skew = sympy.Matrix([[0, -c, b], [c, 0, -a], [-b, a, 0]])
    return (sympy.eye(3) - skew) * (sympy.eye(3) + skew).inv()


SHIFT = (sympy.Rational(1, 7), sympy.Rational(-2, 9), sympy.Rational(3, 11))


def rotated(text: str, seed: int):
    e = Surface.parse(text).expr
    v = rational_rotation(seed) * sympy.Matrix([X - SHIFT[0], Y - SHIFT[1], Z - SHIFT[2]])
    return sympy.expand(e.subs({X: v[0], Y: v[1], Z: v[2]}, simultaneous=True)), np.array(SHIFT, float)


def check_singular_mesh(m, point, branches, box, f):
    """The facts the issue asks for, counted on the mesh alone."""
    found = [s for s in m.singularities if np.abs(s.point - point).max() <= 1e-9]
    assert len(found) == 1, f"singular point {point} not found: {[s.point for s in m.singularities]}"
    s = found[0]
    assert not mc.non_manifold_edges(m.faces)
    assert mc.boundary_edges_off_box(m.vertices, m.faces, np.array(box, float)) == []
    # Sharp cusps: no triangle of (absolutely) no area, no vertices a hair apart.
    assert mc.tiny_triangles(m.vertices, m.faces, box) == 0
    assert mc.close_vertex_pairs(m.vertices, box) == 0
    if branches == 0:
        assert s.vertex is None
        return
    assert s.vertex is not None, "the singular point is not a mesh vertex"
    assert np.abs(m.vertices[s.vertex] - point).max() <= 1e-9
    assert mc.fans_at(m.faces, s.vertex) == branches
    assert mc.fans_are_closed(m.faces, s.vertex)
    # Vertices on the surface: |F| / |grad F| away from singular points, |F| at them.
    singular = [t.vertex for t in m.singularities if t.vertex is not None]
    v = np.delete(m.vertices, singular, axis=0)
    dist = np.abs(f(v)) / np.linalg.norm(f.grad(v), axis=1)
    assert dist.max() <= 1e-10 * np.ptp(np.array(box, float), axis=1).max()
    assert abs(f(m.vertices[s.vertex][None])[0]) <= 1e-12


# ------------------------------------------------------------------ oracle
@pytest.mark.parametrize("label, text", CASES, ids=[c[0] for c in CASES])
def test_expected_branches_agree_with_sphere_count(label, text):
    f = numpy_f(Surface.parse(text).expr)
    assert branches_on_sphere(f, np.zeros(3), 0.3) == expected_branches(label)


# ------------------------------------------------------------------ normal forms at the centre
@pytest.mark.parametrize("label, text", CASES, ids=[c[0] for c in CASES])
def test_normal_form_at_centre(label, text):
    m = singmesh.mesh(text, BOX1)
    check_singular_mesh(m, np.zeros(3), expected_branches(label), BOX1, numpy_f(Surface.parse(text).expr))
    assert len(m.singularities) == 1


# ------------------------------------------------------------------ rotated and shifted
@pytest.mark.parametrize("label, text", CASES, ids=[c[0] for c in CASES])
def test_normal_form_rotated_and_shifted(label, text):
    seed = sum(map(ord, label)) * 7 % 1000
    expr, shift = rotated(text, seed)
    m = singmesh.mesh(expr, BOX1)
    check_singular_mesh(m, shift, expected_branches(label), BOX1, numpy_f(expr))


# ------------------------------------------------------------------ named surfaces
def test_cayley_nodes_from_sympy():
    text = "4(x^2+y^2+z^2)+16xyz-1"
    expr = Surface.parse(text).expr
    sols = sympy.solve([expr] + [sympy.diff(expr, v) for v in (X, Y, Z)], [X, Y, Z], dict=True)
    nodes = np.array([[float(s[v]) for v in (X, Y, Z)] for s in sols])
    assert len(nodes) == 4
    box = ((-1.5, 1.5),) * 3
    m = singmesh.mesh(text, box)
    assert len(m.singularities) == 4
    for p in nodes:
        check_singular_mesh(m, p, 2, box, numpy_f(expr))
    assert mc.euler(m.vertices, m.faces) == 2 and mc.components(m.faces) == 1


@pytest.mark.parametrize("key, text, box, count", [
    ("kummer", "(x^2+y^2+z^2-1.69)^2 - 407/131 (1-z-sqrt(2) x)(1-z+sqrt(2) x)(1+z+sqrt(2) y)(1+z-sqrt(2) y)",
     ((-2.5, 2.5),) * 3, 16),
    ("barth", "4(t^2 x^2-y^2)(t^2 y^2-z^2)(t^2 z^2-x^2) - (1+2t)(x^2+y^2+z^2-1)^2; t = (1+sqrt(5))/2;",
     ((-2, 2),) * 3, 50),
])
def test_many_nodes(key, text, box, count):
    from benchmarks import nodes

    truth = nodes.true_nodes(key)
    assert len(truth) == count  # the literature count, by an independent solver
    m = singmesh.mesh(text, box)
    assert len(m.singularities) == count
    f = numpy_f(Surface.parse(text).expr)
    for p in truth:
        check_singular_mesh(m, p, 2, box, f)


@pytest.mark.parametrize("coeffs", [(-0.2, 0.1, -0.5, -0.46, 0.26, -0.10), (-0.23, 0.49, -0.41, -0.95, 0.78, -0.63)])
def test_seed_quadratic_forms(coeffs):
    a, b, c, d, e, f = coeffs
    text = f"{a} x^2 + {2 * b} x y + {2 * c} x z + {d} y^2 + {2 * e} y z + {f} z^2"
    m = singmesh.mesh(text, BOX1)
    check_singular_mesh(m, np.zeros(3), 2, BOX1, numpy_f(Surface.parse(text).expr))


def test_isolated_real_point_is_reported():
    m = singmesh.mesh("x^2 + y^2 + z^2", BOX1)
    assert len(m.faces) == 0
    assert len(m.singularities) == 1 and m.singularities[0].vertex is None
    assert np.abs(m.singular_points[0]).max() <= 1e-12
    assert m.singularities[0].branches == 0


# ------------------------------------------------------------------ the mathematics
def test_delta_test_against_direct_computation():
    # V(F, grad F . v) for a quadratic form is the form restricted to the
    # plane (M v) . w = 0: two real lines iff that binary form is indefinite.
    rng = np.random.default_rng(7)
    for _ in range(50):
        q = rng.normal(size=(3, 3))
        m = q + q.T
        for v in FIXED_DIRECTIONS:
            basis = np.linalg.svd((m @ v)[None])[2][1:]
            indefinite = np.linalg.det(basis @ m @ basis.T) < 0
            assert (delta(m, v) > 0) == indefinite


def test_eigen_directions_rescue_the_seed_form():
    a, b, c, d, e, f = (-0.23, 0.49, -0.41, -0.95, 0.78, -0.63)
    m = np.array([[a, b, c], [b, d, e], [c, e, f]])
    assert not (delta(m, FIXED_DIRECTIONS) > 0).any(), "all thirteen fixed directions fail (seed 002)"
    dirs = skeleton_directions(m)
    assert len(dirs) >= 1 and (delta(m, dirs) > 0).all()


def test_newton_converges_on_degenerate_points():
    # Rotated A5: double precision alone fixes it only to ~eps^(1/6).
    expr, shift = rotated("x^6 - y^2 - z^2", 3)
    pts, overflow = singular_points(Surface.parse(expr), np.array(BOX1, float), 7)
    assert not overflow and len(pts) == 1
    assert np.abs(pts[0].point - shift).max() <= 1e-12
    assert pts[0].hessian_rank == 2


def test_gauss_newton_puts_a_node_on_a_symmetry_plane_onto_it_at_once():
    """A start next to Barth's node (-1, 0, 0): the coordinates going to 0
    fall by about eps per step (the rounding of the other residuals) and
    reached 0 by underflow some 20 steps later; now they are 0 once below
    NEWTON_ZERO of the point.  The node is the same (checked against the
    exact node and against the 40-step result), and a node off every
    plane (a float-rotated cone's apex) is left as Newton puts it."""
    from singmesh.skeleton.singular import gauss_newton

    s = Surface.parse("4 (t^2 x^2 - y^2)(t^2 y^2 - z^2)(t^2 z^2 - x^2) - (1 + 2 t)(x^2 + y^2 + z^2 - 1)^2;"
                      " t = (1 + sqrt(5))/2;")
    h = 4 / 256
    starts = np.array([[-1 - h / 2, h / 2, h / 2], [-1 + h / 2, h / 2, -h / 2], [h / 2, 1 - h / 2, -h / 2]])
    want = np.array([[-1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    assert np.array_equal(gauss_newton(s, starts, iterations=6), want)
    assert np.array_equal(gauss_newton(s, starts, iterations=40), want)
    expr, shift = rotated("x^2 + y^2 - z^2", 5)
    cone = Surface.parse(expr)
    x = gauss_newton(cone, np.array([shift]) + 1e-3)
    assert np.abs(x - shift).max() <= 1e-12 and (np.abs(x) > 1e-3).all()


def test_classification_reported():
    m = singmesh.mesh("y x^2 - y^3 - z^2", BOX1)
    (s,) = m.singularities
    assert s.classification.name == "D4" and s.classification.branches == 3 == s.branches


def test_skeleton_nodes_of_the_sphere():
    # F = Fx = Fy = 0 at the poles, and likewise for the other axis pairs.
    m = singmesh.mesh("x^2 + y^2 + z^2 - 1", coarse=8)
    pts = m.skeleton_nodes[np.lexsort(m.skeleton_nodes.T)]
    expected = np.array([[0, 0, -1], [0, -1, 0], [-1, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    expected = expected[np.lexsort(expected.T)]
    assert np.allclose(pts, expected, atol=1e-12)


def test_skeleton_nodes_against_sympy():
    # A tilted ellipsoid: solve F = Fx = Fy = 0 exactly and compare.
    text = "x^2 + 2 y^2 + 3 z^2 + x y - y z - 1"
    expr = Surface.parse(text).expr
    sols = sympy.solve([expr, sympy.diff(expr, X), sympy.diff(expr, Y)], [X, Y, Z], dict=True)
    truth = np.array([[complex(s[v]).real for v in (X, Y, Z)] for s in sols
                      if all(abs(complex(s[v]).imag) < 1e-12 for v in (X, Y, Z))])
    m = singmesh.mesh(text, coarse=8)
    got = m.skeleton_nodes[(m.skeleton_node_axes == [0, 1]).all(axis=1)]
    assert len(got) == len(truth) == 2
    for p in truth:
        assert np.abs(got - p).max(axis=1).min() <= 1e-10


def test_deeper_candidate_search_goes_on_from_the_kept_boxes():
    """The point search (level 8) starts from the boxes the curve search
    (level 6) ended with on the same surface: the same boxes as a search
    from the whole box, on a fresh parse, and each true node is in one."""
    from benchmarks import nodes

    from singmesh.skeleton.singular import candidate_boxes

    text = "4(t^2 x^2-y^2)(t^2 y^2-z^2)(t^2 z^2-x^2) - (1+2t)(x^2+y^2+z^2-1)^2; t = (1+sqrt(5))/2;"
    box = np.array(((-2, 2),) * 3, float)
    fresh = candidate_boxes(Surface.parse(text), box, 7)
    s = Surface.parse(text)
    candidate_boxes(s, box, 5)
    resumed = candidate_boxes(s, box, 7)
    assert np.array_equal(fresh[0], resumed[0]) and np.array_equal(fresh[1], resumed[1])
    lo, hi = resumed
    for p in nodes.true_nodes("barth"):
        assert np.any(np.all((lo <= p + 1e-12) & (p - 1e-12 <= hi), axis=1)), p


@pytest.mark.parametrize("seed", [3, 4])
def test_two_nodes_two_fine_cells_apart_both_have_stars(seed):
    """(u^2 - a^2)^2 + a^2 (v^2 - w^2) in a float rotated frame (15 digits):
    nodes at u = +-a, v = w = 0, here 1.6 and 1.8 fine cells apart at the
    defaults.  Their star cubes overlapped, and one node was no vertex;
    the fine lattice is made finer until they are three cells apart."""
    a, centre = 0.02, np.array([0.1234, -0.2345, 0.0567])
    q, _ = np.linalg.qr(np.random.default_rng(seed).standard_normal((3, 3)))
    u, v, w = sympy.Matrix(q.tolist()) * sympy.Matrix([X - centre[0], Y - centre[1], Z - centre[2]])
    e = sympy.expand((u**2 - a**2) ** 2 + a**2 * (v**2 - w**2))
    text = " + ".join(f"({float(c):.15g})*" + "*".join(f"{s}^{k}" for s, k in zip("xyz", m) if k)
                      if any(m) else f"({float(c):.15g})" for m, c in sympy.Poly(e, X, Y, Z).terms())
    nodes = [centre + sgn * a * q[0] for sgn in (1, -1)]
    box = ((-2, 2),) * 3
    gap = np.abs(nodes[0] - nodes[1]).max() / (4 / 256)
    assert 1.5 < gap < 2  # the case: closer than the stars' reach at fine = 256
    m = singmesh.mesh(text, box)
    assert len(m.singularities) == 2
    f = numpy_f(Surface.parse(text).expr)
    for p in nodes:
        check_singular_mesh(m, p, 2, box, f)
