"""Classification of singular points: ADE type, real form, branches, axis.

Expected values are derived here, independently of the classifier:

* the normalised real form of a normal form comes from brute force over the
  coordinate reflections and permutations and F -> -F (``_orbit``), with
  the representatives the thesis seed names (A_n-- / A_n+-, D_n+- / D_n--,
  E6++ / E6+-, E7++, E8++, and A_n++ for the odd isolated points);
* the number of real branches is counted on a small sphere around the
  point (``count_link_components``: components of the curve F = 0 on a
  triangulated sphere);
* the axes come from the thesis's triangulation vectors of the normal forms;
* the type of a few dozen random rotated normal forms is compared with
  Singular's classify.lib (``quickclass``: type from the Milnor algebra)
  when ``Singular`` is installed (see tests/README_singular.md).
"""

from __future__ import annotations

import dataclasses
import functools
import itertools
import re
import shutil
import subprocess

import numpy as np
import pytest
import sympy as sp
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from singmesh import tolerances
from singmesh.errors import SurfaceError
from singmesh.skeleton.classify import (
    NotSingularError,
    SingularityType,
    classify,
    classify_command,
)
from singmesh.surface import Surface, X, Y, Z

VARS = (X, Y, Z)
PAIRS = {"++": (1, 1), "+-": (1, -1), "-+": (-1, 1), "--": (-1, -1)}


# ----------------------------------------------------------- normal forms
def normal_form(family: str, k: int, a: int, b: int) -> dict:
    """Monomial exponents -> coefficient of the seed's Definition 10."""
    if family == "A":
        return {(k + 1, 0, 0): 1, (0, 2, 0): a, (0, 0, 2): b}
    if family == "D":
        return {(2, 1, 0): 1, (0, k - 1, 0): a, (0, 0, 2): b}
    if k == 6:
        return {(3, 0, 0): 1, (0, 4, 0): a, (0, 0, 2): b}
    if k == 7:
        return {(3, 0, 0): 1, (1, 3, 0): a, (0, 0, 2): b}
    return {(3, 0, 0): 1, (0, 5, 0): a, (0, 0, 2): b}


def as_expr(mono: dict) -> sp.Expr:
    return sum(c * X ** e[0] * Y ** e[1] * Z ** e[2] for e, c in mono.items())


def _transforms():
    """All signed permutations of (x, y, z), times F -> +-F."""
    for perm in itertools.permutations(range(3)):
        for signs in itertools.product((1, -1), repeat=3):
            for overall in (1, -1):
                yield perm, signs, overall


def _apply(mono: dict, perm, signs, overall) -> dict:
    """F(x) -> overall * F(x') with x'_i = signs[i] * x_perm[i]."""
    out = {}
    for e, c in mono.items():
        new = [0, 0, 0]
        for i in range(3):
            new[perm[i]] += e[i]
        sign = overall
        for i in range(3):
            sign *= signs[i] ** e[i]
        out[tuple(new)] = c * sign
    return out


@functools.lru_cache(maxsize=None)
def _orbit(family: str, k: int, a: int, b: int) -> frozenset:
    """Sign pairs whose normal form is a reflected / permuted / negated copy."""
    forms = {p: normal_form(family, k, *v) for p, v in PAIRS.items()}
    start = normal_form(family, k, a, b)
    found = set()
    for t in _transforms():
        image = _apply(start, *t)
        for p, f in forms.items():
            if image == f:
                found.add(p)
    return frozenset(found)


# The representative of each class: the sign pairs the thesis analyses,
# in order of preference (A_n++ stays for the odd isolated points, the only
# class of odd A_n containing neither -- nor +-).
PREFERENCE = {"A": ("--", "+-", "++"), "D": ("--", "+-"), "E": ("++", "+-")}


def expected_real_form(family: str, k: int, a: int, b: int) -> str:
    orbit = _orbit(family, k, a, b)
    for p in PREFERENCE[family]:
        if p in orbit:
            return f"{family}{k}{p}"
    raise AssertionError(f"no representative for {family}{k} {orbit}")


