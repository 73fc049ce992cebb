"""The fast paths of issue #11 against the plain computations they replace.

Each shortcut (face modes on a subset of rows, face links without the
squares inside a star, the zero lattice points read on the lines along x,
a polygon's farthest vertex without a sort, sorted vertex triples without
np.sort) must give what the straightforward computation gives, bit for
bit, on inputs as users give them (float coefficients, a float-rotated
surface, lattice points on the surface).
"""

from __future__ import annotations

import numpy as np
import pytest

import singmesh
from singmesh import tolerances as tol
from singmesh.boxes import edges as edges_mod
from singmesh.boxes import faces as faces_mod
from singmesh.boxes.edges import compute_events
from singmesh.boxes.faces import face_links
from singmesh.boxes.octree import KeptRows, StackedRows, subdivide
from singmesh.boxes import polynomial_lines
from singmesh.facets.assemble import _last_max
from singmesh.facets.flips import area_and_longest
from singmesh.facets.triangulate import (_choose_template, _combos, _template_combos, _template_quality, _triple_keys,
                                        polygon_triangulations, triangle_quality)
from singmesh.skeleton.centre import residual, residual_each
from singmesh.surface import Surface

from test_rounded import float_rotated

BOX = np.array([[-1.0, 1.0]] * 3)


def _surfaces():
    return [
        Surface.parse("4(x^2+y^2+z^2) + 16 x y z - 1"),          # Cayley: nodes
        Surface.parse("x^2 - y^2 z"),                             # zeros along lattice lines
        Surface.parse(float_rotated("x^2 + y^2 - z^2 + 0.3 x y z", 7)[0]),
        Surface.parse("max(abs(x), abs(y), abs(z)) - 0.5"),       # intervals, corners on the lattice
    ]


@pytest.fixture(scope="module", params=range(4), ids=["cayley", "whitney", "rotated cone", "cube"])
def tree_of(request):
    surface = _surfaces()[request.param]
    return surface, subdivide(surface, BOX, 3, 5)


