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


def _nodes_right(text: str, box, expr, truth, radius: float) -> None:
    """The mesh of ``text`` on ``box`` has no open edge inside the box, no
    non-manifold edge, and each of the nodes ``truth`` (found without
    singmesh) is one vertex with the fans the sphere oracle counts at
    ``radius`` on the part of the sphere inside the box."""
    import sympy

    from singmesh.surface import X, Y, Z

    m = singmesh.mesh(text, box)
    f = sympy.lambdify((X, Y, Z), expr, "numpy")
    lim = np.array(box, float)
    size = float(np.max(lim[:, 1] - lim[:, 0]))
    assert not boundary_edges_off_box(m.vertices, m.faces, box)
    assert not non_manifold_edges(m.faces)
    for p in truth:
        d = np.linalg.norm(m.vertices - p, axis=1)
        assert int((d <= 1e-9 * size).sum()) == 1, p
        want = branches_on_sphere(lambda q: f(q[..., 0], q[..., 1], q[..., 2]), p, radius, 240, 480, box=lim)
        assert fans_at(m.faces, int(np.argmin(d))) == want, p


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


def _point_meshed(mesh, point, want: int, box) -> None:
    """The point is one vertex with ``want`` fans (the oracle's arcs) when it
    has any; no open edge inside the box, no non-manifold edge."""
    d = np.linalg.norm(mesh.vertices - point, axis=1)
    assert int((d <= 1e-9).sum()) == (1 if want else 0)
    assert not boundary_edges_off_box(mesh.vertices, mesh.faces, box)
    assert not non_manifold_edges(mesh.faces)
    if want:
        assert fans_at(mesh.faces, int(np.argmin(d))) == want


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
    # Both nappes in the quadrant and F >= 0 along the box edge: no root
    # event at the apex; the face links pass it by from nappe to nappe.
    "-36 x^2 - 36 y^2 + 48 (z - 0.5)^2 + 20 x (z - 0.5)",
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
    from benchmarks.nodes import find_nodes
    from singmesh.surface import Surface

    t6 = "(32 {v}^6 - 48 {v}^4 + 18 {v}^2 - 1)"
    text = " + ".join(t6.format(v=v) for v in "xyz") + " + 1"
    box = ((0.0, 1.25),) * 3
    expr = Surface.parse(text).expr
    truth = find_nodes(expr, box, starts=12)
    on_edges = (np.abs(truth) <= 1e-12).sum(axis=1) >= 2
    assert on_edges.sum() == 3
    _nodes_right(text, box, expr, truth, 0.02)


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


@pytest.mark.parametrize("seed", range(4))
def test_dedupe_clusters_are_scipys_single_linkage(seed):
    """``_dedupe``'s clusters (a k-d tree's pairs) are scipy's single-linkage
    clusters cut at the radius (``fcluster(linkage(pdist))``, the dense
    computation it replaced): the same representatives, bit for bit, for
    chains, clumps and lone points, with and without a key."""
    from scipy.cluster.hierarchy import fcluster, linkage
    from scipy.spatial.distance import pdist

    from singmesh.skeleton.singular import _dedupe, _representatives

    rng = np.random.default_rng(seed)
    centres = rng.uniform(-1, 1, size=(12, 3))
    chain = np.cumsum(rng.normal(scale=0.03, size=(40, 3)), axis=0)  # a chain of links under the radius
    x = np.vstack([centres[rng.integers(0, 12, 200)] + rng.normal(scale=0.02, size=(200, 3)), chain,
                   rng.uniform(-3, 3, size=(30, 3))])
    key = rng.uniform(size=len(x))
    for k in (None, key):
        labels = fcluster(linkage(pdist(x), method="single"), t=0.1, criterion="distance")
        reps, extent = _representatives(x, labels, k)
        order = np.lexsort(reps.T[::-1])
        got, spans = _dedupe(x, 0.1, key=k, spans=True)
        assert np.array_equal(got, reps[order]) and np.array_equal(spans, extent[order])
        assert 1 < len(got) < len(x)