def all_forms():
    for k in range(1, 7):
        for p in PAIRS:
            yield "A", k, p
    for k in range(4, 8):
        for p in PAIRS:
            yield "D", k, p
    for k in (6, 7, 8):
        for p in PAIRS:
            yield "E", k, p


FORMS = list(all_forms())
FORM_IDS = [f"{f}{k}{p}" for f, k, p in FORMS]


def test_orbits_match_the_thesis_equivalences():
    """The brute-force helper reproduces the equivalences the seed states."""
    assert _orbit("D", 4, 1, 1) == {"++", "+-"}
    assert _orbit("D", 4, -1, 1) == {"-+", "--"}
    assert _orbit("D", 5, 1, 1) == {"++", "--"}
    assert _orbit("D", 5, -1, 1) == {"-+", "+-"}
    assert _orbit("E", 6, 1, 1) == {"++", "--"}
    assert _orbit("E", 6, 1, -1) == {"+-", "-+"}
    assert _orbit("E", 7, 1, -1) == set(PAIRS)
    assert _orbit("E", 8, -1, -1) == set(PAIRS)
    for k in (2, 4, 6):
        assert _orbit("A", k, 1, 1) == {"++", "--"}
    for k in (3, 5):
        assert _orbit("A", k, 1, 1) == {"++"}
        assert _orbit("A", k, -1, -1) == {"--"}
    assert _orbit("A", 1, 1, -1) == {"+-", "-+", "--"}


# ------------------------------------------------------ rotated copies
def cayley_rotation(rng) -> sp.Matrix:
    """An exact rational rotation: Cayley transform of a rational skew matrix.

    Halves keep the denominators (4 (1 + a^2 + b^2 + c^2)) small, which keeps
    sympy's expansion of the rotated polynomials fast; the rotations are
    still generic (no entry zero in general).
    """
    a, b, c = (sp.Rational(int(rng.integers(-4, 5)), 2) for _ in range(3))
    A = sp.Matrix([[0, -a, b], [a, 0, -c], [-b, c, 0]])
    eye = sp.eye(3)
    R = (eye - A).inv() * (eye + A)
    assert R.T * R == eye and R.det() == 1
    return R


def float_rotation(rng) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    return q * np.sign(np.diag(r))


def moved(mono: dict, R, shift) -> sp.Expr:
    """F(R^T (x - shift)): the normal form rotated by R and moved to shift.

    Left unexpanded, as a user would type it; the parser expands it.
    """
    u = sp.Matrix(R).T * (sp.Matrix(VARS) - sp.Matrix(shift))
    return as_expr(mono).xreplace(dict(zip(VARS, u)))


def unit_axis(family, k, a, b):
    """Thesis triangulation vector of the normal form (None: no axis).

    Returns (vector, signed): ``signed`` False when the branches lie along
    both +v and -v so that only the line is defined.
    """
    if family != "A":
        return None, False
    if k == 1:
        signs = (1, a, b)
        if abs(sum(signs)) == 3:
            return None, False
        minority = -np.sign(sum(signs))
        return np.eye(3)[signs.index(minority)], False
    if k % 2 == 1:
        if a == b == 1:
            return None, False                  # isolated point
        if a == b == -1:
            return np.array([1.0, 0, 0]), False   # x^(k+1) = y^2 + z^2
        return (np.array([0, 0, 1.0]) if b == -1 else np.array([0, 1.0, 0])), False
    if a == b:
        # x^(k+1) = -a (y^2 + z^2): the half-cone lies where x has sign -a.
        return np.array([-a, 0.0, 0.0]), True
    return np.array([1.0, 0, 0]), False