def test_face_modes_on_rows_are_the_rows_of_all(tree_of):
    surface, tree = tree_of
    rng = np.random.default_rng(1)
    rows = np.sort(rng.choice(len(tree.level), size=len(tree.level) // 2, replace=False))
    for n in range(3):
        side = rng.integers(0, 2, len(rows))
        full = np.full(len(tree.level), 0, np.int64)
        full[rows] = side
        want = surface.face_modes(tree.data, n, full)[rows]
        assert np.array_equal(surface.face_modes(tree.data, n, side, rows=rows), want)


def test_links_without_inner_squares_are_the_others(tree_of):
    """Leaves grouped in blocks: the links given the groups are those of the squares between blocks."""
    surface, tree = tree_of
    events = compute_events(surface, tree)
    everything = face_links(surface, tree, events)
    block = tree.corner // 8  # lattice blocks of 8 fine cells: leaves in one share an id
    _, group = np.unique(block, axis=0, return_inverse=True)
    group = group.ravel().astype(np.int64) + len(tree.level)
    fewer = face_links(surface, tree, events, group=group)
    m, p = everything.minus, everything.plus
    inner = (m >= 0) & (p >= 0) & (group[np.maximum(m, 0)] == group[np.maximum(p, 0)])
    assert inner.any() and (~inner).any()
    assert np.array_equal(fewer.square, everything.square[~inner])
    assert np.array_equal(fewer.minus, m[~inner]) and np.array_equal(fewer.plus, p[~inner])
    kept = ~inner[everything.link_square]
    old_to_new = np.cumsum(~inner) - 1
    assert np.array_equal(fewer.link_square, old_to_new[everything.link_square[kept]])
    assert np.array_equal(fewer.start, everything.start[kept])
    assert np.array_equal(fewer.end, everything.end[kept])
    assert np.array_equal(fewer.ambiguous, everything.ambiguous[~inner])


def test_links_read_graph_axes_only_where_they_pair(tree_of, monkeypatch):
    """Links for tubes read the graph axes of the squares with events; without tubes, only of
    those with more than two, and only the squares with events are kept: the links of reading
    every square's axis on every square, and its ``ambiguous`` flags on the squares read."""
    surface, tree = tree_of
    events = compute_events(surface, tree)
    fast = {tubes: face_links(surface, tree, events, tubes=tubes) for tubes in (True, False)}
    plain = faces_mod.graph_modes
    monkeypatch.setattr(faces_mod, "graph_modes", lambda *args, which=None: plain(*args))
    every = face_links(surface, tree, events)
    counts = np.bincount(every.link_square, minlength=len(every.square))  # links per square
    assert (counts == 1).any() and (counts == 0).any()
    for tubes, links in fast.items():
        kept = np.ones(len(counts), bool) if tubes else counts > 0
        for name in ("square", "minus", "plus", "inconsistent"):
            assert np.array_equal(getattr(links, name), getattr(every, name)[kept]), name
        assert np.array_equal(links.link_square, (np.cumsum(kept) - 1)[every.link_square])
        assert np.array_equal(links.start, every.start) and np.array_equal(links.end, every.end)
        read = counts >= (1 if tubes else 2)
        assert np.array_equal(links.ambiguous, (every.ambiguous & (read | every.inconsistent))[kept])


def test_kept_rows_read_as_the_concatenation(tree_of):
    """A refined tree's data (kept rows of the first tree's and new ones) reads as their copy."""
    surface, tree = tree_of
    rng = np.random.default_rng(3)
    keep = rng.random(len(tree.level)) < 0.7
    more = [surface.split(tree.data[:3]).reshape((-1,) + tree.data.shape[1:]), tree.data[5:9]]
    want = np.concatenate([tree.data[keep]] + more)
    kept = KeptRows(tree.data, keep, more)
    assert len(kept) == len(want) and kept.shape == want.shape
    rows = rng.choice(len(want), size=40)
    rows[:3] = [0, len(want) - 1, -1]
    side = rng.integers(0, 2, len(rows))
    for n in range(3):
        assert np.array_equal(surface.face_modes(kept, n, side, rows=rows), surface.face_modes(want, n, side, rows=rows))
        if want.ndim == 4:  # Bernstein tensors: the face slices as face_modes takes them
            index = [rows, slice(None), slice(None), slice(None)]
            index[1 + n] = np.where(side == 1, want.shape[1 + n] - 1, 0)
            assert np.array_equal(kept[tuple(index)], want[tuple(index)])
    assert np.array_equal(kept[rows], want[rows]) and np.array_equal(kept[list(rows)], want[list(rows)])
    mask = rng.random(len(want)) < 0.5
    assert np.array_equal(kept[mask], want[mask]) and np.array_equal(kept[2:7], want[2:7])
    assert np.array_equal(np.asarray(kept), want) and np.array_equal(kept[rows], want[rows])


def _zero_points_by_unique(surface, tree, corners, uniq):
    """The zero lattice points as read before: F once per distinct lattice point (np.unique)."""
    xyz = edges_mod._corner_xyz(corners)
    b = tol.MAX_LEVEL + 1
    packed = (xyz[:, 0] << (2 * b)) | (xyz[:, 1] << b) | xyz[:, 2]
    distinct, inverse = np.unique(packed, return_inverse=True)
    zero = surface.is_zero(tree.lattice_to_space(edges_mod._unpack(distinct, 3, b)))[inverse.ravel()]
    xyz, a = xyz[zero], corners[zero, 0]
    r = np.arange(len(a))
    return np.searchsorted(uniq, edges_mod.line_keys(a, xyz[r, (a + 1) % 3], xyz[r, (a + 2) % 3])), xyz[r, a]


def test_zero_lattice_points_as_by_unique(tree_of, monkeypatch):
    surface, tree = tree_of
    seen = []

    def both(surface, tree, corners, uniq):
        got = fast(surface, tree, corners, uniq)
        want = _zero_points_by_unique(surface, tree, corners, uniq)
        seen.append(len(want[0]))
        assert np.array_equal(got[0], want[0]) and np.array_equal(got[1], want[1])
        return got

    fast = edges_mod._zero_lattice_points
    monkeypatch.setattr(edges_mod, "_zero_lattice_points", both)
    compute_events(surface, tree)
    assert seen


def test_zero_lattice_points_are_the_exact_zeros(monkeypatch):
    """x^2 - y^2 z at the leaf corners (dyadic, so F is exact in floats): the
    (line, position) pairs read are the corners where F is 0, on every line."""
    surface = Surface.parse("x^2 - y^2 z")
    tree = subdivide(surface, BOX, 3, 5)
    seen = []

    def spy(surface, tree, corners, uniq):
        out = fast(surface, tree, corners, uniq)
        seen.append((corners, uniq, out))
        return out

    fast = edges_mod._zero_lattice_points
    monkeypatch.setattr(edges_mod, "_zero_lattice_points", spy)
    compute_events(surface, tree)
    (corners, uniq, (line, pos)), = seen
    a, u, v, s = corners.T
    xyz = np.zeros((len(a), 3))
    r = np.arange(len(a))
    xyz[r, a], xyz[r, (a + 1) % 3], xyz[r, (a + 2) % 3] = s, u, v
    x, y, z = (BOX[:, 0] + xyz * (BOX[:, 1] - BOX[:, 0]) / 32).T
    exact = x * x - y * y * z == 0
    assert exact.sum() > 100
    want = np.searchsorted(uniq, edges_mod.line_keys(a[exact], u[exact], v[exact])) * 64 + s[exact]
    assert np.array_equal(np.sort(line * 64 + pos), np.sort(want))


def test_last_max_is_the_sorts_last():
    rng = np.random.default_rng(3)
    for _ in range(200):
        sizes = rng.integers(1, 7, rng.integers(1, 30))
        offsets = np.concatenate([[0], np.cumsum(sizes)])
        poly_of = np.repeat(np.arange(len(sizes)), sizes)
        values = rng.integers(0, 4, offsets[-1]).astype(float) * 0.1
        values[rng.random(len(values)) < 0.1] = np.nan
        want = np.zeros(len(sizes), np.int64)
        order = np.lexsort((values, poly_of))
        want[poly_of[order]] = order
        assert np.array_equal(_last_max(values, offsets, poly_of), want)


def test_triple_keys_of_sorted_triples():
    rng = np.random.default_rng(4)
    tri = rng.integers(0, 1000, (5000, 3))
    tri[::7, 1] = tri[::7, 0]
    t = np.sort(tri, axis=1)
    assert np.array_equal(_triple_keys(tri, 1000), (t[:, 0] << 42) | (t[:, 1] << 21) | t[:, 2])


def _row_quality(p, normal):
    """Smallest angle of triangles (..., 3, 3) from rows of 3 (norm, einsum, cross), -1 facing away."""
    e0, e1, e2 = p[..., 1, :] - p[..., 0, :], p[..., 2, :] - p[..., 1, :], p[..., 0, :] - p[..., 2, :]
    n0, n1, n2 = (np.linalg.norm(e, axis=-1) for e in (e0, e1, e2))

    def angle(a, b, na, nb):
        return np.arccos(np.clip(np.einsum("...i,...i->...", a, b) / np.maximum(na * nb, 1e-300), -1.0, 1.0))

    ang = np.minimum(np.minimum(angle(e0, -e2, n0, n2), angle(e1, -e0, n1, n0)), angle(e2, -e1, n2, n1))
    cross = np.cross(e0, -e2)
    facing = np.einsum("...i,...i->...", cross, normal)
    # Flat (what assemble drops): below facing away.
    flat = np.linalg.norm(cross, axis=-1) <= 1e-12 * np.maximum(np.maximum(n0 * n0, n1 * n1), n2 * n2)
    return np.where(flat, -1.5, np.where(facing > 0, ang, -1.0))


@pytest.mark.parametrize("n", [4, 5, 6, 8])
def test_template_quality_per_coordinate_is_the_rows(n):
    """The triangle qualities written per coordinate are those of rows of 3, bit for bit: on
    float points, slivers (corners 1e-12 apart), triangles facing away and repeated corners."""
    rng = np.random.default_rng(n)
    points = rng.normal(size=(400, 3)) @ np.linalg.qr(rng.normal(size=(3, 3)))[0]
    points[::5] = points[1::5] + 1e-12 * rng.normal(size=points[1::5].shape)
    normals = rng.normal(size=(400, 3))
    poly = rng.integers(0, 400, (300, n))
    poly[::9, 1] = poly[::9, 0]
    combos = _combos(n)
    want = _row_quality(points[poly[:, combos]], normals[poly].sum(axis=1)[:, None, :])
    got = _template_quality(poly, points, normals)
    assert (want == -1.0).any() and (want > 0).any() and (want == -1.5).any()
    assert np.array_equal(got.view(np.int64), want.view(np.int64))
    p = points[poly[:, :3]]
    assert np.array_equal(triangle_quality(p, normals[:300]).view(np.int64),
                          _row_quality(p, normals[:300]).view(np.int64))


def test_area_and_longest_per_coordinate_are_the_rows():
    """Doubled areas and longest sides written per coordinate are those of norm, cross and sum
    over rows of 3, bit for bit (float points, slivers, repeated corners)."""
    rng = np.random.default_rng(5)
    vertices = rng.normal(size=(500, 3)) @ np.linalg.qr(rng.normal(size=(3, 3)))[0]
    vertices[::4] = vertices[1::4] + 1e-13 * rng.normal(size=vertices[1::4].shape)
    faces = rng.integers(0, 500, (2000, 3))
    faces[::11, 2] = faces[::11, 0]
    p = vertices[faces]
    area2 = np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    longest = np.max([np.sum((p[:, i] - p[:, (i + 1) % 3]) ** 2, axis=1) for i in range(3)], axis=0)
    got_area, got_longest = area_and_longest(vertices, faces)
    assert (area2 == 0).any()
    assert np.array_equal(got_area.view(np.int64), area2.view(np.int64))
    assert np.array_equal(got_longest.view(np.int64), longest.view(np.int64))


def _line_polynomials(rng, count):
    """Polynomials in tau of degree 1..6 with roots where they are hard to tell apart: near +-1,
    near-double, complex pairs 1e-9..1e-3 off the axis (about ROOT_IMAG), tiny leading terms."""
    out = []
    for _ in range(count):
        n = int(rng.integers(1, 7))
        roots = rng.uniform(-1.6, 1.6, n).astype(complex)
        kind = rng.random()
        if kind < 0.25 and n >= 2:
            roots[1] = np.conj(roots[0]) if roots[0].imag else roots[0] + 10 ** rng.uniform(-12, -4)
        if 0.25 <= kind < 0.5 and n >= 2:
            roots[0] = roots[0].real + 1j * 10 ** rng.uniform(-9, -3)
            roots[1] = np.conj(roots[0])
        if 0.5 <= kind < 0.6:
            roots[0] = rng.choice([-1.0, 1.0]) * (1 + rng.choice([0.0, 1e-15, -1e-15, 1e-9]))
        c = np.real(np.polynomial.polynomial.polyfromroots(roots)) * 10 ** rng.uniform(-6, 6)
        if rng.random() < 0.1:
            c[-1] *= 1e-11
        out.append(np.concatenate([c, np.zeros(7 - len(c))]))
    return np.array(out)


def test_line_roots_without_root_free_lines_are_all_roots(monkeypatch):
    """Lines proven free of roots to keep (Bernstein hulls on pieces of the segment) skip the
    eigenvalues: the roots are those of all lines' eigenvalues, bit for bit, on hard polynomials
    and on the lines of a float-rotated surface."""
    rng = np.random.default_rng(6)
    polys = [_line_polynomials(rng, 3000)]
    surface = Surface.parse(float_rotated("x^2 + y^2 - z^2 + 0.3 x y z", 7)[0])
    tree = subdivide(surface, BOX, 3, 5)
    cap = []
    real = polynomial_lines.real_roots
    monkeypatch.setattr(polynomial_lines, "real_roots", lambda p, b, **kw: cap.append(p) or real(p, b, **kw))
    compute_events(surface, tree)
    monkeypatch.setattr(polynomial_lines, "real_roots", real)
    polys += cap
    skipped = 0
    for p in polys:
        got = real(p, 1.0)
        skipped += sum(int(polynomial_lines._far_from_zero(p[np.abs(p[:, d]) > 0, :d + 1]).sum()) for d in range(3, p.shape[1]))
        with monkeypatch.context() as m:
            m.setattr(polynomial_lines, "_far_from_zero", lambda q: np.zeros(len(q), bool))
            want = real(p, 1.0)
        assert np.array_equal(got[0], want[0]) and np.array_equal(got[1].view(np.int64), want[1].view(np.int64))
    assert skipped > 100


def test_newton_polish_stops_at_fixed_points():
    """real_roots' Newton polish on the roots still moving only gives the roots of all
    NEWTON_ITERATIONS steps on all of them, bit for bit."""
    rng = np.random.default_rng(7)
    polys = _line_polynomials(rng, 2000)
    row, root = polynomial_lines.real_roots(polys, 1.0)
    # The same eigenvalues, polished the plain way.
    seen = []
    orig = polynomial_lines._horner
    try:
        polynomial_lines._horner = lambda c, t: seen.append(len(t)) or orig(c, t)
        polynomial_lines.real_roots(polys, 1.0)
    finally:
        polynomial_lines._horner = orig
    assert len(seen) < 2 * tol.NEWTON_ITERATIONS or min(seen) < max(seen)  # the shortcut is taken
    start = _eigen_roots(polys, row)
    coeffs = polys[row]
    for _ in range(tol.NEWTON_ITERATIONS):
        p, dp = orig(coeffs, start)
        ok = np.abs(dp) > 0
        trial = start - np.where(ok, p / np.where(ok, dp, 1.0), 0.0)
        start = np.where(np.abs(orig(coeffs, trial)[0]) <= np.abs(p), trial, start)
    assert np.array_equal(root.view(np.int64), start.view(np.int64))


def _eigen_roots(polys, row):
    """The unpolished roots real_roots starts from, in its order (rows ``row``)."""
    orig = polynomial_lines._horner
    starts = []

    def first(c, t):
        if not starts:
            starts.append(t.copy())
        return orig(c, t)
    try:
        polynomial_lines._horner = first
        polynomial_lines.real_roots(polys, 1.0)
    finally:
        polynomial_lines._horner = orig
    assert len(starts[0]) == len(row)
    return starts[0]


def _plain_jet(T, tol, order):
    """The jet text term by term (the loop over monomials _format_jet's table replaces)."""
    terms = []
    for total in range(2, order + 1):
        for i in range(total, -1, -1):
            for j in range(total - i, -1, -1):
                k = total - i - j
                if max(i, j, k) >= T.shape[0] or abs(float(T[i, j, k])) <= tol:
                    continue
                c = float(T[i, j, k])
                mono = " ".join(v if e == 1 else f"{v}^{e}" for v, e in (("x", i), ("y", j), ("z", k)) if e)
                terms.append(("-" if c < 0 else "+", ("" if abs(abs(c) - 1.0) <= 1e-9 else f"{abs(c):.6g} ") + mono))
    if not terms:
        return "0"
    return ("-" if terms[0][0] == "-" else "") + terms[0][1] + "".join(f" {s} {t}" for s, t in terms[1:])


def test_jet_text_and_hessian_from_tables():
    """classify's jet text and Hessian read through index tables: as term by term."""
    from singmesh.skeleton import classify

    rng = np.random.default_rng(8)
    for n in (1, 2, 3, 4, 7):
        for _ in range(100):
            T = rng.normal(size=(n, n, n)) * (rng.random((n, n, n)) < 0.5)
            T[rng.random((n, n, n)) < 0.1] = rng.choice([-1.0, 1.0])
            for order in (2, 3, 4):
                assert classify._format_jet(T, 0.3, order) == _plain_jet(T, 0.3, order)
            if n >= 3:
                want = [[T[tuple(np.eye(3, dtype=int)[a] + np.eye(3, dtype=int)[b])] * (2.0 if a == b else 1.0)
                         for b in range(3)] for a in range(3)]
                assert np.array_equal(T[classify._HESSIAN_INDEX] * classify._HESSIAN_FACTOR, np.array(want))


def test_face_modes_with_faces_along_rows_are_the_sign_tests():
    """face_modes' sign tests on faces laid along the last axis: those of bernstein.sign_definite on each
    face's differences (exact zeros, constant rows, NaN, a variable of degree 0)."""
    from singmesh.boxes.bernstein import sign_definite
    from singmesh.boxes.polynomial_bounds import face_modes

    rng = np.random.default_rng(9)
    for shape in [(400, 4, 4, 4), (400, 3, 1, 3), (400, 2, 2, 2)]:
        t = np.round(rng.normal(size=shape), 1)
        t[::5] = np.cumsum(np.abs(t[::5]), axis=2)          # monotone along z
        t[1::7] = 0.0
        t[2::11, 0, 0, 0] = np.nan
        for n in range(3):
            side = rng.integers(0, 2, len(t))
            face = np.stack([np.take(t[i], -side[i], axis=n) for i in range(len(t))])
            if n == 1:
                face = np.swapaxes(face, 1, 2)
            over_u = sign_definite(np.diff(face, axis=2), (1, 2))
            over_v = sign_definite(np.diff(face, axis=1), (1, 2))
            want = np.where(over_u, 0, np.where(over_v, 1, 2))
            assert np.array_equal(face_modes(t, n, side), want)


def test_rescaled_line_polynomials_with_each_power_once():
    """_rescale reads centre^(i - j) from one table of powers per centre: the coefficients are
    those of a power per (i, j), bit for bit (centres 0, negative, 15-digit decimals)."""
    from scipy.special import comb

    rng = np.random.default_rng(10)
    for n in range(0, 7):
        poly = rng.normal(size=(500, n + 1))
        centre = np.round(rng.uniform(-3, 3, 500), 15)
        centre[::5] = 0.0
        half = rng.uniform(0.01, 1, 500)
        i, j = np.arange(n + 1)[None, :, None], np.arange(n + 1)[None, None, :]
        m = np.where(i >= j, comb(i, j) * centre[:, None, None] ** np.maximum(i - j, 0), 0.0)
        want = np.einsum("li,lij->lj", poly, m) * half[:, None] ** np.arange(n + 1)
        assert np.array_equal(polynomial_lines._rescale(poly, centre, half).view(np.int64), want.view(np.int64))


def test_side_signs_read_each_midpoint_once(tree_of, monkeypatch):
    """The signs left and right of every root, F read once per midpoint between two roots:
    those of the two plain evaluations (left samples, right samples), on the surfaces' own roots."""
    surface, tree = tree_of
    seen = {}
    real = edges_mod._events_from_roots

    def grab(surface, tree, lines, uniq, line_of, pos, snap):
        seen.update(lines=lines, line_of=line_of, pos=pos)
        return real(surface, tree, lines, uniq, line_of, pos, snap)
    monkeypatch.setattr(edges_mod, "_events_from_roots", grab)
    compute_events(surface, tree)
    lines, line_of, pos = seen["lines"], seen["line_of"], seen["pos"]
    assert len(pos) > 10 and (line_of[1:] == line_of[:-1]).any()
    same_prev = np.concatenate([[False], line_of[1:] == line_of[:-1]])
    same_next = np.concatenate([line_of[:-1] == line_of[1:], [False]])
    prev = np.where(same_prev, np.roll(pos, 1), pos - 1.0)
    nxt = np.where(same_next, np.roll(pos, -1), pos + 1.0)
    want_left = edges_mod._signs(surface, tree, lines[line_of], (pos + prev) / 2)
    want_right = edges_mod._signs(surface, tree, lines[line_of], (pos + nxt) / 2)
    left, right = edges_mod._side_signs(surface, tree, lines, line_of, pos)
    assert np.array_equal(left, want_left) and np.array_equal(right, want_right)
    empty = edges_mod._side_signs(surface, tree, lines, line_of[:0], pos[:0])
    assert len(empty[0]) == 0 and len(empty[1]) == 0


def test_is_zero_skips_the_term_sizes_only_where_no_value_is_small():
    """A polynomial's is_zero reads the sum of |terms| only when some |F| is under its bound: the
    answer is Surface.is_zero's, with zeros at lattice points, near-zeros and none."""
    from singmesh.surface import Surface as Base

    rng = np.random.default_rng(11)
    for text in ["4(x^2+y^2+z^2) + 16 x y z - 1", "x^2 - y^2 z", float_rotated("x^2 + y^2 - z^2 + 0.3 x y z", 7)[0],
                 "x^4-5x^2+y^4-5y^2+z^4-5z^2+11.8"]:
        s = Surface.parse(text)
        lattice = np.stack(np.meshgrid(*[np.linspace(-2, 2, 17)] * 3, indexing="ij"), -1).reshape(-1, 3)
        for pts in [lattice, rng.uniform(-3, 3, (500, 3)), lattice[:1], np.zeros((0, 3)), np.array([[0.0, 0.0, 0.0], [0.5, 0.5, -0.5]])]:
            assert np.array_equal(s.is_zero(pts), Base.is_zero(s, pts))
    cayley = Surface.parse("4(x^2+y^2+z^2) + 16 x y z - 1")
    assert cayley.is_zero(np.array([[0.5, 0.5, -0.5], [0.5, 0.5, 0.5]])).tolist() == [True, False]
    # On the sphere to rounding: |F| of an ulp or two, not 0, and zero to is_zero.
    sphere = Surface.parse("x^2 + y^2 + z^2 - 1")
    on = rng.normal(size=(300, 3))
    on /= np.linalg.norm(on, axis=1)[:, None]
    on = on[sphere(on) != 0]
    assert len(on) > 50 and sphere.is_zero(on).all()


@pytest.mark.parametrize("n", [4, 5, 6, 8])
def test_best_template_by_columns_is_by_rows(n):
    """The template whose worst triangle is best, its worst read column by column: the choice of
    q[:, templates].min(axis=2) and argmax (ties, -1 and -2 qualities, NaN)."""
    rng = np.random.default_rng(12 + n)
    poly = rng.integers(0, 1000, (500, n))
    q = np.round(rng.random((500, len(_combos(n)))), 1)
    q[rng.random(q.shape) < 0.05] = -1.0
    q[::17, 0] = np.nan
    best = np.argmax(q[:, _template_combos(n)].min(axis=2), axis=1)
    tri = polygon_triangulations(n)[best]
    want = np.take_along_axis(poly[:, None, :], tri.reshape(len(poly), -1)[:, None, :], axis=2).reshape(-1, 3)
    assert np.array_equal(_choose_template(poly, q), want)


def test_faces_without_loops_along_rows_are_the_sign_tests():
    """face_without_loops with the faces laid along the last axis: the plain tests per face
    (tangential differences of one sign, or no sign change), with ties, NaN, a side of one
    coefficient and no face at all."""
    from singmesh.boxes.bernstein import sign_definite
    from singmesh.boxes.polynomial_bounds import face_without_loops

    rng = np.random.default_rng(14)
    for shape in [(600, 5, 5), (600, 3, 1), (600, 2, 2), (0, 4, 4)]:
        face = np.round(rng.normal(size=shape), 1)
        face[::4] = np.abs(face[::4])
        face[1::6] = np.cumsum(np.abs(face[1::6]), axis=1)
        if len(face):
            face[2::9, 0, 0] = np.nan
        want = (sign_definite(np.diff(face, axis=1), (1, 2)) | sign_definite(np.diff(face, axis=2), (1, 2))
                | (face.min(axis=(1, 2), initial=np.inf) >= 0) | (face.max(axis=(1, 2), initial=-np.inf) < 0))
        assert np.array_equal(face_without_loops(face), want)


def _point_cloud(seed: int) -> np.ndarray:
    # Points as the per-point calls meet them: general position at several
    # scales, with coordinates exactly 0 and -0 (a point on a split plane).
    rng = np.random.default_rng(seed)
    p = np.concatenate([rng.normal(size=(40, 3)) * s for s in (1e-3, 0.5, 2.0)])
    p[::7, 0] = 0.0
    p[::5, 2] = -0.0
    p[::11] = 0.0
    return p


@pytest.mark.parametrize("text", ["4(x^2+y^2+z^2) + 16 x y z - 1", float_rotated("x^2 + y^2 - z^2 + 0.3 x y z", 7)[0],
                                  "x y z + 0.123456789012345 x^3 - 0.3 y^5 z^2 + 1.5 z^6"])
def test_each_point_alone_in_one_call(text):
    # hessian_each, taylor_each and magnitudes_each give every point the
    # bits of hessian(), taylor(), magnitude() and gradient_magnitude()
    # called at that point alone (one BLAS row is not a row of a batch).
    s = Surface.parse(text)
    pts = _point_cloud(3)
    hess = s.hessian_each(pts)
    taylor = s.taylor_each(pts)
    mag, gmag = s.magnitudes_each(pts)
    val, grad = s.value_gradient_each(pts)
    alone = s.magnitude_each(pts)
    res = residual_each(s, pts)
    for k, p in enumerate(pts):
        f, g = s.value_gradient(p)
        assert val[k].tobytes() == np.asarray(f, float).tobytes() and grad[k].tobytes() == g.tobytes()
        assert alone[k].tobytes() == np.asarray(s.magnitude(p), float).tobytes()
        assert res[k].tobytes() == np.asarray(residual(s, p), float).tobytes()
        assert hess[k].tobytes() == s.hessian(p).tobytes()
        assert taylor[k].tobytes() == s.taylor(p).tobytes()
        assert mag[k].tobytes() == np.asarray(s.magnitude(p), float).tobytes()
        assert gmag[k].tobytes() == s.gradient_magnitude(p).tobytes()


def test_analyse_each_is_analyse_per_point():
    # At the nodes of Cayley's cubic (float-rotated: 15-digit input) and at
    # points that are not singular: the same types and frames, the same
    # refusals.
    from singmesh.skeleton.classify import analyse, analyse_each

    text, _ = float_rotated("4(x^2+y^2+z^2) + 16 x y z - 1", 5)
    s = Surface.parse(text)
    from singmesh.skeleton.singular import singular_points

    nodes = np.array([sp.point for sp in singular_points(s, BOX * 1.5)[0]])
    assert len(nodes) == 4
    pts = np.concatenate([nodes, [[0.3, 0.2, 0.1]]])
    got = analyse_each(s, pts)
    for p, g in zip(pts, got):
        try:
            want = analyse(s, p)
        except Exception as e:
            assert type(g) is type(e) and str(g) == str(e)
            continue
        assert g[0] == want[0]
        assert g[1].basis.tobytes() == want[1].basis.tobytes()
        assert g[1].eigenvalues.tobytes() == want[1].eigenvalues.tobytes()
    assert isinstance(got[-1], Exception)


@pytest.mark.parametrize("where", ["taylor_each", "analyse"])
def test_analyse_each_lets_a_time_limit_through(where, monkeypatch):
    # The gallery's time limit is an alarm that raises TimeoutError wherever
    # the work is: in the batch it was kept as a point's answer (or, from
    # the batched jets, dropped), and the entry ran on past its limit.
    import singmesh.skeleton.classify as classify

    s = Surface.parse("4(x^2+y^2+z^2) + 16 x y z - 1")

    def alarm(*args, **kwargs):
        raise TimeoutError("time limit")

    if where == "taylor_each":
        monkeypatch.setattr(type(s), "taylor_each", alarm)
    else:
        monkeypatch.setattr(classify, "analyse", alarm)
    with pytest.raises(TimeoutError):
        classify.analyse_each(s, np.array([[0.5, 0.5, -0.5], [0.3, 0.2, 0.1]]))


def test_relation_of_boxes_and_regions_is_the_full_table():
    # Boxes of one level against regions (cubes round points, some on
    # lattice planes, so that boxes touch them exactly): the lattice lookup
    # (or the k-d tree, for regions spanning many boxes) finds what the
    # (boxes x regions) table of closed-box tests finds.
    from singmesh.boxes.octree import _near_pairs, _relation

    rng = np.random.default_rng(5)
    lattice_path = 0
    for _ in range(120):
        fine = int(rng.integers(4, 9))
        level = int(rng.integers(2, fine + 1))
        box = np.sort(rng.uniform(-3, 3, size=(3, 2)), axis=1)
        size = 1 << (fine - level)
        index = np.unique(rng.integers(0, 1 << level, size=(int(rng.integers(1, 400)), 3)), axis=0)
        cell = (box[:, 1] - box[:, 0]) / (1 << fine)
        k = int(rng.integers(1, 40))
        pts = box[:, 0] + rng.uniform(0, 1, size=(k, 3)) * (box[:, 1] - box[:, 0])
        snap = rng.random(k) < 0.4
        pts[snap] = box[:, 0] + np.round((pts[snap] - box[:, 0]) / cell) * cell
        half = cell * rng.integers(1, 4, size=(k, 1))
        regions = np.stack([pts - half, pts + half], axis=1)
        meets, inside = _relation(box, fine, level, index * size, regions)
        lo = box[:, 0] + index * size * cell
        hi = lo + size * cell
        pad = 1e-9 * size * cell
        lo, hi, r_lo, r_hi = lo[:, None], hi[:, None], regions[None, :, 0], regions[None, :, 1]
        assert np.array_equal(meets, ((lo - pad <= r_hi) & (hi + pad >= r_lo)).all(axis=2).any(axis=1))
        assert np.array_equal(inside, ((lo + pad >= r_lo) & (hi - pad <= r_hi)).all(axis=2).any(axis=1))
        lattice_path += _near_pairs(box, level, index, regions, size * cell) is not None
    assert lattice_path > 60


def test_powers_of_few_values_are_the_repeated_products():
    """The running product of few values (one point's coordinates) has the bits of one product per power,
    as have the row-wise products of many (laid out as columns afterwards)."""
    from singmesh.monomials import _FEW_VALUES, powers

    rng = np.random.default_rng(5)
    for shape in [(1,), (3,), (2, 3), (_FEW_VALUES,), (_FEW_VALUES + 1,), (5000,), (40, 30)]:
        values = rng.standard_normal(shape) * 10.0 ** rng.integers(-8, 8, shape)
        values.flat[0] = -0.0
        if values.size > 2:
            values.flat[1], values.flat[2] = np.inf, np.nan
        for n in (1, 2, 5, 11):
            want = np.empty(shape + (n,))
            want[..., 0] = 1.0
            for i in range(1, n):
                want[..., i] = want[..., i - 1] * values
            with np.errstate(invalid="ignore", over="ignore"):
                got = powers(values, n)
            assert got.shape == want.shape
            assert np.array_equal(got.view(np.int64), want.view(np.int64))


@pytest.mark.parametrize("text", ["4(x^2+y^2+z^2) + 16 x y z - 1", float_rotated("x^2 + y^2 - z^2 + 0.3 x y z", 7)[0],
                                  "x y z + 0.123456789012345 x^3 - 0.3 y^5 z^2 + 1.5 z^6"])
def test_many_points_in_one_product_are_independent_of_the_batch(text):
    # evaluate_tensors on many points (monomials._contract_many): a point's
    # values do not depend on the other points of the call nor on the other
    # tensors evaluated with it, and agree with the per-point contraction
    # to the rounding of the sum of |terms|.
    from singmesh.monomials import _MANY, _contract, evaluate_tensors

    s = Surface.parse(text)
    tensors = [s.coeffs, *s.gradient_coeffs]
    rng = np.random.default_rng(11)
    pts = np.concatenate([_point_cloud(4), rng.uniform(-2, 2, (3000, 3))])
    full = np.stack(evaluate_tensors(tensors, pts), axis=-1)
    for a, b in [(0, _MANY + 1), (3, 100), (17, 1017), (7, 136), (1, 2 * _MANY + 3), (50, len(pts))]:
        part = np.stack(evaluate_tensors(tensors, pts[a:b]), axis=-1)
        assert part.tobytes() == full[a:b].tobytes()
        assert evaluate_tensors(tensors[:1], pts[a:b])[0].tobytes() == full[a:b, 0].tobytes()
    alone = np.stack(_contract(tensors, pts, alone=True), axis=-1)
    mag = np.stack(_contract([np.abs(t) for t in tensors], np.abs(pts), alone=True), axis=-1)
    assert (np.abs(full - alone) <= 8 * np.finfo(float).eps * mag).all()


def test_line_polynomials_are_F_on_the_lines_whatever_the_batch():
    # polynomial_lines.line_polynomials (one matrix product of all lines):
    # each line's coefficients do not depend on the other lines of the call,
    # and the polynomial is F along the line (Newton-free check: F at
    # points of the line, to the rounding of the sum of |terms|).
    text = float_rotated("x^2 + y^2 - z^2 + 0.3 x y z", 7)[0]
    s = Surface.parse(text)
    rng = np.random.default_rng(12)
    fixed = np.concatenate([rng.uniform(-1, 1, (700, 2)), np.round(rng.uniform(-1, 1, (300, 2)) * 64) / 64])
    fixed[::9, 0] = 0.0
    for axis in range(3):
        poly = polynomial_lines.line_polynomials(s.coeffs, axis, fixed)
        for a, b in [(0, 1), (5, 6), (3, 300), (17, 529), (0, len(fixed))]:
            part = polynomial_lines.line_polynomials(s.coeffs, axis, fixed[a:b])
            assert part.tobytes() == poly[a:b].tobytes()
        t = rng.uniform(-1.2, 1.2, len(fixed))
        pts = np.empty((len(fixed), 3))
        pts[:, axis], pts[:, (axis + 1) % 3], pts[:, (axis + 2) % 3] = t, fixed[:, 0], fixed[:, 1]
        along = np.polynomial.polynomial.polyval(t, poly.T, tensor=False)
        mag = s.magnitude(pts)
        assert (np.abs(along - s(pts)) <= 64 * np.finfo(float).eps * mag).all()


def test_root_polishing_stops_swinging_roots_where_the_last_step_would_leave_them(monkeypatch):
    # polynomial_lines.real_roots stops a root that Newton takes back and
    # forth between two floats: its roots are those of every root taking
    # all NEWTON_ITERATIONS steps, bit for bit (hard polynomials and the
    # lines of a float-rotated surface and of a sphere).
    from singmesh import tolerances

    rng = np.random.default_rng(13)
    polys = [_line_polynomials(rng, 3000)]
    for text in ["x^2 + y^2 + z^2 - 1", float_rotated("x^2 + y^2 - z^2 + 0.3 x y z", 7)[0]]:
        surface = Surface.parse(text)
        fixed = np.round(rng.uniform(-1, 1, (2000, 2)) * 64) / 64
        s0, s1 = np.full(2000, -1.5), np.full(2000, 1.5)
        poly = polynomial_lines.line_polynomials(surface.coeffs, 0, fixed)
        polys.append(polynomial_lines._rescale(poly, (s0 + s1) / 2, (s1 - s0) / 2))
    swung = 0
    for p in polys:
        got_row, got = polynomial_lines.real_roots(p, 1.0)
        with monkeypatch.context() as m:
            m.setattr(tolerances, "NEWTON_ITERATIONS", 0)
            row, root = polynomial_lines.real_roots(p, 1.0)
        assert np.array_equal(row, got_row)
        # Every root through every step (the loop without stops).
        c = p[row]
        seen = [root]
        for _ in range(tolerances.NEWTON_ITERATIONS):
            val, d = polynomial_lines._horner(c, root)
            ok = np.abs(d) > 0
            trial = root - np.where(ok, val / np.where(ok, d, 1.0), 0.0)
            root = np.where(np.abs(polynomial_lines._horner(c, trial)[0]) <= np.abs(val), trial, root)
            seen.append(root)
        assert got.tobytes() == root.tobytes()
        swung += int(((seen[-1] == seen[-3]) & (seen[-1] != seen[-2])).sum())
    assert swung > 10


def test_star_points_distance_is_the_k_d_trees():
    """skeleton.curves.StarPoints.distance (a node against every vertex of its star's
    cycles, all pairs at once) is cKDTree's query with p = inf, to the bit: jobs of one
    point share a star, points on the vertices (distance 0) and 1e-31 off them (fuzz
    s1-324's node on another cycle's event) included, a star without vertices is inf."""
    from scipy.spatial import cKDTree

    from singmesh.skeleton.curves import StarPoints

    rng = np.random.default_rng(11)
    centres = rng.normal(size=(5, 3)) * 0.123456789012345
    jobs = []
    for j in range(17):
        p = centres[j % 5].copy()  # equal bits: the same star
        jobs.append((p, p + rng.normal(size=(int(rng.integers(2, 30)), 3)) * 0.01, [], np.zeros((0, 3))))
    jobs.append((np.array([7.0, 7.0, 7.0]), np.zeros((0, 3)), [], np.zeros((0, 3))))
    stars = StarPoints(jobs)
    job = rng.integers(0, len(jobs), 400)
    q = np.array([jobs[j][0] for j in job]) + rng.normal(size=(400, 3)) * 0.02
    on = np.flatnonzero(np.array([len(jobs[j][1]) for j in job]) > 0)[:60]
    q[on[:30]] = [jobs[job[k]][1][k % len(jobs[job[k]][1])] for k in on[:30]]
    q[on[30:]] = [jobs[job[k]][1][0] + 1e-31 for k in on[30:]]
    got = stars.distance(job, q)
    for k in range(len(job)):
        key = jobs[job[k]][0].tobytes()
        pts = np.concatenate([jb[1] for jb in jobs if jb[0].tobytes() == key]).reshape(-1, 3)
        want = cKDTree(pts).query(q[k], p=np.inf)[0] if len(pts) else np.inf
        assert got[k] == want
    assert (got[on[:30]] == 0).all()


def test_sector_polygons_of_many_cycles_are_each_alone(monkeypatch):
    """facets.fans.sector_polygons_many (the zippers' distances and the flat-triangle
    test of all star cycles at once) gives each cycle's polygons, splits and keys as
    sector_polygons of that cycle alone gives them, to the bit: Barth's 100 star cycles
    and a float-rotated D4's."""
    import singmesh
    from singmesh.facets import fans, polygons

    jobs = []
    original = fans.sector_polygons_many

    def record(many, next_key):
        jobs.append((list(many), next_key))
        return original(many, next_key)

    monkeypatch.setattr(polygons, "sector_polygons_many", record)
    barth = ("4*(((1+sqrt(5))/2)**2*x**2-y**2)*(((1+sqrt(5))/2)**2*y**2-z**2)*(((1+sqrt(5))/2)**2*z**2-x**2)"
             "-(1+2*((1+sqrt(5))/2))*(x**2+y**2+z**2-1)**2")
    singmesh.mesh(barth, box=((-2.0, 2.0),) * 3)
    singmesh.mesh(float_rotated("x^2 y - y^3 + z^2", 3)[0], box=BOX)
    assert [len(m) for m, _ in jobs] == [100, len(jobs[1][0])] and len(jobs[1][0]) >= 1
    for many, next_key in jobs:
        got, got_splits, got_next = fans.sector_polygons_many(many, next_key)
        key = next_key
        for job, (k, p, s), split in zip(many, got, got_splits):
            (k1, p1, s1), split1, key = fans.sector_polygons(*job[:5], key, cycle_squares=job[5])
            assert np.array_equal(k, k1) and p.tobytes() == p1.tobytes() and s == s1
            assert split.keys() == split1.keys()
            assert all(a[0] == b[0] and np.array_equal(a[1], b[1])
                       for q in split for a, b in zip(split[q], split1[q]))
        assert got_next == key


def test_column_dots_do_not_depend_on_the_batch():
    # improve._dot: a column's dot product is the same alone (einsum takes
    # n = 1 by another loop) as among others, so that values computed in
    # one call can stand for those another call would compute.
    from singmesh.facets.improve import _dot

    rng = np.random.default_rng(5)
    a = rng.normal(size=(3, 40)) * 10.0 ** rng.integers(-8, 8, size=(3, 40))
    b = rng.normal(size=(3, 40)) * 10.0 ** rng.integers(-8, 8, size=(3, 40))
    full = _dot(a, b)
    for j in range(40):
        # Contiguous columns, as the gathers give them (a strided view takes yet another loop).
        for k in (1, 2):
            one = _dot(np.ascontiguousarray(a[:, j:j + k]), np.ascontiguousarray(b[:, j:j + k]))
            assert one.tobytes() == full[j:j + k].tobytes()


@pytest.mark.parametrize("text, box", [
    (float_rotated("4(x^2+y^2+z^2) + 16 x y z - 1", 3)[0], 1.5),    # nodes, float coefficients
    (float_rotated("x^4 - 5x^2 + y^4 - 5y^2 + z^4 - 5z^2 + 11.8", 4)[0], 3.0),
])
def test_kept_leans_are_the_leans_of_the_triangles_as_they_are(text, box, monkeypatch):
    # The shaping pass keeps each triangle's lean from the step or flip
    # that computed it (improve._State.lean): after every step and every
    # flip pass, each kept lean must be, to the bit, the lean of that
    # triangle computed afresh from its corners' places and normals.
    from singmesh.facets import improve

    checked = []

    def check(state):
        t = np.flatnonzero(state.has_lean)
        ft = state.f[t]
        p = [np.take(state.p, ft[:, i], axis=1) for i in range(3)]
        ref = sum(np.take(state.n, ft[:, i], axis=1) for i in range(3))
        assert state.lean[t].tobytes() == improve._lean(*p, ref).tobytes()
        checked.append(len(t))

    relax, flip = improve._State.relax, improve._State.flip_pass

    def relax_checked(self, surface):
        out = relax(self, surface)
        check(self)
        return out

    def flip_checked(self, dirty):
        out = flip(self, dirty)
        check(self)
        return out

    monkeypatch.setattr(improve._State, "relax", relax_checked)
    monkeypatch.setattr(improve._State, "flip_pass", flip_checked)
    m = singmesh.mesh(text, box=((-box, box),) * 3, coarse=16, fine=64)
    assert m.stats["improve"]["moves"] > 0 and max(checked) > 100


def test_eigenvalues_of_distinct_matrices_are_those_of_all():
    # polynomial_lines._eigvals_of_distinct: each distinct companion matrix
    # solved once, its copies given its values, is np.linalg.eigvals of the
    # whole stack bit for bit: copies in any order, rows differing in one
    # bit or in the sign of a zero kept apart, all-real stacks real.
    from singmesh.boxes.polynomial_lines import _eigvals_of_distinct

    rng = np.random.default_rng(8)

    def stack(c):
        d = c.shape[1]
        comp = np.zeros((len(c), d, d))
        comp[:, np.arange(1, d), np.arange(d - 1)] = 1.0
        comp[:, :, -1] = -c
        return comp

    base = rng.normal(size=(300, 4)) * 10.0 ** rng.integers(-6, 6, size=(300, 4))
    near = base[:20].copy()
    near[:, 0] = np.nextafter(near[:, 0], np.inf)        # one bit off
    signed = np.zeros((2, 4))
    signed[1, 2] = -0.0                                   # -0 beside +0
    c = np.concatenate([base, base[rng.integers(0, 300, 500)], near, signed, -base[:50]])
    c = c[rng.permutation(len(c))]
    got = _eigvals_of_distinct(stack(c), c)
    want = np.linalg.eigvals(stack(c))
    assert got.dtype == want.dtype and got.tobytes() == want.tobytes()
    # Quadratics with real roots only: the result is real, as eigvals's.
    q = np.array([[-1.0, 0.0], [-0.25, 0.0], [-1.0, 0.0], [-4.0, 1.5]])
    got, want = _eigvals_of_distinct(stack(q), q), np.linalg.eigvals(stack(q))
    assert got.dtype == want.dtype == np.float64 and got.tobytes() == want.tobytes()


@pytest.mark.parametrize("text, box", [
    ("4*(((1+sqrt(5))/2)**2*x**2-y**2)*(((1+sqrt(5))/2)**2*y**2-z**2)*(((1+sqrt(5))/2)**2*z**2-x**2)"
     "-(1+2*((1+sqrt(5))/2))*(x**2+y**2+z**2-1)**2", 2.0),      # Barth: lines equal in eights
    ("x^4 - 5x^2 + y^4 - 5y^2 + z^4 - 5z^2 + 11.8", 3.0),
    (float_rotated("4(x^2+y^2+z^2) + 16 x y z - 1", 3)[0], 1.5),  # no two lines alike
])
def test_line_roots_of_symmetric_surfaces_solve_each_polynomial_once(text, box, monkeypatch):
    # compute_events's line roots with each distinct line polynomial solved
    # once are those with every line solved, bit for bit; on the symmetric
    # surfaces fewer matrices go to LAPACK.
    surface = Surface.parse(text)
    tree = subdivide(surface, np.array([[-box, box]] * 3), 3, 5)
    sizes, plain = [], np.linalg.eigvals
    monkeypatch.setattr(polynomial_lines.np.linalg, "eigvals", lambda a: sizes.append(len(a)) or plain(a))
    got = compute_events(surface, tree)
    solved = sum(sizes)
    sizes.clear()
    monkeypatch.setattr(polynomial_lines, "_distinct_rows", lambda k: None)  # every line solved
    want = compute_events(surface, tree)
    assert got.key.tobytes() == want.key.tobytes() and got.pos.tobytes() == want.pos.tobytes()
    if "sqrt" in text or "11.8" in text:
        assert solved < 0.6 * sum(sizes)


def test_column_products_in_one_stacked_product_are_the_blocks_one_by_one():
    # monomials.column_products: the full blocks of columns go to BLAS in
    # one stacked matmul; each block must have the bits of its own product
    # (the loop it replaces), whatever the number of columns.
    from singmesh.monomials import _COLUMNS, column_products

    rng = np.random.default_rng(12)
    for rows, inner in [(5, 25), (7, 49), (10, 25), (1, 9)]:
        w = rng.normal(size=(rows, inner)) * 10.0 ** rng.integers(-6, 6, size=(rows, inner))
        for k in [1, 7, _COLUMNS - 1, _COLUMNS, _COLUMNS + 1, 3 * _COLUMNS, 5 * _COLUMNS + 17]:
            q = rng.normal(size=(inner, k)) * 10.0 ** rng.integers(-3, 3, size=(inner, 1))
            want = np.empty((rows, k))
            full = k - k % _COLUMNS
            for c in range(0, full, _COLUMNS):
                np.matmul(w, q[:, c:c + _COLUMNS], out=want[:, c:c + _COLUMNS])
            if full < k:
                last = np.zeros((inner, _COLUMNS))
                last[:, :k - full] = q[:, full:]
                want[:, full:] = (w @ last)[:, :k - full]
            assert column_products(w, q).tobytes() == want.tobytes()


def test_stacked_rows_read_as_the_concatenation(tree_of):
    """A subdivision's data (the levels' stacks, not concatenated) reads as their copy, and a
    refined tree's kept rows of it too; out-of-range rows are refused as numpy refuses them."""
    surface, tree = tree_of
    whole = np.asarray(tree.data)
    rng = np.random.default_rng(4)
    cuts = np.sort(rng.choice(np.arange(1, len(whole)), size=3, replace=False))
    stacked = StackedRows(np.split(whole, cuts))
    assert len(stacked) == len(whole) and stacked.shape == whole.shape and stacked.nbytes == whole.nbytes
    rows = rng.choice(len(whole), size=50)
    rows[:3] = [0, len(whole) - 1, -2]
    mask = rng.random(len(whole)) < 0.3
    for index in [rows, list(rows), mask, (rows, slice(None), 0), (mask, -1), slice(3, 9), 4]:
        assert np.array_equal(stacked[index], whole[index])
    side = rng.integers(0, 2, len(rows))
    for n in range(3):
        assert np.array_equal(surface.face_modes(stacked, n, side, rows=rows), surface.face_modes(whole, n, side, rows=rows))
    for bad in ([len(whole)], [-len(whole) - 1]):
        with pytest.raises(IndexError):
            stacked[np.array(bad)]
    keep = rng.random(len(whole)) < 0.6
    kept = KeptRows(StackedRows(np.split(whole, cuts)), keep, [whole[:4]])
    want = np.concatenate([whole[keep], whole[:4]])
    assert np.array_equal(kept[rows % len(want)], want[rows % len(want)]) and np.array_equal(np.asarray(kept), want)
    assert np.array_equal(np.asarray(stacked), whole)


def test_is_zero_reads_the_term_sizes_only_at_small_values(monkeypatch):
    # PolynomialSurface.is_zero on many points: the sum of |terms| only
    # where |F| is under its bound, by the contraction whose bits do not
    # depend on the other points: the answer of the sum read at all points.
    import singmesh.surface as surface_mod
    from singmesh.monomials import evaluate_tensors_many

    read = []
    monkeypatch.setattr(surface_mod, "evaluate_tensors_many",
                        lambda t, p: read.append(len(p)) or evaluate_tensors_many(t, p))
    eps = surface_mod.ZERO_ULPS * np.finfo(float).eps
    for text in ["4(x^2+y^2+z^2) + 16 x y z - 1", "x^2 - y^2 z", float_rotated("x^2 + y^2 - z^2 + 0.3 x y z", 7)[0]]:
        s = Surface.parse(text)
        lattice = np.stack(np.meshgrid(*[np.linspace(-2, 2, 33)] * 3, indexing="ij"), -1).reshape(-1, 3)
        on = s.project(lattice[::7] * 0.5)
        for pts in [lattice, np.concatenate([lattice[::5], on]), on]:
            read.clear()
            got = s.is_zero(pts)
            want = np.abs(s(pts)) <= eps * s.magnitude(pts)
            assert np.array_equal(got, want)
            assert sum(read) <= len(pts) and (pts is not lattice or sum(read) < len(pts) // 2)
    assert max(read) > 0


def test_real_roots_of_equal_rows_are_each_rows_own():
    # polynomial_lines.real_roots solves each distinct row once (bit for
    # bit equal rows, in any order among the others) and gives every copy
    # its roots in the order of the rows: the rows, roots and order of
    # solving every row, on random polynomials with copies, rows equal up
    # to a factor (negated), and rows of other degrees.
    rng = np.random.default_rng(9)
    base = _line_polynomials(rng, 400)
    low = base.copy()
    low[:60, -2:] = 0.0                                   # lower effective degree
    rows = np.concatenate([base, base[rng.integers(0, 400, 300)], -base[:40], low[:60], low[:30]])
    rows = rows[rng.permutation(len(rows))]
    got = polynomial_lines.real_roots(rows, 1.0)
    want = polynomial_lines._real_roots(rows, 1.0, repeats=False)
    assert len(got[0]) > 200
    assert np.array_equal(got[0], want[0]) and got[1].tobytes() == want[1].tobytes()
    assert polynomial_lines._distinct_rows(rows) is not None and polynomial_lines._distinct_rows(base) is None


def test_mirror_symmetry_of_line_polynomials():
    # polynomial_lines._mirrored: the lines across ``axis`` come in mirror
    # pairs exactly when F is even or odd in one or both coordinates across.
    from singmesh.boxes.polynomial_lines import _mirrored

    cases = {"x^2 + y^2 - z^2 + 0.3 x y z": [True, True, True],       # (y, z) -> (-y, -z) ...
             "x^3 + y^2 z + 0.5": [True, False, True],                  # even in y: lines along x and z
             float_rotated("x^2 + y^2 - z^2 + 0.3 x y z", 7)[0]: [False, False, False]}
    for text, want in cases.items():
        s = Surface.parse(text)
        assert [_mirrored(s.coeffs, a) for a in range(3)] == want, text


def test_events_on_segments_in_chunks_are_those_in_one_go(tree_of, monkeypatch):
    # Events.on_segments takes many segments in chunks (temporaries the
    # allocator reuses): each segment's events do not depend on the others,
    # so the chunks' results in order are those of one pass, whatever the
    # chunk size, on the contact squares' edges as face_links gives them.
    surface, tree = tree_of
    events = compute_events(surface, tree)
    squares, _, _ = faces_mod.contact_squares(tree)
    n, plane, u0, v0, size = squares.T
    e_axis = np.stack([(n + 1) % 3, (n + 2) % 3, (n + 1) % 3, (n + 2) % 3], 1).ravel()
    e_f1 = np.stack([v0, plane, v0 + size, plane], 1).ravel()
    e_f2 = np.stack([plane, u0 + size, plane, u0], 1).ravel()
    e_start = np.stack([u0, v0, u0, v0], 1).ravel()
    e_end = e_start + np.repeat(size, 4)
    monkeypatch.setattr(edges_mod, "_SEGMENT_CHUNK", 1 << 40)
    want = events.on_segments(e_axis, e_f1, e_f2, e_start, e_end)
    assert len(want[0]) > 0
    for chunk in (1, 7, 100, len(e_axis) - 1):
        monkeypatch.setattr(edges_mod, "_SEGMENT_CHUNK", chunk)
        got = events.on_segments(e_axis, e_f1, e_f2, e_start, e_end)
        assert np.array_equal(got[0], want[0]) and np.array_equal(got[1], want[1])


def _dedupe_loop(x, radius, key=None, spans=False):
    """singular._dedupe as it was: one cluster at a time (the reference)."""
    from scipy.cluster.hierarchy import fcluster, linkage
    from scipy.spatial.distance import pdist

    labels = fcluster(linkage(pdist(x), method="single"), t=radius, criterion="distance")
    reps, extent = [], []
    for lab in np.unique(labels):
        sel = labels == lab
        members = x[sel]
        extent.append(np.ptp(members, axis=0).max())
        if key is not None:
            reps.append(members[np.lexsort((members[:, 2], members[:, 1], members[:, 0], key[sel]))[0]])
            continue
        c = members.mean(axis=0)
        reps.append(members[np.argmin(np.linalg.norm(members - c, axis=1))])
    reps = np.array(reps)
    order = np.lexsort(reps.T[::-1])
    return (reps[order], np.array(extent)[order]) if spans else reps[order]


@pytest.mark.parametrize("seed", range(4))
def test_dedupe_of_all_clusters_at_once_is_the_loop(seed):
    """singular._dedupe picks every cluster's representative in one batch: the points and
    extents the loop over clusters gives, bit for bit: Newton end points about nodes
    (clusters of 1 to 300 members 1e-13 apart, float coordinates), ties in the key and in
    the distance to the centre, one cluster, all apart, a point given twice."""
    from singmesh.skeleton.singular import _dedupe

    rng = np.random.default_rng(seed)
    centres = rng.normal(size=(int(rng.integers(1, 6 if seed == 0 else 60)), 3)) * 10.0 ** rng.integers(-2, 3)
    sizes = rng.integers(1, 300 if seed == 0 else 12, len(centres))
    x = np.concatenate([c + rng.normal(size=(k, 3)) * 1e-13 * (1 + np.abs(c)) for c, k in zip(centres, sizes)])
    x = x[rng.permutation(len(x))]
    x[-1] = x[0]  # a point twice
    sym = np.concatenate([x[:4], -x[:4]])  # a cluster symmetric about its centre: equal distances
    key = np.round(rng.random(len(x)), 1)  # ties in the key
    for pts, radius in [(x, 1e-7), (x, 1e-16), (x, 1e6), (sym, 1e6)]:
        k = key[:len(pts)]
        for kw in [{}, {"key": k}, {"spans": True}, {"key": k, "spans": True}]:
            got, want = _dedupe(pts, radius, **kw), _dedupe_loop(pts, radius, **kw)
            for g, w in zip(got if kw.get("spans") else [got], want if kw.get("spans") else [want]):
                assert g.shape == w.shape and np.array_equal(g, w) and g.tobytes() == w.tobytes()


def test_short_stars_by_sorted_boxes_is_the_count_table():
    """stars.short_stars counts the star boxes' cycles by binary search in the sorted
    boxes: the points the table of every box's count gives, in the stars' order (boxes
    with no cycle, unknown branch counts, stars given in any order, no cycles at all)."""
    from singmesh.facets.stars import short_stars

    rng = np.random.default_rng(9)
    for n_cycles in [0, 1, 40, 12000]:
        box = rng.integers(0, 300, n_cycles)
        ids = rng.permutation(np.arange(250, 320))[:50].tolist()
        stars = {b: i for i, b in enumerate(ids)}
        expected = [None if rng.random() < 0.2 else int(rng.integers(0, 4)) for _ in ids]
        cycles = type("Cycles", (), {"box": box, "__len__": lambda self: len(self.box)})()
        counts = dict(zip(*np.unique(box, return_counts=True))) if len(box) else {}
        want = [i for b, i in stars.items() if expected[i] is not None and counts.get(b, 0) < expected[i]]
        assert short_stars(cycles, stars, expected) == want
    assert short_stars(cycles, {}, []) == []


def test_sorted_leaf_keys_are_made_once_per_tree(tree_of):
    """Octree.sorted_leaf_keys: the argsort of the leaf keys and the sorted keys, made once
    per tree (the same arrays the next time, read-only) and again for a tree with other
    leaves; the leaf look-ups give what they gave with the keys sorted at each call."""
    from dataclasses import replace

    from singmesh.boxes.octree import containing_leaves

    _, tree = tree_of
    keys = tree.leaf_keys()
    order, sk = tree.sorted_leaf_keys()
    assert np.array_equal(sk, np.sort(keys)) and np.array_equal(keys[order], sk)
    again = tree.sorted_leaf_keys()
    assert again[0] is order and again[1] is sk and not order.flags.writeable
    other = replace(tree, level=tree.level[::-1].copy(), corner=tree.corner[::-1].copy())
    o2, s2 = other.sorted_leaf_keys()
    assert np.array_equal(s2, sk) and np.array_equal(other.leaf_keys()[o2], s2) and not np.array_equal(o2, order)
    rng = np.random.default_rng(2)
    pts = tree.box[:, 0] + rng.random((200, 3)) * (tree.box[:, 1] - tree.box[:, 0])
    first = containing_leaves(tree, pts)
    second = containing_leaves(tree, pts)
    assert all(np.array_equal(a, b) for a, b in zip(first, second))
    doubled = 2 * np.floor((pts - tree.box[:, 0]) / tree.cell).astype(np.int64) + 1
    found = tree.find_leaves(doubled)
    lo, hi = 2 * tree.corner, 2 * (tree.corner + tree.size[:, None])
    inside = ((lo[None] < doubled[:, None]) & (doubled[:, None] < hi[None])).all(axis=2)  # (points, leaves)
    want = np.where(inside.any(axis=1), inside.argmax(axis=1), -1)
    assert np.array_equal(found, want) and (found >= 0).any() and (found < 0).any()


def test_pieces_from_two_sides_of_each_triangle_are_those_of_three():
    """lattice_specks labels the mesh's pieces from two sides of each triangle: the count
    and the labels of the pieces from all three sides, on a float-rotated mesh of two
    spheres (two pieces) plus random triangles over few vertices (many small pieces)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    m = singmesh.mesh("((x-0.5)^2+y^2+z^2-0.1)*((x+0.5)^2+y^2+z^2-0.1)*1.000000000000001", ((-1, 1),) * 3,
                      coarse=16, fine=32)
    rng = np.random.default_rng(6)
    for faces, n in [(np.asarray(m.faces), len(m.vertices)), (rng.integers(0, 500, (300, 3)), 500)]:
        a, b = faces.ravel(), np.roll(faces, -1, axis=1).ravel()
        three = connected_components(coo_matrix((np.ones(len(a)), (a, b)), shape=(n, n)), directed=False)
        two = (np.concatenate([faces[:, 0], faces[:, 1]]), np.concatenate([faces[:, 1], faces[:, 2]]))
        got = connected_components(coo_matrix((np.ones(len(two[0]), np.int8), two), shape=(n, n)), directed=False)
        assert got[0] == three[0] and np.array_equal(got[1], three[1])
    assert three[0] > 50


def _insert_link_nodes_loop(offsets, keys, points, squares, splits):
    """fans.insert_link_nodes as it was: one insertion at a time (the reference)."""
    if not splits:
        return offsets, keys, points
    n = len(keys)
    poly = np.repeat(np.arange(len(offsets) - 1), np.diff(offsets))
    nxt = np.arange(n) + 1
    nxt[offsets[1:] - 1] = offsets[:-1]
    split_squares = np.array(sorted({q for q, _, _ in splits}), dtype=np.int64)
    cand = np.nonzero(np.isin(squares, split_squares))[0]
    insert_after = {}
    for i in cand.tolist():
        link = (int(squares[i]), int(keys[nxt[i]]), int(keys[i]))
        if link in splits:
            insert_after[i] = splits[link][::-1]
    if not insert_after:
        return offsets, keys, points
    out_k, out_p, sizes = [], [], np.diff(offsets).copy()
    last = 0
    for i in sorted(insert_after):
        out_k.append(keys[last:i + 1])
        out_p.append(points[last:i + 1])
        ins = insert_after[i]
        out_k.append(np.array([k for k, _ in ins], np.int64))
        out_p.append(np.array([q for _, q in ins]))
        sizes[poly[i]] += len(ins)
        last = i + 1
    out_k.append(keys[last:])
    out_p.append(points[last:])
    return np.concatenate([[0], np.cumsum(sizes)]), np.concatenate(out_k), np.concatenate(out_p)


@pytest.mark.parametrize("seed", range(3))
def test_link_nodes_inserted_at_once_are_those_one_by_one(seed):
    """fans.insert_link_nodes puts every subdivided link's nodes into the polygons across
    in one np.insert: the polygons of the insertion one by one, bit for bit (links with one
    to three nodes, at a polygon's last vertex (its closing link), links on other squares
    or the other way round (no insertion), splits matching nothing, none at all)."""
    from singmesh.facets.fans import insert_link_nodes

    rng = np.random.default_rng(seed)
    sizes = rng.integers(3, 9, 400)
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    n = int(offsets[-1])
    keys = rng.integers(-5, 4000, n)
    points = rng.normal(size=(n, 3))
    squares = np.where(rng.random(n) < 0.4, rng.integers(0, 50, n), -1)
    nxt = np.arange(n) + 1
    nxt[offsets[1:] - 1] = offsets[:-1]
    splits, key = {}, 10 ** 6
    for i in rng.choice(np.flatnonzero(squares >= 0), 120, replace=False).tolist():
        k = int(rng.integers(1, 4))
        link = (int(squares[i]), int(keys[nxt[i]]), int(keys[i]))
        if rng.random() < 0.2:
            link = (link[0] + 1, link[1], link[2])  # another square: no insertion
        elif rng.random() < 0.2:
            link = (link[0], link[2], link[1])  # the same way round: no insertion
        splits[link] = [(key + j, rng.normal(size=3)) for j in range(k)]
        key += k
    splits[(7, -99, -98)] = [(key, np.zeros(3))]
    for sp in [splits, {}, {(7, -99, -98): [(1, np.zeros(3))]}]:
        got = insert_link_nodes(offsets, keys, points, squares, sp)
        want = _insert_link_nodes_loop(offsets, keys, points, squares, sp)
        for g, w in zip(got, want):
            assert g.dtype == w.dtype and np.array_equal(g, w) and g.tobytes() == w.tobytes()
    assert len(insert_link_nodes(offsets, keys, points, squares, splits)[1]) > n


def test_find_leaves_with_guessed_levels_are_those_without(tree_of):
    """Octree.find_leaves looks at a guessed level first (_sides: the owner's): the same
    leaves whatever the guesses (right, wrong, levels without leaves), on the points the
    squares' sides ask for and on random points (some in no leaf)."""
    from singmesh.boxes.faces import contact_squares

    _, tree = tree_of
    squares, owner, side = contact_squares(tree)
    n, plane, u0, v0, size = squares.T
    other = np.zeros((len(squares), 3), np.int64)
    r = np.arange(len(squares))
    other[r, (n + 1) % 3] = 2 * u0 + size
    other[r, (n + 2) % 3] = 2 * v0 + size
    other[r, n] = np.where(side == 0, 2 * plane - 1, 2 * plane + 1)
    rng = np.random.default_rng(7)
    top = 2 << tree.fine_level
    odd = 2 * rng.integers(0, top // 2, (500, 3)) + 1
    for pts, right in [(other, tree.level[owner]), (odd, np.full(len(odd), tree.level.max()))]:
        want = tree.find_leaves(pts)
        for guess in [right, rng.integers(0, tree.fine_level + 1, len(pts)), np.zeros(len(pts), np.int64)]:
            assert np.array_equal(tree.find_leaves(pts, guess=guess), want)
        assert (want >= 0).any()
    assert (tree.find_leaves(odd) < 0).any()