def _boundary_cones(seed: int, n: int):
    """``n`` cones (float coefficients, 17 digits) with the apex on a face of
    [0, 1]^3 off and on the lattice, on an edge, at a corner and 1e-15 to
    1e-11 inside a face (meshed as on it: the sphere oracle at 0.05 sees
    it so); none with a
    box edge within 0.1 of the cone (then a sliver of surface along it is
    below the sphere oracle's resolution)."""
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < n:
        kind = ("face", "face on a lattice line", "edge", "corner", "a hair inside a face")[len(out) % 5]
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        m = q @ np.diag(np.array([1.0, rng.uniform(0.3, 2), -rng.uniform(0.3, 2)]) * rng.choice([-1.0, 1.0])) @ q.T
        if np.abs(np.diag(m)).min() < 0.1:
            continue
        p = {"face": [0.0, rng.uniform(0.2, 0.8), rng.uniform(0.2, 0.8)],
             "face on a lattice line": [0.0, 0.5, rng.uniform(0.2, 0.8)],
             "edge": [0.0, 0.0, rng.uniform(0.2, 0.8)], "corner": [0.0, 0.0, 0.0],
             "a hair inside a face": [10.0 ** -rng.uniform(11, 15), rng.uniform(0.2, 0.8), rng.uniform(0.2, 0.8)]}[kind]
        p = np.array(p) if kind.startswith("a hair") else np.round(np.array(p), 15)
        v = [f"({c} - {float(a)!r})" for c, a in zip("xyz", p)]
        text = " + ".join(f"{float(m[i, j] * (1 if i == j else 2))!r}*{v[i]}*{v[j]}" for i in range(3) for j in range(i, 3))
        out.append(pytest.param(text, m, p, id=f"{seed}-{len(out)}-{kind}"))
    return out


@pytest.mark.parametrize("text, m, apex", _boundary_cones(11, 20) + _boundary_cones(12, 20))
def test_cones_with_the_apex_on_the_box_boundary(text, m, apex):
    # Each piece of the surface inside the box meets the apex in one fan:
    # as many fans as the arcs of F = 0 on the part of a small sphere about
    # the apex inside the box (the oracle), and one vertex there.
    box = ((0.0, 1.0),) * 3
    with warnings.catch_warnings():
        warnings.simplefilter("error", singmesh.SingularPointWarning)
        mesh = singmesh.mesh(text, box)

    def f(r):
        d = r - apex
        return np.einsum("...i,ij,...j->...", d, m, d)

    want = branches_on_sphere(f, apex, 0.05, 240, 480, box=box)
    _point_meshed(mesh, apex, want, box)


def _boundary_germs(seed: int):
    """A_k germs (x^2 -+ y^2 +- z^(k+1)) under a seeded float rotation with
    the point on a face of [0, 1]^3, on a lattice line of that face, on an
    edge and at a corner: (id, text, sympy expression, point)."""
    import sympy

    x, y, z = sympy.symbols("x y z")
    forms = {"A1": x**2 - y**2 - z**2, "A2": x**2 + y**2 - z**3, "A2 (two sheets)": x**2 - y**2 + z**3,
             "A3 (two sheets)": x**2 - y**2 + z**4}
    rng = np.random.default_rng(seed)
    out = []
    for name, form in forms.items():
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        for kind, p in (("face", [0.0, rng.uniform(0.2, 0.8), rng.uniform(0.2, 0.8)]),
                        ("face on a lattice line", [0.0, 0.5, rng.uniform(0.2, 0.8)]),
                        ("edge", [0.0, 0.0, rng.uniform(0.2, 0.8)]), ("corner", [0.0, 0.0, 0.0])):
            p = np.round(np.array(p), 15)
            u = [sum(float(q[i, j]) * (v - float(p[j])) for j, v in enumerate((x, y, z))) for i in range(3)]
            e = sympy.expand(form.subs(dict(zip((x, y, z), u)), simultaneous=True))
            out.append(pytest.param(str(e).replace("**", "^"), e, p, id=f"{seed}-{name}-{kind}"))
    return out


@pytest.mark.parametrize("text, expr, point", _boundary_germs(21) + _boundary_germs(22))
def test_degenerate_points_on_the_box_boundary(text, expr, point):
    # The point is found (Gauss-Newton fixes a degenerate point only to
    # ~eps^(1/k), as likely just outside the box as in), is one vertex, and
    # meets each piece of the surface inside the box in one fan (the arcs
    # on the part of a small sphere about it inside the box).
    import sympy

    box = ((0.0, 1.0),) * 3
    with warnings.catch_warnings():
        # Right, so nothing to warn of (a point whose cone points out of
        # the box is no vertex and not lost).
        warnings.simplefilter("error", singmesh.SingularPointWarning)
        mesh = singmesh.mesh(text, box)
    assert len(mesh.singular_points)
    assert np.linalg.norm(mesh.singular_points - point, axis=1).min() <= 1e-9
    f = sympy.lambdify(sympy.symbols("x y z"), expr, "numpy")
    want = branches_on_sphere(lambda r: f(r[..., 0], r[..., 1], r[..., 2]), point, 0.02, 360, 720, box=box)
    # No arc: the nappe points out of the box, the point is all there is.
    _point_meshed(mesh, point, want, box)