# --------------------------------------------------- branch counting
@functools.lru_cache(maxsize=None)
def _icosphere(level: int):
    t = (1 + 5 ** 0.5) / 2
    V = np.array([(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
                  (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)], float)
    F = np.array([(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9),
                  (5, 11, 4), (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2),
                  (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10),
                  (8, 6, 7), (9, 8, 1)])
    V /= np.linalg.norm(V, axis=1, keepdims=True)
    for _ in range(level):
        e = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
        uniq, inv = np.unique(e, axis=0, return_inverse=True)
        mid = V[uniq[:, 0]] + V[uniq[:, 1]]
        mid /= np.linalg.norm(mid, axis=1, keepdims=True)
        ids = len(V) + inv.reshape(3, -1)
        ab, bc, ca = ids
        a, b, c = F.T
        V = np.vstack([V, mid])
        F = np.concatenate([np.stack(s, 1) for s in
                            ((a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca))])
    # A fixed generic rotation keeps vertices off the symmetry planes of the
    # normal forms (where F may vanish exactly).
    Q = float_rotation(np.random.default_rng(12345))
    e = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    uniq, inv = np.unique(e, axis=0, return_inverse=True)
    return V @ Q.T, uniq, inv.reshape(3, -1).T


def count_link_components(surface: Surface, center, radius: float, level: int = 6) -> int:
    """Components of {F = 0} on the sphere |x - center| = radius.

    Marching triangles on an icosphere: the crossing edges are the nodes,
    two crossing edges of one triangle are joined.  Zero counts as positive.
    Meant for isolated singular points, whose link is a disjoint union of
    circles; a non-isolated one (two planes) has a singular link that this
    resolves like a perturbed level set.
    """
    V, uniq, tri = _icosphere(level)
    pos = surface(np.asarray(center, float) + radius * V) >= 0
    crossing = pos[uniq[:, 0]] != pos[uniq[:, 1]]
    c = crossing[tri]
    rows = tri[c.sum(axis=1) == 2]
    mask = c[c.sum(axis=1) == 2]
    pairs = rows[mask].reshape(-1, 2)
    n = len(uniq)
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    _, labels = connected_components(graph, directed=False)
    return len(np.unique(labels[crossing]))


def test_branch_counter_on_known_links():
    """The counter itself: cone 2, plane 1, isolated point 0, two disjoint
    cones around the x and y axes 4."""
    assert count_link_components(Surface.parse("x^2 - y^2 - z^2"), (0, 0, 0), 1) == 2
    assert count_link_components(Surface.parse("x^2 + y^2 + z^2"), (0, 0, 0), 1) == 0
    assert count_link_components(Surface.parse("z"), (0, 0, 0), 1) == 1
    two_cones = "(x^2 - 9 y^2 - 9 z^2) (y^2 - 9 x^2 - 9 z^2)"
    assert count_link_components(Surface.parse(two_cones), (0, 0, 0), 1) == 4


# --------------------------------------------------------- the tests
@pytest.mark.parametrize("family,k,p", FORMS, ids=FORM_IDS)
def test_normal_form_at_origin(family, k, p):
    a, b = PAIRS[p]
    mono = normal_form(family, k, a, b)
    s = Surface.parse(as_expr(mono))
    t = classify(s, (0.0, 0.0, 0.0))
    assert t.name == f"{family}{k}"
    assert t.milnor == k
    assert t.real_form == expected_real_form(family, k, a, b)
    assert t.corank == (0 if (family, k) == ("A", 1) else 1 if family == "A" else 2)
    assert t.branches == count_link_components(s, (0, 0, 0), 0.5)


def _check_moved(got: SingularityType, family, k, a, b, rotation, surface=None, center=None):
    if surface is not None:
        assert got.branches == count_link_components(surface, center, 0.5)
    assert got.name == f"{family}{k}"
    assert got.real_form == expected_real_form(family, k, a, b)
    assert got.milnor == k
    axis, signed = unit_axis(family, k, a, b)
    if axis is None:
        assert got.axis is None
    else:
        want = rotation @ axis
        dot = float(np.dot(got.axis, want))
        assert abs(np.linalg.norm(got.axis) - 1) < 1e-9
        assert (dot if signed else abs(dot)) == pytest.approx(1.0, abs=1e-6)


@pytest.mark.parametrize("family,k,p", FORMS, ids=FORM_IDS)
def test_normal_form_rotated_exact(family, k, p):
    """Exact rational rotation (Cayley transform) and rational shift."""
    a, b = PAIRS[p]
    mono = normal_form(family, k, a, b)
    rng = np.random.default_rng(1000 + FORM_IDS.index(f"{family}{k}{p}"))
    R = cayley_rotation(rng)
    shift = [sp.Rational(int(rng.integers(-12, 13)), 5) for _ in range(3)]
    s = Surface.parse(moved(mono, R, shift))
    center = [float(c) for c in shift]
    _check_moved(classify(s, center), family, k, a, b, np.array(R, dtype=float), s, center)


# Every second form, the sign pairs alternating from one k to the next so
# that all four appear (parsing the rotated polynomials dominates run time).
FLOAT_INDEX = [i for i in range(len(FORMS)) if (i + i // 4) % 2 == 0]


@pytest.mark.parametrize("family,k,p", [FORMS[i] for i in FLOAT_INDEX],
                         ids=[FORM_IDS[i] for i in FLOAT_INDEX])
def test_normal_form_rotated_float(family, k, p):
    """Floating-point rotation (QR of a random matrix) and float shift."""
    a, b = PAIRS[p]
    mono = normal_form(family, k, a, b)
    rng = np.random.default_rng(2000 + FORM_IDS.index(f"{family}{k}{p}"))
    R = float_rotation(rng)
    shift = rng.uniform(-2, 2, 3)
    s = Surface.parse(moved(mono, R, shift))
    _check_moved(classify(s, shift), family, k, a, b, R)


CUBICS = [
    # x z + x y^2 + y^3: x z is indefinite, eliminating x, z leaves y^3.
    ("x z + x y^2 + y^3", "A2", "A2+-"),
    # eliminating gives x = z = -y^2, residual -y^4; x z indefinite.
    ("x z + (x+z) y^2", "A3", "A3+-"),
    # on the plane x + y + z = 0 the cubic -x y (x + y) has three real lines.
    ("(x+y+z)^2 + x y z", "D4", "D4--"),
    # x = -z^2/2 leaves y^2 z - z^4/4: normal form signs (-, +), class +-.
    ("x^2 + x z^2 + y^2 z", "D5", "D5+-"),
    # x = -z^2/2 + ... leaves y^3 - z^4/4: signs (-, +), class +-.
    ("x^2 (1-x-y-z) + x z^2 + y^3", "E6", "E6+-"),
]


@pytest.mark.parametrize("text,name,real_form", CUBICS, ids=[c[1] for c in CUBICS])
def test_cubic_surfaces(text, name, real_form):
    s = Surface.parse(text)
    t = classify(s, (0, 0, 0))
    assert (t.name, t.real_form) == (name, real_form)
    # Not too small a sphere: these germs are thin slabs near the point
    # (x^2 + y^3 + ...), which a finite icosphere no longer resolves.
    assert t.branches == count_link_components(s, (0, 0, 0), 0.05)
    assert t.branches == count_link_components(s, (0, 0, 0), 0.1)


def test_cayley_cubic_nodes():
    text = "4(x^2+y^2+z^2) + 16 x y z - 1"
    s = Surface.parse(text)
    F = s.expr
    nodes = sp.solve([F, sp.diff(F, X), sp.diff(F, Y), sp.diff(F, Z)], [X, Y, Z], dict=True)
    nodes = sorted({tuple(n[v] for v in VARS) for n in nodes})
    assert len(nodes) == 4
    for n in nodes:
        assert all(abs(c) == sp.Rational(1, 2) for c in n) and n[0] * n[1] * n[2] < 0
        t = classify(text, [float(c) for c in n])
        assert (t.name, t.real_form, t.corank, t.milnor) == ("A1", "A1--", 0, 1)
        assert t.branches == 2 == count_link_components(s, [float(c) for c in n], 0.05)
        # The cone axis of a Cayley node points to the centre.
        assert abs(np.dot(t.axis, np.array(n, float) / np.linalg.norm(np.array(n, float)))) \
            == pytest.approx(1.0)


HIDDEN = [
    # Normal forms behind a coordinate change x -> x + y^2, where the first
    # non-zero coefficient of a pure power of y is *not* the answer.
    # (x + y^2)^2 + y^5 + z^2: residual y^5, both squares positive.
    ("x^2 + 2 x y^2 + y^4 + y^5 + z^2", "A4--"),
    # y (x + y^2)^2 + c y^6 + z^2: D7 with a = sign(c), b = +1.
    ("x^2 y + 2 x y^3 + y^5 + y^6 + z^2", "D7--"),
    ("x^2 y + 2 x y^3 + y^5 - y^6 + z^2", "D7+-"),
    # y (x + y^2 / 2)^2 - y^5 / 4 + z^2: D6 with a < 0, three half-cones.
    ("x^2 y + x y^3 + z^2", "D6--"),
    # (x + y^2)^3 + y^5 - z^2 (the y^4 and x y^3 terms cancel): E8.
    ("x^3 + 3 x^2 y^2 + 3 x y^4 + y^6 + y^5 - z^2", "E8++"),
]


@pytest.mark.parametrize("text,real_form", HIDDEN, ids=[h[1] for h in HIDDEN])
def test_hidden_normal_forms(text, real_form):
    s = Surface.parse(text)
    t = classify(s, (0, 0, 0))
    assert t.real_form == real_form
    assert t.branches == count_link_components(s, (0, 0, 0), 0.2)


def _newton_singular(s: Surface, p, steps=60):
    """Gauss-Newton on (F, grad F) = 0, with the parser's derivatives only."""
    p = np.asarray(p, float)
    for _ in range(steps):
        g = s.gradient(p)
        J = np.vstack([g, s.hessian(p)])
        r = np.concatenate([[s(p)], g])
        dp = np.linalg.lstsq(J, -r, rcond=None)[0]
        p = p + dp
        if np.linalg.norm(dp) < 1e-15:
            break
    return p


def test_barth_sextic_node():
    s = Surface.parse("4(t^2 x^2-y^2)(t^2 y^2-z^2)(t^2 z^2-x^2) - (1+2t)(x^2+y^2+z^2-1)^2;"
                      " t = (1+sqrt(5))/2;")
    p = _newton_singular(s, (0.97, 1.02, 1.01))
    assert abs(s(p)) < 1e-10 and np.linalg.norm(s.gradient(p)) < 1e-10
    t = classify(s, p)
    assert (t.name, t.real_form, t.milnor) == ("A1", "A1--", 1)
    assert t.branches == count_link_components(s, p, 0.01)


@pytest.mark.parametrize("text", ["x y z", "x^3 + y^3 + z^3 + 2 x y z"])
def test_non_simple_corank_3(text):
    t = classify(text, (0, 0, 0))
    assert t.name == "non-simple" and t.corank == 3
    assert t.milnor is None and t.real_form is None and t.branches is None
    assert t.hessian_signature == (0, 0, 3)
    assert "x y z" in t.jet
    assert "non-simple" in t.describe() and t.jet in t.describe()


@pytest.mark.parametrize("text,corank", [
    ("x^2 y - z^2", 2),          # Whitney umbrella: a line of singular points
    ("x^2 + y^2", 1),            # a line of A1 points (the z-axis)
    ("x^4 + y^4 + z^2", 2),      # X9-type: cubic form zero on the kernel
    ("x^3 + y^6 + z^2", 2),      # J10: cube, no y^4, x y^3, y^5 terms
])
def test_non_simple_corank_1_and_2(text, corank):
    t = classify(text, (0, 0, 0))
    assert t.name == "non-simple" and t.corank == corank and t.milnor is None


def test_point_error_of_1e_12_is_tolerated():
    rng = np.random.default_rng(7)
    mono = normal_form("D", 6, -1, 1)
    R = float_rotation(rng)
    shift = rng.uniform(-1, 1, 3)
    s = Surface.parse(moved(mono, R, shift))
    for _ in range(3):
        t = classify(s, shift + 1e-12 * rng.normal(size=3))
        assert t.real_form == "D6--"


def test_hessian_signature_and_describe():
    t = classify("x^2 - y^2 - z^2", (0, 0, 0))
    assert t.hessian_signature == (1, 2, 0)
    line = t.describe()
    assert line.startswith("A1-- (node)") and "2 real branches" in line and "corank 0" in line
    assert str(t) == line
    with pytest.raises(dataclasses.FrozenInstanceError):
        t.name = "A2"
    assert isinstance(t, SingularityType)
    assert classify(Surface.parse("x^2 - y^2 - z^2"), [0, 0, 0]) == t


def test_not_singular_and_bad_input():
    with pytest.raises(NotSingularError, match="not on the surface"):
        classify("x^2 + y^2 + z^2 - 1", (0, 0, 0))
    with pytest.raises(NotSingularError, match="grad"):
        classify("x^2 + y^2 + z^2 - 1", (1, 0, 0))
    assert issubclass(NotSingularError, SurfaceError)
    with pytest.raises(SurfaceError):
        classify("x^2 + y^2 + z^2", (0, 0))
    with pytest.raises(SurfaceError):
        classify("x^2 + y^2 + z^2", (0, 0, float("nan")))
    with pytest.raises(SurfaceError):
        classify("sin(x) + y", (0, 0, 0))


def test_tolerances_are_in_the_tolerance_module():
    for name in ("CLASSIFY_SINGULAR_RTOL", "CLASSIFY_RANK_RTOL", "CLASSIFY_JET_RTOL",
                 "CLASSIFY_ORDERS"):
        assert hasattr(tolerances, name)


# ------------------------------------------------------------- command
def test_classify_command_prints_lines(capsys):
    code = classify_command(["4(x^2+y^2+z^2) + 16 x y z - 1", "--at", "1/2", "1/2", "-1/2",
                             "--at", "-0.5", "-0.5", "-0.5"])
    out = capsys.readouterr()
    assert code == 0 and out.err == ""
    lines = out.out.strip().splitlines()
    assert len(lines) == 2 and all(line.startswith("A1-- (node)") for line in lines)


def test_classify_command_parameters(capsys):
    assert classify_command(["x^3 + a y^4 + z^2", "--at", "0", "0", "0", "a=-2"]) == 0
    assert capsys.readouterr().out.startswith("E6+-")


@pytest.mark.parametrize("args", [["-x^2+y^2-(z+1/2)^2", "--at", "0", "0", "-1/2"],
                                  ["--at", "0", "0", "-1/2", "-x^2+y^2-a*(z+1/2)^2", "a=1"]])
def test_classify_command_equation_with_a_leading_minus(capsys, args):
    # argparse took "-x^2+..." (no spaces) for an unknown option ("the
    # following arguments are required: equation"); singmesh mesh does not.
    assert classify_command(args) == 0, capsys.readouterr().err
    assert capsys.readouterr().out.startswith("A1-- (node) at (0, 0, -0.5)")


@pytest.mark.parametrize("args,message", [
    (["x^2 + y^2 + z^2 - 1", "--at", "0", "0", "0"], "not a singular point"),
    (["x^2 + y^2 - z^2", "--at", "0", "0", "0", "b=1"], "parameter b is not used"),
    (["x^2 + y^2 - z^2", "--at", "0", "0", "0", "-b"], "name=value, not '-b'"),
    (["x^2 + y^2 + z^2 - 1", "--at", "1", "0", "0"], "grad"),
    (["x^2 + y^2 -", "--at", "0", "0", "0"], "syntax error"),
    (["x^2 + y^2", "--at", "0", "0"], "--at"),
    (["x^2 + y^2"], "--at"),
    (["x^2 + b y^2 - z^2", "--at", "0", "0", "0"], "unknown symbol"),
])
def test_classify_command_errors(capsys, args, message):
    assert classify_command(args) == 2
    out = capsys.readouterr()
    lines = out.err.strip().splitlines()
    assert len(lines) == 1 and message in lines[0]


# ------------------------------------------------------------ Singular
# quickclass prints e.g. "Singularity R-equivalent to :  E[6k+2]=E[8]".
SINGULAR_TYPE = re.compile(r"R-equivalent to\s*:\s*(?:\S+=)?([ADE])\[(\d+)\]")


# Every monomial of this degree or more has weight > 1 for the weights that
# make the normal form quasi-homogeneous of degree 1, so adding one does
# not change the type (semi-quasi-homogeneous germs).
SAFE_DEGREE = {("E", 6): 5, ("E", 7): 5, ("E", 8): 6}


def _safe_degree(family, k):
    if family == "A":
        return k + 2
    if family == "D":
        return k
    return SAFE_DEGREE[(family, k)]


def _singular_cases(n=30):
    rng = np.random.default_rng(2024)
    kinds = [("A", k) for k in range(1, 7)] + [("D", k) for k in range(4, 8)] + \
            [("E", k) for k in (6, 7, 8)]
    cases = []
    for i in range(n):
        family, k = kinds[i % len(kinds)]
        a, b = (int(v) for v in rng.choice([-1, 1], size=2))
        mono = dict(normal_form(family, k, a, b))
        # One extra term above the Newton diagram: same type, less special input.
        d = _safe_degree(family, k)
        i1 = int(rng.integers(0, d + 1))
        i2 = int(rng.integers(0, d - i1 + 1))
        e = (i1, i2, d - i1 - i2)
        mono[e] = mono.get(e, 0) + sp.Rational(int(rng.integers(-5, 6)), 3)
        cases.append((f"{family}{k}", mono, cayley_rotation(rng)))
    return cases


def _singular_text(mono: dict, R: sp.Matrix) -> str:
    """The rotated polynomial in Singular syntax, unexpanded (Singular
    expands it faster than sympy).  Coefficients are written (p/q) in front:
    Singular reads x^3/7 as x^(3/7)."""
    def rational(c):
        c = sp.Rational(c)
        return f"({c.p}/{c.q})"

    forms = []
    for i in range(3):             # u_i = sum_j R[j, i] x_j, i.e. u = R^T x
        forms.append("(" + " + ".join(f"{rational(R[j, i])}*{v}"
                                      for j, v in enumerate("xyz")) + ")")
    terms = []
    for e, c in mono.items():
        factors = [f"{forms[i]}^{e[i]}" for i in range(3) if e[i]]
        terms.append(rational(c) + "*" + "*".join(factors))
    return " + ".join(terms)


def test_against_singular_classify_lib(tmp_path):
    exe = shutil.which("Singular")
    if exe is None:
        pytest.skip("Singular is not on PATH (Debian/Ubuntu: apt-get install singular); "
                    "see tests/README_singular.md")
    cases = _singular_cases()
    script = ['LIB "classify.lib";', "ring r = 0,(x,y,z),ds;", "poly f;"]
    for i, (_, mono, R) in enumerate(cases):
        text = _singular_text(mono, R)
        script += [f"f = {text};", f'print("@@BEGIN {i}");', "quickclass(f);",
                   f'print("@@END {i}");']
    script.append("quit;")
    # classify.lib writes its normal-form database (NFlist.dir/.pag) into
    # the working directory: keep it out of the repository.
    run = subprocess.run([exe, "-q"], input="\n".join(script), capture_output=True,
                         text=True, timeout=120, cwd=tmp_path)
    blocks = re.findall(r"@@BEGIN (\d+)(.*?)@@END \1", run.stdout, flags=re.S)
    assert len(blocks) == len(cases), run.stdout[-2000:] + run.stderr[-2000:]
    for (index, block), (name, mono, R) in zip(blocks, cases):
        m = SINGULAR_TYPE.search(block)
        assert m, block
        singular_name = m.group(1) + m.group(2)
        assert singular_name == name            # the construction is what we think
        t = classify(Surface.parse(moved(mono, R, (0, 0, 0))), (0, 0, 0))
        assert t.name == singular_name, (mono, R, t.describe())
        assert t.milnor == int(m.group(2))