@pytest.mark.parametrize("box", [((0.0, 1.8),) * 3, ((-1.8, 1.8), (-1.8, 1.8), (0.0, 1.8))], ids=["octant", "half"])
def test_barth_sextic_cut_at_its_symmetry_planes(box):
    # Users mesh an octant or a half of a symmetric surface: Barth's sextic
    # has nodes on its symmetry planes (e.g. (0, 1/phi, phi)) where both
    # nappes of the cone cross the plane, two fans inside the box.
    from benchmarks.nodes import find_nodes
    from singmesh.surface import Surface

    phi = (1 + 5 ** 0.5) / 2
    text = (f"4*({phi}^2*x^2 - y^2)*({phi}^2*y^2 - z^2)*({phi}^2*z^2 - x^2)"
            f" - (1 + 2*{phi})*(x^2 + y^2 + z^2 - 1)^2")
    expr = Surface.parse(text).expr
    truth = find_nodes(expr, box, starts=12)
    lim = np.array(box)
    on_faces = (np.abs(truth[:, :, None] - lim[None]) <= 1e-9).any(axis=(1, 2))
    assert on_faces.sum() >= 6
    _nodes_right(text, box, expr, truth, 0.02)


def _cones_just_inside_a_face(seed: int):
    """Cones (float coefficients, 17 digits) with the apex 1e-9, 1e-7,
    1e-5, 1e-3 and 0.3 fine cells (of 256) inside a face of [0, 1]^3 that
    cuts both nappes (the face and its side drawn at random): (id, text,
    matrix, apex, depth)."""
    rng = np.random.default_rng(seed)
    out = []
    for depth in (1e-9, 1e-7, 1e-5, 1e-3, 0.3 / 256):
        while True:
            q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
            m = q @ np.diag(np.array([1.0, rng.uniform(0.3, 2), -rng.uniform(0.3, 2)]) * rng.choice([-1.0, 1.0])) @ q.T
            axis, side = int(rng.integers(3)), int(rng.integers(2))
            rest = [a for a in range(3) if a != axis]
            # The face cuts both nappes (the cone restricted to it is
            # indefinite), no box edge near the cone.
            if np.linalg.det(m[np.ix_(rest, rest)]) < 0 and np.abs(np.diag(m)).min() >= 0.1:
                break
        p = rng.uniform(0.2, 0.8, 3)
        p[axis] = 1.0 - depth if side else depth
        v = [f"({c} - {float(a)!r})" for c, a in zip("xyz", p)]
        text = " + ".join(f"{float(m[i, j] * (1 if i == j else 2))!r}*{v[i]}*{v[j]}" for i in range(3) for j in range(i, 3))
        out.append(pytest.param(text, m, p, depth, id=f"{seed}-{depth:.3g}-{'xyz'[axis]}{'+' if side else '-'}"))
    return out


def _nappes_in_box(m, apex, box, radius: float) -> int:
    """How many nappes of the cone d^T m d = 0 about ``apex`` have points
    inside ``box`` at ``radius`` from the apex (a nappe is the side of the
    plane across the axis, the eigenvector of m whose eigenvalue has the
    sign the other two have not)."""
    w, v = np.linalg.eigh(m)
    odd = int(np.argmax(np.sign(w) != np.sign(np.sum(np.sign(w)))))
    lat, lon = np.meshgrid(np.linspace(0, np.pi, 721), np.linspace(0, 2 * np.pi, 1441), indexing="ij")
    u = np.stack([np.sin(lat) * np.cos(lon), np.sin(lat) * np.sin(lon), np.cos(lat)], axis=-1)
    g = np.einsum("...i,ij,...j->...", u, m, u)
    change = np.zeros(g.shape, bool)
    change[:-1] |= np.sign(g[:-1]) != np.sign(g[1:])
    change[:, :-1] |= np.sign(g[:, :-1]) != np.sign(g[:, 1:])
    q = apex + radius * u[change]
    lim = np.asarray(box, float)
    inside = ((q >= lim[:, 0]) & (q <= lim[:, 1])).all(axis=1)
    return len(np.unique(np.sign(u[change][inside] @ v[:, odd])))


@pytest.mark.parametrize("text, m, apex, depth", _cones_just_inside_a_face(31) + _cones_just_inside_a_face(32)
                         + _cones_just_inside_a_face(33))
def test_cones_with_the_apex_just_inside_a_face(text, m, apex, depth):
    # The apex is inside the box: there the surface is the whole cone, two
    # nappes meeting only at the apex (the sphere oracle inside the box
    # counts 2), the face cutting them further out.  Each nappe that
    # reaches beyond a cell is one fan closed round the apex (a face
    # cutting a nappe in a small ellipse round the apex leaves a cap of it
    # about a cell wide or less, which the lattice may not see).
    # The links on the face pass the nappes' traces less than a square
    # apart and used to join them into one cycle: one fan for both.
    box = ((0.0, 1.0),) * 3

    def f(r):
        d = r - apex
        return np.einsum("...i,ij,...j->...", d, m, d)

    assert branches_on_sphere(f, apex, 0.5 * depth, 240, 480, box=box) == 2
    want = _nappes_in_box(m, apex, box, 0.02)
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always", singmesh.SingularPointWarning)
        mesh = singmesh.mesh(text, box)
    if want == 2:
        assert not [w for w in said if issubclass(w.category, singmesh.SingularPointWarning)]
    d = np.linalg.norm(mesh.vertices - apex, axis=1)
    assert int((d <= 1e-9).sum()) == 1
    i = int(np.argmin(d))
    # (A cap the lattice sees is meshed: its fan is right too.)
    assert fans_at(mesh.faces, i) in {want, 2}
    assert not boundary_edges_off_box(mesh.vertices, mesh.faces, box)
    assert not non_manifold_edges(mesh.faces)
    # Each fan closed round the apex: no edge at it on one triangle only.
    from meshcheck import boundary_edges

    assert not [e for e in boundary_edges(mesh.faces) if i in e]


def _d4_germs(seed: int, picks: list):
    """D4 germs x^2 y - y^3 + z^2 (three half-cones) and x^2 y + y^3 + z^2
    (one) under a seeded float rotation, the point on an edge, at a corner
    and on a face of [0, 1]^3 by turns: the cases ``picks`` of the seeded
    sequence as (id, text, sympy expression, point)."""
    import sympy

    x, y, z = sympy.symbols("x y z")
    forms = {"D4-": x**2 * y - y**3 + z**2, "D4+": x**2 * y + y**3 + z**2}
    rng = np.random.default_rng(seed)
    out = []
    for t in range(max(picks) + 1):
        name = list(forms)[t % 2]
        kind = ("edge", "corner", "face")[(t // 2) % 3]
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        a, b = rng.uniform(0.2, 0.8, 2)
        p = {"face": [0.0, a, b], "edge": [0.0, 0.0, a], "corner": [0.0, 0.0, 0.0]}[kind]
        if t not in picks:
            continue
        p = np.round(np.array(p), 15)
        u = [sum(float(q[i, j]) * (v - float(p[j])) for j, v in enumerate((x, y, z))) for i in range(3)]
        e = sympy.expand(forms[name].subs(dict(zip((x, y, z), u)), simultaneous=True))
        out.append(pytest.param(str(e).replace("**", "^"), e, p, id=f"{seed}-{t}-{name}-{kind}"))
    return out


@pytest.mark.parametrize("text, expr, point", _d4_germs(6, [10, 14, 25, 52, 61]) + _d4_germs(7, [0, 14, 24, 42, 60]))
def test_d4_points_on_the_box_boundary(text, expr, point):
    # A D4 point's star reaches many cells (the leaves round it that fail
    # the simplicity test), and a sheet near its tangent plane can graze a
    # face of the box inside the star away from the point: a small disc
    # flat on the face (7-24, 7-60), or a bubble across one lattice edge
    # (6-52), which was fanned into the point: one fan too many.  A sheet
    # through the point along the face, cut by it into a row of small
    # cycles (7-0, 7-14, 7-42), keeps its fan.  Each piece of the surface
    # inside the box meets the point in one fan: the arcs on the part of a small sphere about it
    # inside the box, the same at every radius from 0.003 to 0.02 (below
    # the star's size; where they change below a cell the lattice cannot
    # tell, and such cases are not here).
    import sympy

    box = ((0.0, 1.0),) * 3
    f = sympy.lambdify(sympy.symbols("x y z"), expr, "numpy")
    arcs = {branches_on_sphere(lambda r: f(r[..., 0], r[..., 1], r[..., 2]), point, radius, 360, 720, box=box)
            for radius in (0.003, 0.01, 0.02)}
    assert len(arcs) == 1
    want = arcs.pop()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", singmesh.SingularPointWarning)
        mesh = singmesh.mesh(text, box)
    _point_meshed(mesh, point, want, box)
