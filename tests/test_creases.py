"""Sharp edges (issue #10): creases of Min/Max, Abs and R-functions followed by mesh edges.

Checked independently of the mesher: crease points are found here by
Newton (numpy, minimum-norm steps) on the two operands whose common zeros
hold the crease, from random starts, and kept where F (written again in
numpy) vanishes; each must lie on a mesh edge whose two ends are on the
crease (to rounding, plus the chord's sagitta on a curved crease).  The
edges along the crease have two triangles each, corners of three creases
are vertices, and the mesh is closed (or open only on the box), manifold,
with vertices on the surface.
"""

import itertools
import re

import numpy as np
import pytest
import sympy as sp
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

import singmesh

import meshcheck as mc

X, Y, Z = sp.symbols("x y z", real=True)
LOC = {"x": X, "y": Y, "z": Z, "Max": sp.Max, "Min": sp.Min, "Abs": sp.Abs, "sqrt": sp.sqrt}
SPH = "(x**2+y**2+z**2-1)"


def _rotation(seed: int) -> np.ndarray:
    """A float rotation (numpy QR), rows rounded to 15 significant digits as a user types them."""
    q, r = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return np.array([[float(f"{c:.15g}") for c in row] for row in q])


def _lin(row) -> str:
    return "({:.15g}*x + {:.15g}*y + {:.15g}*z)".format(*row)


R = _rotation(11)
N = _rotation(5)[0]

#: name, equation (sympy syntax), box half-width, closed, crease pairs, radius of curvature of the
#: creases (inf: straight), corners (points that must be vertices).
CUBE_PAIRS = [(f"{a}{s}0.7", f"{b}{t}0.7") for a, b in (("x", "y"), ("x", "z"), ("y", "z"))
              for s in "+-" for t in "+-"]


def _rot_pairs(a):
    """The 12 edges of the rotated cube of half-width a: pairs of face planes."""
    return [(f"{_lin(R[i])}{s}{a}", f"{_lin(R[j])}{t}{a}") for i, j in ((0, 1), (0, 2), (1, 2))
            for s in "+-" for t in "+-"]


ROT_PAIRS, ROT_PAIRS_CUT = _rot_pairs(0.5), _rot_pairs(0.7)
CUBE_CORNERS = np.array([[a, b, c] for a in (-0.7, 0.7) for b in (-0.7, 0.7) for c in (-0.7, 0.7)])
CUT_CORNERS = np.linalg.solve(R, CUBE_CORNERS.T).T
# The octahedron's creases: the Abs creases x = 0, y = 0, z = 0 on it, straight between its
# vertices, where two of them cross (on the split planes of the symmetric box).
OCTA_PAIRS = [(a, f"{s}{b}{t}{c}-1") for a, b, c in (("x", "y", "z"), ("y", "x", "z"), ("z", "x", "y"))
              for s in ("", "-") for t in ("+", "-")]
OCTA_CORNERS = np.vstack([np.eye(3), -np.eye(3)])


def _shifted_octahedron(seed):
    """|L1 + s1| + |L2 + s2| + |L3 + s3| = 1: the octahedron rotated by a float matrix and shifted
    off the box's centre, so that no corner or crease is on a split plane.  (Seed 39 made a hole in
    the tube near a corner, seed 21 a trace from a corner back to it: both failed before.)"""
    r = _rotation(seed)
    s = np.random.default_rng(seed).uniform(-0.05, 0.05, 3).round(12)
    lin = [_lin(row)[:-1] + f" + {c:.12g})" for row, c in zip(r, s)]
    pairs = [(lin[i], f"{sg}{lin[j]}{t}{lin[k]}-1") for i, j, k in ((0, 1, 2), (1, 0, 2), (2, 0, 1))
             for sg in ("", "-") for t in ("+", "-")]
    return (f"octahedron-shifted-{seed}", "Abs({}) + Abs({}) + Abs({}) - 1".format(*lin), 1.3, True, pairs, np.inf,
            np.linalg.solve(r, (OCTA_CORNERS - s).T).T)


def _square_prism(seed):
    """Max(|u| + |v|, |w|) = 0.7 in rotated, shifted coordinates u, v, w: a square prism whose
    8 corners are where an Abs crease (a side edge) meets the rim of a top or bottom face, a
    crease of the Max that has corners of its own there.  The rims were traced as closed loops
    through those corners and the side edges ended beside them, not on them: the corners came out
    as two vertices each, read as two creases 0 cells apart, which raised the fine level to the
    limit (2048: 662,502 triangles in 78 s)."""
    r = _rotation(seed)
    s = np.random.default_rng(seed).uniform(-0.05, 0.05, 3).round(12)
    u, v, w = (_lin(row)[:-1] + f" + {c:.12g})" for row, c in zip(r, s))
    pairs = [(u, f"{v}{t}0.7") for t in "+-"] + [(v, f"{u}{t}0.7") for t in "+-"] + \
        [(f"{w}{t}0.7", f"{a}*{u} + {b}*{v} - 0.7") for t in "+-" for a in (1, -1) for b in (1, -1)]
    corners = np.array([[0, a, b] for a in (-0.7, 0.7) for b in (-0.7, 0.7)] +
                       [[a, 0, b] for a in (-0.7, 0.7) for b in (-0.7, 0.7)])
    return (f"square-prism-{seed}", f"Max(Abs({u}) + Abs({v}), Abs({w})) - 0.7", 1.1, True, pairs, np.inf,
            np.linalg.solve(r, (corners - s).T).T)


CASES = [
    ("half-ball-max", f"Max({SPH}, z)", 1.5, True, [(SPH, "z")], 1.0, None),
    ("half-ball-rfunction", f"{SPH} + z + sqrt({SPH}**2 + z**2)", 1.5, True, [(SPH, "z")], 1.0, None),
    ("cube-max", "Max(Abs(x), Abs(y), Abs(z)) - 0.7", 1.0, True, CUBE_PAIRS, np.inf, CUBE_CORNERS),
    # (its corners 0.866 from the centre: inside the box)
    ("cube-rotated", "Max(Abs({}), Abs({}), Abs({})) - 0.5".format(*(_lin(r) for r in R)), 1.0, True, ROT_PAIRS,
     np.inf, np.linalg.solve(R, CUBE_CORNERS.T / 1.4).T),
    # ... and one whose corners poke out of the box: creases end on its faces a few cells apart.
    ("cube-rotated-cut", "Max(Abs({}), Abs({}), Abs({})) - 0.7".format(*(_lin(r) for r in R)), 1.0, False,
     ROT_PAIRS_CUT, np.inf, CUT_CORNERS[np.all(np.abs(CUT_CORNERS) < 1, axis=1)]),
    ("half-ball-rotated", f"Max({SPH}, {_lin(N)})", 1.5, True, [(SPH, _lin(N))], 1.0, None),
    # Creases on split planes of the symmetric box: z = 0 and x = 0.
    ("octahedron", "Abs(x) + Abs(y) + Abs(z) - 1", 1.3, True, OCTA_PAIRS, np.inf, OCTA_CORNERS),
    ("octahedron-rotated", "Abs({}) + Abs({}) + Abs({}) - 1".format(*(_lin(r) for r in R)), 1.3, True,
     [(_lin(R[i]), f"{s}{_lin(R[j])}{t}{_lin(R[k])}-1") for i, j, k in ((0, 1, 2), (1, 0, 2), (2, 0, 1))
      for s in ("", "-") for t in ("+", "-")], np.inf, np.linalg.solve(R, OCTA_CORNERS.T).T),
    *[_shifted_octahedron(seed) for seed in (21, 39)],
    _square_prism(17),
    ("upper-half-ball", f"Max({SPH}, -z)", 1.5, True, [(SPH, "z")], 1.0, None),
    ("min-on-x0", f"Min({SPH}, x)", 1.5, False, [(SPH, "x")], 1.0, None),
]


def _expr(text):
    return sp.sympify(text, locals=LOC)


def _numpy(expr):
    f = sp.lambdify((X, Y, Z), expr, "numpy")
    return lambda p: np.broadcast_to(np.asarray(f(p[:, 0], p[:, 1], p[:, 2]), float), (len(p),))


def crease_points(eq, pairs, box, starts=1200, seed=0):
    """Points where both expressions of a pair vanish and F does (minimum-norm Newton from random starts)."""
    F = _numpy(_expr(eq))
    rng = np.random.default_rng(seed)
    out = []
    for a, b in pairs:
        ea, eb = _expr(a), _expr(b)
        fs = [_numpy(ea), _numpy(eb)]
        js = [[_numpy(sp.diff(e, v)) for v in (X, Y, Z)] for e in (ea, eb)]
        p = box[:, 0] + rng.random((max(100, starts // len(pairs)), 3)) * (box[:, 1] - box[:, 0])
        for _ in range(40):
            r = np.stack([f(p) for f in fs], 1)
            j = np.stack([np.stack([d(p) for d in row], 1) for row in js], 1)
            p = p - np.einsum("nij,nj->ni", np.linalg.pinv(j), r)
        r = np.stack([f(p) for f in fs], 1)
        size = float(np.max(box[:, 1] - box[:, 0]))
        ok = np.isfinite(p).all(1) & (np.abs(r).max(1) < 1e-12)
        ok &= np.all((p > box[:, 0] + 0.02 * size) & (p < box[:, 1] - 0.02 * size), 1)
        p = p[ok]
        out.append(p[np.abs(F(p)) < 1e-12])
    return np.concatenate(out)


def _on_crease(vertices, pairs, tol):
    on = np.zeros(len(vertices), bool)
    for a, b in pairs:
        on |= (np.abs(_numpy(_expr(a))(vertices)) < tol) & (np.abs(_numpy(_expr(b))(vertices)) < tol)
    return on


def _segment_distance(p, a, b):
    """Distance of each point p (n, 3) to the nearest of the segments a-b (m, 3)."""
    d = b - a
    best = np.full(len(p), np.inf)
    for start in range(0, len(p), 256):
        q = p[start:start + 256, None, :]
        t = np.clip(np.einsum("nmi,mi->nm", q - a[None], d) / np.maximum(np.einsum("mi,mi->m", d, d), 1e-300),
                    0, 1)
        best[start:start + 256] = np.linalg.norm(q - (a[None] + t[..., None] * d[None]), axis=2).min(axis=1)
    return best


def _sagitta(chord, radius):
    """Distance of a circle of this radius from the middle of a chord (c^2 / 8r for short ones)."""
    return radius - np.sqrt(radius ** 2 - chord ** 2 / 4)


def _edges(T):
    """The mesh's edges (sorted pairs) and the triangles each has, in numpy."""
    e = np.sort(np.concatenate([T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]]), axis=1)
    return np.unique(e, axis=0, return_counts=True)


def _crease_edges(V, T, pairs, size, cells, coarse=32):
    """Mesh edges along a crease: both ends and the midpoint on one crease (to 1e-10 of the box), or
    both ends on one crease and at most 4 fine cells or 1.25 coarse cells' face diagonals long (a
    chord of a curved crease, whose midpoint is a sagitta off it: the fine triangles along a crease
    are merged to the coarse lattice's size, a quarter more where a sliver goes); not a chord across
    a flat piece between two creases.  On
    flat faces the edges along a straight crease are as long as the coarse lattice's.
    Returns the edges, their triangle counts and lengths."""
    edges, cnt = _edges(T)
    tol = 1e-10 * size
    on = _on_crease(V, pairs, tol)
    sel = on[edges[:, 0]] & on[edges[:, 1]]
    e = edges[sel]
    length = np.linalg.norm(V[e[:, 0]] - V[e[:, 1]], axis=1)
    mid = 0.5 * (V[e[:, 0]] + V[e[:, 1]])
    along = np.zeros(len(e), bool)
    chord = np.zeros(len(e), bool)
    for a, b in pairs:
        fa, fb = _numpy(_expr(a)), _numpy(_expr(b))
        ends = np.ones(len(e), bool)
        for q in (V[e[:, 0]], V[e[:, 1]]):
            ends &= (np.abs(fa(q)) < tol) & (np.abs(fb(q)) < tol)
        along |= ends & (np.abs(fa(mid)) < tol) & (np.abs(fb(mid)) < tol)
        chord |= ends
    keep = along | (chord & (length <= max(4 * size / cells, 1.8 * size / coarse)))
    return e[keep], cnt[sel][keep], length[keep]


def _mesh(name):
    case = next(c for c in CASES if c[0] == name)
    return singmesh.mesh(case[1], box=[[-case[2], case[2]]] * 3)


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_crease_followed_by_edges(case):
    name, eq, r, closed, pairs, radius, corners = case
    box = np.array([[-r, r]] * 3)
    size = 2 * r
    m = _mesh(name)
    V, T = m.vertices, m.faces
    crease_edges, counts, length = _crease_edges(V, T, pairs, size, 256)
    assert len(crease_edges) > 50
    samples = crease_points(eq, pairs, box)
    assert len(samples) > 50
    d = _segment_distance(samples, V[crease_edges[:, 0]], V[crease_edges[:, 1]])
    longest = float(length.max())
    sagitta = 0.0 if np.isinf(radius) else _sagitta(longest, radius) * 1.01
    assert d.max() <= sagitta + 1e-9 * size, (d.max(), sagitta)
    # Each edge along the crease has its two half-sheets' triangles.
    assert np.all(counts == 2), np.bincount(counts)
    if corners is not None:
        dist = np.linalg.norm(V[None] - corners[:, None], axis=2).min(axis=1)
        assert dist.max() <= 1e-12 * size, dist
        # The report (as the CLI prints it) lists the 12 edges and the corners.
        text = m.report_text()
        assert "creases              12" in text and text.count("corner of creases") == len(corners)
        # Creases that meet at a corner are not two creases close together.
        assert m.stats["fine"] == 256, m.stats["crease_gap"]
    # The rest of the mesh is right.
    _check_mesh(m, eq, box, closed)


def _check_mesh(m, eq, box, closed):
    size = float(np.max(box[:, 1] - box[:, 0]))
    V, T = m.vertices, m.faces
    F = _numpy(_expr(eq))
    h = 1e-7
    g = np.stack([(F(V + h * u) - F(V - h * u)) / (2 * h) for u in np.eye(3)], 1)
    gn = np.linalg.norm(g, axis=1)
    assert np.abs(F(V)).max() / np.median(gn) <= 1e-10 * size
    edges, cnt = _edges(T)
    assert (cnt > 2).sum() == 0
    # Open edges only on a face of the box (both ends on the same face).
    tol = 1e-9 * size
    open_ = edges[cnt == 1]
    same_face = np.zeros(len(open_), bool)
    for a in range(3):
        for side in (0, 1):
            on_face = np.abs(V[:, a] - box[a, side]) <= tol
            same_face |= on_face[open_[:, 0]] & on_face[open_[:, 1]]
    assert same_face.all(), (~same_face).sum()
    if closed:
        assert len(open_) == 0
        assert len(np.unique(T)) - len(edges) + len(T) == 2
        graph = coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(len(V), len(V)))
        label = connected_components(graph, directed=False)[1]
        assert len(np.unique(label[np.unique(T)])) == 1
    # The mesh lists its creases, each edge with two triangles.
    assert m.singular_curves and all(c.type == "crease" for c in m.singular_curves)
    assert m.curve_edges_short_of_sheets() == 0
    assert len(m.curve_lines()[1]) == 0  # no curve edge without triangles


def test_polynomial_has_no_creases():
    assert singmesh.Surface.parse("x^2 + y^2 + z^2 - 1").crease_systems() == []
    m = singmesh.mesh("x^2 + y^2 + z^2 - 1", box=[[-1.5, 1.5]] * 3, coarse=16, fine=64)
    assert m.singular_curves == [] and m.stats["creases"] == 0


def test_inactive_kinks_make_no_crease():
    s = singmesh.Surface.parse("Max(Abs(x), Abs(y), Abs(z)) - 0.7")

    def creases_at(q):
        return [c for c in s.crease_systems() if np.abs(c.values(q)[0]).max() < 1e-15 and c.active(q).all()]

    # Abs(x)'s kink at x = 0 lies under the Max's other arguments: no crease there ...
    assert creases_at(np.array([[0.0, 0.7, 0.2]])) == []
    assert creases_at(np.array([[0.0, 0.3, -0.7]])) == []
    # ... while the tie of |x| and |y| on the surface is one, and the corner is on three.
    assert len(creases_at(np.array([[0.7, -0.7, 0.1]]))) == 1
    assert len(creases_at(np.array([[0.7, -0.7, 0.7]]))) == 3


def test_close_creases_raise_the_fine_level():
    # A cube with a cylindrical hole whose rims pass 0.21 from the cube's
    # edges: 6.6 fine cells at fine = 64, where the two creases' tubes
    # merge and the strip of the top face between them is lost (open and
    # non-manifold edges).  The fine level is raised until they are
    # CREASE_MIN_GAP cells apart, and the mesh is right.
    r, cx, cy = 0.4687654321, 0.0123456789, -0.0234567891
    hole = f"((x-{cx})**2+(y-({cy}))**2)"
    eq = f"Max(Max(Abs(x), Abs(y), Abs(z)) - 0.7, {r} - sqrt({hole}))"
    box = np.array([[-1.0, 1.0]] * 3)
    m = singmesh.mesh(eq, box=box, coarse=16, fine=64)
    assert m.stats["fine"] == 128 and 12 <= m.stats["crease_gap"] < 24
    pairs = CUBE_PAIRS + [(f"z{s}0.7", f"{hole}-{r}**2") for s in "+-"]
    V, T = m.vertices, m.faces
    size = 2.0
    crease_edges, counts, length = _crease_edges(V, T, pairs, size, 128, coarse=16)
    samples = crease_points(eq, pairs, box, starts=1400)
    assert len(samples) > 100
    d = _segment_distance(samples, V[crease_edges[:, 0]], V[crease_edges[:, 1]])
    sagitta = _sagitta(float(length.max()), r) * 1.01
    assert d.max() <= sagitta + 1e-9 * size, d.max()
    assert np.all(counts == 2), np.bincount(counts)
    assert np.linalg.norm(V[None] - CUBE_CORNERS[:, None], axis=2).min(axis=1).max() <= 1e-12 * size
    # Closed, of genus 1 (the checks for a sphere's closed=True aside).
    _check_mesh(m, eq, box, closed=False)
    edges, cnt = _edges(T)
    assert (cnt == 1).sum() == 0 and (cnt > 2).sum() == 0
    assert len(np.unique(T)) - len(edges) + len(T) == 0
    assert m.stats["creases"] == 14


def test_small_closed_crease_raises_the_fine_level():
    # A thin capped cylinder in general position: its rims are circles 8.6
    # fine cells across, with no corner on them.  Across a circle the way
    # along the crease is only pi/2 times the distance, so the corner rule
    # took the two sides for one crease; their tubes merged and the caps
    # were lost (54 open edges at fine = 256).
    r, h = 0.0337, 0.8123456789
    u, v, w = (f"({_lin(N_ROWS[i])}{c:+.10f})" for i, c in enumerate((0.0123456789, -0.0234567891, 0.0345678912)))
    eq = f"Max({u}**2 + {v}**2 - {r}**2, Abs({w}) - {h})"
    box = np.array([[-1.0, 1.0]] * 3)
    m = singmesh.mesh(eq, box=box)
    assert m.stats["fine"] > 256 and m.stats["crease_gap"] >= 12
    _check_mesh(m, eq, box, closed=True)
    pairs = [(f"{u}**2 + {v}**2 - {r}**2", f"{w}{s}{h}") for s in "+-"]
    V, T = m.vertices, m.faces
    crease_edges, counts, length = _crease_edges(V, T, pairs, 2.0, m.stats["fine"])
    samples = crease_points(eq, pairs, box, starts=600)
    assert len(samples) > 40
    d = _segment_distance(samples, V[crease_edges[:, 0]], V[crease_edges[:, 1]])
    assert d.max() <= _sagitta(float(length.max()), r) * 1.01 + 1e-9 * 2.0, d.max()
    assert np.all(counts == 2), np.bincount(counts)


N_ROWS = _rotation(23)


def _corners_and_creases(m, eq, pairs, box, corners, starts, least=100, on=None):
    """The corners are vertices, and crease points found by Newton on ``pairs`` (those within 1e-12
    of the segments ``on`` = (a, b), if given) lie on mesh edges with two triangles each."""
    size = float(np.max(box[:, 1] - box[:, 0]))
    V, T = m.vertices, m.faces
    assert np.linalg.norm(V[None] - corners[:, None], axis=2).min(axis=1).max() <= 1e-12 * size
    crease_edges, counts, _ = _crease_edges(V, T, pairs, size, m.stats["fine"])
    samples = crease_points(eq, pairs, box, starts=starts)
    if on is not None:
        samples = samples[_segment_distance(samples, *on) <= 1e-12 * size]
    assert len(samples) > least
    d = _segment_distance(samples, V[crease_edges[:, 0]], V[crease_edges[:, 1]])
    assert d.max() <= 1e-9 * size, d.max()
    assert np.all(counts == 2), np.bincount(counts)


def test_corner_faces_a_few_cells_across_are_meshed_again_finer():
    # A cube truncated at its corners, float-rotated: the corner triangles
    # are 0.71 across, 6 cells from centre to sides at fine = 64.  There
    # each is all tube, without a rail: the 24 crease edges round them
    # had one triangle (470 open edges, chi -6).  The mesh sees its crease
    # edges short of their two triangles and is made again on a finer
    # lattice.
    rot = _rotation(1)
    L = [_lin(row) for row in rot]
    eq = "Max(Max(Abs({0}), Abs({1}), Abs({2})) - 0.7, Abs({0}) + Abs({1}) + Abs({2}) - 1.6)".format(*L)
    faces = [f"{s}{L[i]}-0.7" for i in range(3) for s in ("", "-")]
    cuts = [f"{a}{L[0]}{b}{L[1]}{c}{L[2]}-1.6" for a in ("", "-") for b in "+-" for c in "+-"]
    pairs = [(f, g) for f, g in itertools.combinations(faces, 2) if f.lstrip("-") != g.lstrip("-")] + [
        (f, c) for f in faces for c in cuts]
    box = np.array([[-1.3, 1.3]] * 3)
    m = singmesh.mesh(eq, box=box, coarse=32, fine=64)
    assert m.stats["fine"] > 64
    _check_mesh(m, eq, box, closed=True)
    corners = np.array([np.roll([s * 0.7, t * 0.7, r * 0.2], k) for k in range(3)
                        for s in (-1, 1) for t in (-1, 1) for r in (-1, 1)])
    _corners_and_creases(m, eq, pairs, box, np.linalg.solve(rot, corners.T).T, starts=1200)


def _tetrahedron_pairs(rot, a):
    """The regular tetrahedron Max(L1 + L2 + L3, L1 - L2 - L3, ...) - a of the rotated coordinates,
    and its 6 edges as pairs of face planes."""
    L = [_lin(row) for row in rot]
    faces = [f"{L[0]}+{L[1]}+{L[2]}", f"{L[0]}-{L[1]}-{L[2]}", f"-{L[0]}+{L[1]}-{L[2]}", f"-{L[0]}-{L[1]}+{L[2]}"]
    eq = "Max({}, {}, {}, {}) - {}".format(*faces, a)
    pairs = [(f"{faces[i]}-{a}", f"{faces[j]}-{a}") for i in range(4) for j in range(i + 1, 4)]
    return eq, pairs


@pytest.mark.parametrize("shape", ["octahedron", "tetrahedron"])
def test_faces_narrower_than_the_tubes_raise_the_fine_level(shape):
    # At coarse = fine = 32 every face of these float-rotated solids is
    # narrower than the tubes round its sides: the whole surface was
    # tube, no rail, and the mesh empty (0 triangles, a note blaming
    # rounding).  The fine level is doubled until a face is not all tube.
    rot = _rotation(5)
    if shape == "octahedron":
        L = [_lin(row) for row in rot]
        eq = "Abs({}) + Abs({}) + Abs({}) - 0.9".format(*L)
        pairs = [(L[i], f"{s}{L[j]}{t}{L[k]}-0.9") for i, j, k in ((0, 1, 2), (1, 0, 2), (2, 0, 1))
                 for s in ("", "-") for t in ("+", "-")]
        corners = np.linalg.solve(rot, 0.9 * OCTA_CORNERS.T).T
    else:
        eq, pairs = _tetrahedron_pairs(rot, 0.5)
        corners = np.linalg.solve(rot, -0.5 * np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1.0]]).T).T
    box = np.array([[-1.2, 1.2]] * 3)
    m = singmesh.mesh(eq, box=box, coarse=32, fine=32)
    assert len(m.faces) > 0 and m.stats["fine"] > 32
    _check_mesh(m, eq, box, closed=True)
    _corners_and_creases(m, eq, pairs, box, corners, starts=400, least=20)


_U, _V, _W = (f"({_lin(R[i])}{c:+.10f})" for i, c in enumerate((0.0123456789, -0.0234567891, 0.0345678912)))
#: The point u = v = w = 0 (where the kinks fade out).
_FADE = np.linalg.solve(R, -np.array([0.0123456789, -0.0234567891, 0.0345678912]))


@pytest.mark.parametrize("eq, pairs, fade_vertex", [
    # The kink of |u| fades out (its jump 2 v^2 goes to 0) at v = 0: the
    # crease u = w = 0 (v > 0) ends inside the box, where the surface is
    # smooth (C^1).
    (f"{_W} - Abs({_U})*Max({_V}, 0)**2", [(_U, _W)], False),
    # Both kinks fade out where they meet: |u| (jump 2 v) on the crease of
    # max(v, 0) (jump |u|): a T junction whose three creases end at one
    # vertex.
    (f"{_W} - Abs({_U})*Max({_V}, 0)", [(_U, _W), (_V, _W)], True),
], ids=["fading-end", "fading-T"])
def test_crease_ending_inside_the_box(eq, pairs, fade_vertex):
    box = np.array([[-1.0, 1.0]] * 3)
    size = 2.0
    m = singmesh.mesh(eq, box=box, coarse=16, fine=64)
    V, T = m.vertices, m.faces
    crease_edges, counts, length = _crease_edges(V, T, pairs, size, 64)
    # Crease samples where the kink is there (v > 0 for |u|'s), a little
    # away from where it fades: on mesh edges.
    v_of = _numpy(_expr(_V))
    samples = crease_points(eq, pairs, box)
    samples = samples[(v_of(samples) > 0.02) | (np.abs(_numpy(_expr(_U))(samples)) > 0.02)]
    assert len(samples) > 50
    d = _segment_distance(samples, V[crease_edges[:, 0]], V[crease_edges[:, 1]])
    assert d.max() <= 1e-9 * size, d.max()
    assert np.all(counts == 2), np.bincount(counts)
    # The crease ends at a vertex at (T: exactly) or next to (fading end)
    # the point where the kinks fade, and the surface is a manifold disc
    # around it.
    dist = np.linalg.norm(V - _FADE, axis=1)
    assert dist.min() <= (1e-12 if fade_vertex else 1e-2) * size
    end = int(np.argmin(dist))
    assert _on_crease(V[end:end + 1], pairs, 1e-10 * size)[0]
    assert mc.fans_at(T, end) == 1 and mc.fans_are_closed(T, end)
    _check_mesh(m, eq, box, closed=False)
    assert len(np.unique(T)) - len(_edges(T)[0]) + len(T) == 1


@pytest.mark.parametrize("eq, pairs, kink", [
    # jump 2|y|: fades at the origin, goes on
    ("z - y*Abs(x)", [("x", "z")], lambda p: np.abs(p[:, 1]) > 0.05),
    # the T junction on split planes (|x|'s kink only where y > 0)
    ("z - Abs(x)*Max(y, 0)", [("x", "z"), ("y", "z")], lambda p: (p[:, 1] > 0.05) | (np.abs(p[:, 0]) > 0.05)),
], ids=["linear-fade", "T"])
def test_fading_creases_on_split_planes(eq, pairs, kink):
    # Every term of F vanishes on these creases (x = z = 0): a point 1e-17
    # off one has F at the size of its terms, and must still count as on it.
    box = np.array([[-1.0, 1.0]] * 3)
    m = singmesh.mesh(eq, box=box, coarse=16, fine=64)
    V, T = m.vertices, m.faces
    edges, _ = _edges(T)
    crease_edges, counts, _ = _crease_edges(V, T, pairs, 2.0, 64, coarse=16)
    samples = crease_points(eq, pairs, box)
    samples = samples[kink(samples)]
    assert len(samples) > 50
    d = _segment_distance(samples, V[crease_edges[:, 0]], V[crease_edges[:, 1]])
    assert d.max() <= 2e-9, d.max()
    assert np.all(counts == 2)
    _check_mesh(m, eq, box, closed=False)
    assert len(np.unique(T)) - len(edges) + len(T) == 1


def test_crease_with_a_double_point_where_the_operands_are_tangent():
    # Two capped cylinders of one radius, joined by Min (the Steinmetz union),
    # rotated by a float matrix and shifted: the Min's crease, u^2 + v^2 =
    # v^2 + w^2, is two ellipses crossing at u = w = 0, where both cylinders
    # touch the plane v = +-r.  Traced as two loops with no common vertex,
    # their four half-creases there were read as creases 0.6 cells apart:
    # unrotated, the fine level went to 2048 and the mesh (690,160 triangles,
    # 637 s) had Euler characteristic 8.  Each crossing is a corner of four.
    r = _rotation(31)
    s = np.random.default_rng(31).uniform(-0.05, 0.05, 3).round(12)
    u, v, w = (_lin(row)[:-1] + f" + {c:.12g})" for row, c in zip(r, s))
    eq = f"Min(Max({u}**2+{v}**2-0.2, Abs({w})-1), Max({v}**2+{w}**2-0.2, Abs({u})-1))"
    box = np.array([[-1.3, 1.3]] * 3)
    m = singmesh.mesh(eq, box=box)
    _check_mesh(m, eq, box, closed=True)
    pairs = [(f"{u}**2+{v}**2-0.2", f"{v}**2+{w}**2-0.2")] + \
        [(f"{u}**2+{v}**2-0.2", f"{w}{t}1") for t in "+-"] + [(f"{v}**2+{w}**2-0.2", f"{u}{t}1") for t in "+-"]
    V, T = m.vertices, m.faces
    crease_edges, counts, length = _crease_edges(V, T, pairs, 2.6, 256)
    samples = crease_points(eq, pairs, box)
    assert len(samples) > 100
    d = _segment_distance(samples, V[crease_edges[:, 0]], V[crease_edges[:, 1]])
    # The ellipses' least radius of curvature is r / sqrt(2) (r = sqrt(0.2)).
    assert d.max() <= float(length.max()) ** 2 / (8 * np.sqrt(0.1)) * 1.01 + 1e-9 * 2.6, d.max()
    assert np.all(counts == 2), np.bincount(counts)
    # The two crossings are vertices, each on four crease edges.
    for sign in (1, -1):
        x = np.linalg.solve(r, np.array([0.0, sign * np.sqrt(0.2), 0.0]) - s)
        dist = np.linalg.norm(V - x, axis=1)
        assert dist.min() <= 1e-12 * 2.6, dist.min()
        k = int(dist.argmin())
        assert (crease_edges == k).any(axis=1).sum() == 4


def test_a_refusal_after_raising_fine_for_creases_says_so():
    # An L of two boxes joined by Min with coplanar faces: the edges of the
    # two boxes coincide there, read as creases 0 apart, and fine is
    # raised to its limit for them.  The memory refusal named only the
    # user's coarse and fine, which were not what asked for the memory.
    eq = "Min(Max(Abs(x)-0.8, Abs(y)-0.3, Abs(z)-0.3), Max(Abs(x+0.5)-0.3, Abs(y-0.5)-0.8, Abs(z)-0.3))"
    with pytest.raises(singmesh.SurfaceError) as e:
        singmesh.mesh(eq, box=[[-1.2, 1.2]] * 3, coarse=8, fine=16, max_memory="60MB")
    text = str(e.value)
    assert "\n" not in text and "over max_memory" in text
    # (How far apart the traces of this 4-cells-wide L are at fine 16 is
    # not the point: 0 while coincident kinks split each other's traces.)
    assert re.search(r"fine was raised from 16 to 128 for creases [0-9.e-]+ fine cells apart at fine 16", text)
    assert "coplanar faces" in text


@pytest.mark.parametrize("seed", [None, 7])
def test_boxes_with_coplanar_faces_joined_by_min(seed):
    # An L of two boxes, u in [-0.8, 0.8] x [-0.3, 0.3] and [-0.8, -0.2] x
    # [-0.3, 1.0] (z in [-0.3, 0.3] both), the common way to write it: their
    # faces u = -0.8, v = -0.3 and w = +-0.3 are coplanar.  There the two
    # boxes' edges coincide (two kinks along one crease, traced twice: creases
    # 0 apart, and fine raised to 2048 until memory was refused), and on
    # the common face plane the Min of the two boxes is tied to rounding, so
    # the inner kinks of a box seemed active inside a flat face.
    # Float-rotated, the coincident kinks' equations have common zeros all
    # along the edge: each trace stopped at a "corner" with the other kink a
    # few steps on (Gauss-Newton on both lands anywhere on the line), and the
    # corners of ends placed on one point were left apart (creases 0 apart,
    # fine raised to 4096: 165 s).
    rot = np.eye(3) if seed is None else _rotation(seed)
    L = [_lin(row) for row in rot]
    eq = ("Min(Max(Abs({0})-0.8, Abs({1})-0.3, Abs({2})-0.3), "
          "Max(Abs({0}+0.5)-0.3, Abs({1}-0.35)-0.65, Abs({2})-0.3))").format(*L)
    outline = np.array([[-0.8, -0.3], [0.8, -0.3], [0.8, 0.3], [-0.2, 0.3], [-0.2, 1.0], [-0.8, 1.0]])
    corners = np.array([[a, b, c] for a, b in outline for c in (-0.3, 0.3)])
    segments = [(np.r_[p, c], np.r_[q, c]) for p, q in zip(outline, np.roll(outline, -1, 0)) for c in (-0.3, 0.3)]
    segments += [(np.r_[p, -0.3], np.r_[p, 0.3]) for p in outline]
    planes = [f"{L[0]}+0.8", f"{L[0]}-0.8", f"{L[0]}+0.2", f"{L[1]}+0.3", f"{L[1]}-0.3", f"{L[1]}-1.0"]
    pairs = [(a, b) for a, b in itertools.combinations(planes, 2) if a[:len(L[0])] != b[:len(L[0])]]
    pairs += [(p, f"{L[2]}{s}0.3") for p in planes for s in "+-"]
    box = np.array([[-1.2, 1.2]] * 3)
    m = singmesh.mesh(eq, box=box, coarse=16, fine=64)
    assert m.stats["fine"] == 64
    _check_mesh(m, eq, box, closed=True)
    # Every crease vertex is on an edge of the L (no crease inside a flat face) ...
    a = np.linalg.solve(rot, np.array([s[0] for s in segments]).T).T
    b = np.linalg.solve(rot, np.array([s[1] for s in segments]).T).T
    cp = np.concatenate([c.points for c in m.singular_curves])
    assert _segment_distance(cp, a, b).max() <= 1e-9 * 2.4
    # ... and every edge of the L (the stretches of the planes' lines on its outline: the lines run
    # on through flat faces) is on crease edges with two triangles each.
    _corners_and_creases(m, eq, pairs, box, np.linalg.solve(rot, corners.T).T, starts=1500, on=(a, b))


def _stacked_boxes(rot: np.ndarray):
    """The box standing on a larger one, joined by Min, in the frame ``rot``.

    Returns the equation, the corners of both boxes, the pairs of face
    planes meeting on their edges, and the 24 edges' ends (all in the
    original frame).
    """
    L = [_lin(row) for row in rot]
    eq = ("Min(Max(Abs({0})-0.6, Abs({1})-0.6, Abs({2}+0.2)-0.2), "
          "Max(Abs({0})-0.3, Abs({1})-0.3, Abs({2}-0.2)-0.2))").format(*L)
    corners = [[a, b, c] for a in (-0.6, 0.6) for b in (-0.6, 0.6) for c in (-0.4, 0.0)]
    corners += [[a, b, c] for a in (-0.3, 0.3) for b in (-0.3, 0.3) for c in (0.0, 0.4)]
    low = [f"{L[0]}+0.6", f"{L[0]}-0.6", f"{L[1]}+0.6", f"{L[1]}-0.6", f"{L[2]}+0.4", f"{L[2]}"]
    high = [f"{L[0]}+0.3", f"{L[0]}-0.3", f"{L[1]}+0.3", f"{L[1]}-0.3", f"{L[2]}", f"{L[2]}-0.4"]
    pairs = [(a, b) for faces in (low, high) for i, a in enumerate(faces) for b in faces[i + 1:]
             if a[:len(L[0])] != b[:len(L[0])]]
    # The 12 edges of each box (the lines of the pairs run on in the flat faces).
    ends = [(np.array(p, float), np.array(q, float)) for k in (0, 8) for i, p in enumerate(corners[k:k + 8])
            for q in corners[k + i + 1:k + 8] if np.sum(np.array(p) != np.array(q)) == 1]
    a = np.linalg.solve(rot, np.array([e[0] for e in ends]).T).T
    b = np.linalg.solve(rot, np.array([e[1] for e in ends]).T).T
    return eq, np.linalg.solve(rot, np.array(corners, float).T).T, pairs, len(ends), (a, b)


@pytest.mark.parametrize("seed", [None])
def test_stacked_boxes_touching_along_a_face(seed):
    # A box standing on a larger one, joined by Min: |u|, |v| <= 0.6,
    # w in [-0.4, 0] and |u|, |v| <= 0.3, w in [0, 0.4].  The contact patch
    # (w = 0, |u|, |v| < 0.3) is F = 0 with F < 0 on both sides: inside the
    # union, not its boundary, which is meshed where F changes sign.  The
    # patch's zeros on the split plane w = 0 made rails in the tube round the
    # concave rim, zipped to the rim as a third half-sheet (292 triangles on
    # the patch, 108 non-manifold edges, chi 75 at fine 256; with the retry
    # 688 open edges at 512).  The union's boundary: closed, chi 2, the rim
    # a crease with two triangles per edge.
    rot = np.eye(3) if seed is None else _rotation(seed)
    eq, corners, pairs, n_edges, on = _stacked_boxes(rot)
    box = np.array([[-1.2, 1.2]] * 3)
    # (At fine 128 alone 16 edges are still open round the patch: the
    # strips fail and the mesh is made again at 256.)
    m = singmesh.mesh(eq, box=box, coarse=16, fine=256)
    _check_mesh(m, eq, box, closed=True)
    V, T = m.vertices, m.faces
    # No triangle on the contact patch (inside the union).
    c = V[T].mean(axis=1) @ rot.T
    assert not np.any((np.abs(c[:, 2]) < 1e-9) & (np.abs(c[:, :2]).max(axis=1) < 0.3)), "triangles on the patch"
    # Every edge of both boxes, and the rim, is on crease edges with two triangles each; the
    # corners are vertices.
    assert n_edges == 24
    _corners_and_creases(m, eq, pairs, box, corners, starts=1500, on=on)


def test_corner_on_coincident_box_edges_is_exact():
    # Where the box [-0.8, 0.8] x [-0.3, 0.3] x [-0.3, 0.3] of an L ends on
    # the edge it shares with the other box (at (-0.8, 0.3, +-0.3)), the
    # traces meet at a corner whose Gauss-Newton on the two coincident
    # kinks is singular: it landed 7e-8 off the edge (on some machines, at
    # some boxes), on the surface but off the crease.  The kinks through
    # the corner (the end of the first box's edge) pin it.
    eq = ("Min(Max(Abs(x)-0.8, Abs(y)-0.3, Abs(z)-0.3), "
          "Max(Abs(x+0.5)-0.3, Abs(y-0.35)-0.65, Abs(z)-0.3))")
    outline = np.array([[-0.8, -0.3], [0.8, -0.3], [0.8, 0.3], [-0.2, 0.3], [-0.2, 1.0], [-0.8, 1.0]])
    segments = [(np.r_[p, c], np.r_[q, c]) for p, q in zip(outline, np.roll(outline, -1, 0)) for c in (-0.3, 0.3)]
    segments += [(np.r_[p, -0.3], np.r_[p, 0.3]) for p in outline]
    a = np.array([s[0] for s in segments])
    b = np.array([s[1] for s in segments])
    box = np.array([[-1.2, 1.2]] * 3) + 0.0707
    m = singmesh.mesh(eq, box=box, coarse=8, fine=64)
    cp = np.concatenate([c.points for c in m.singular_curves])
    assert _segment_distance(cp, a, b).max() <= 1e-9 * 2.4


def test_box_with_a_pocket_has_each_corner_once():
    # A float-rotated box with a square pocket cut into its top (Max of the
    # box and minus a smaller box): 16 corners of three creases each.  A
    # corner placed by Gauss-Newton beside a trace's own vertex on it (a
    # trace started at a sample there) was two vertices 1e-14 cells apart,
    # joined by an edge of no length, read as two creases 0 cells apart:
    # fine raised to its limit for them (at coarse 16, fine 64: 8192, 4.5
    # million triangles in 333 s).
    from singmesh.skeleton.creases import crease_curves, crease_gap
    rot = _rotation(1)
    u, v, w = (_lin(row) for row in rot)
    eq = (f"Max(Max(Abs({u})-0.6, Abs({v})-0.6, Abs({w})-0.6), "
          f"-Max(Abs({u})-0.3, Abs({v})-0.3, Abs({w}-0.6)-0.3))")
    box = np.array([[-1.2, 1.2]] * 3)
    cell = 2.4 / 64
    curves = crease_curves(singmesh.Surface.parse(eq), box, step=cell)
    corners = [[a, b, c] for a in (-0.6, 0.6) for b in (-0.6, 0.6) for c in (-0.6, 0.6)]
    corners += [[a, b, c] for a in (-0.3, 0.3) for b in (-0.3, 0.3) for c in (0.3, 0.6)]
    corners = np.linalg.solve(rot, np.array(corners).T).T
    P, E = curves.points, curves.edges
    # Each corner is one vertex of the crease graph, with nothing else within a thousandth of a
    # cell of it, and three creases meet there.
    d = np.linalg.norm(P[None] - corners[:, None], axis=2)
    assert np.all(d.min(axis=1) <= 1e-12 * 2.4), d.min(axis=1)
    assert np.all((d <= 1e-3 * cell).sum(axis=1) == 1), (d <= 1e-3 * cell).sum(axis=1)
    degree = np.bincount(E.ravel(), minlength=len(P))
    assert np.all(degree[d.argmin(axis=1)] == 3), degree[d.argmin(axis=1)]
    # No edge of the graph has no length.
    assert np.linalg.norm(P[E[:, 0]] - P[E[:, 1]], axis=1).min() >= 1e-3 * cell
    # The closest creases that are apart (the pocket's rim and the box's top edges, 0.3 apart in
    # the rotated frame: at least 0.3 / sqrt(3) in the max norm) are cells apart, not 0.
    assert crease_gap(curves, box, 6) >= 0.3 / np.sqrt(3) / cell


@pytest.mark.parametrize("seed", [1])
def test_stacked_boxes_rotated_have_one_crease_per_edge(seed):
    # The box standing on a larger one (test_stacked_boxes_touching_along_a_face), float-rotated.
    # Along the rim (the small box's bottom edges, in the large box's top face) three faces meet:
    # the kink of the small box's Max and the Min's tie both hold it, and a step off the crease
    # along the tie's gradient landed on ties of the enclosing Min whose piece is rounding: the
    # kinks came and went along the rim, its traces were fragments of both, ending on each other
    # 0 cells apart (fine raised to 4096: 566 s, 5387 open edges).  The crease graph, checked
    # against the two boxes' 24 edges: 16 corners, each one vertex with three creases, and every
    # crease vertex on an edge.
    from scipy.spatial.transform import Rotation

    from singmesh.skeleton.creases import crease_curves, crease_gap
    # (scipy's random rotation: the QR rotations of _rotation 2 to 7 did not show it.)
    rot = np.array([[float(f"{c:.15g}") for c in row] for row in Rotation.random(random_state=seed).as_matrix()])
    L = [_lin(row) for row in rot]
    eq = ("Min(Max(Abs({0})-0.6, Abs({1})-0.6, Abs({2}+0.2)-0.2), "
          "Max(Abs({0})-0.3, Abs({1})-0.3, Abs({2}-0.2)-0.2))").format(*L)
    box = np.array([[-1.2, 1.2]] * 3)
    cell = 2.4 / 256
    curves = crease_curves(singmesh.Surface.parse(eq), box, step=cell)
    corners = [[a, b, c] for a in (-0.6, 0.6) for b in (-0.6, 0.6) for c in (-0.4, 0.0)]
    corners += [[a, b, c] for a in (-0.3, 0.3) for b in (-0.3, 0.3) for c in (0.0, 0.4)]
    ends = [(np.array(p, float), np.array(q, float)) for k in (0, 8) for i, p in enumerate(corners[k:k + 8])
            for q in corners[k + i + 1:k + 8] if np.sum(np.array(p) != np.array(q)) == 1]
    corners = np.linalg.solve(rot, np.array(corners, float).T).T
    a = np.linalg.solve(rot, np.array([e[0] for e in ends]).T).T
    b = np.linalg.solve(rot, np.array([e[1] for e in ends]).T).T
    P, E = curves.points, curves.edges
    assert _segment_distance(P, a, b).max() <= 1e-9 * 2.4
    d = np.linalg.norm(P[None] - corners[:, None], axis=2)
    assert np.all(d.min(axis=1) <= 1e-12 * 2.4), d.min(axis=1)
    assert np.all((d <= 1e-3 * cell).sum(axis=1) == 1)
    degree = np.bincount(E.ravel(), minlength=len(P))
    assert np.all(degree[d.argmin(axis=1)] == 3), degree[d.argmin(axis=1)]
    # Elsewhere each vertex is on two crease edges: no end of a trace in the middle of an edge.
    inner = np.ones(len(P), bool)
    inner[d.argmin(axis=1)] = False
    assert np.all(degree[inner] == 2), np.bincount(degree[inner])
    # Each of the 24 edges is followed from end to end: its length along the crease edges on it.
    mid = 0.5 * (P[E[:, 0]] + P[E[:, 1]])
    length = np.linalg.norm(P[E[:, 0]] - P[E[:, 1]], axis=1)
    for p, q in zip(a, b):
        on = _segment_distance(mid, p[None], q[None]) <= 1e-9 * 2.4
        assert abs(length[on].sum() - np.linalg.norm(q - p)) <= 1e-9, (p, q, length[on].sum())
    # No creases 0 cells apart (the fine level is not raised for them).
    assert crease_gap(curves, box, 8) == np.inf


def test_a_crease_mesh_open_inside_the_box_is_said():
    # The tubes round the creases of a float-rotated box standing on another, joined by Min,
    # left strips of the faces next to two edges out (598 edges with one triangle at fine 512,
    # stack of test_stacked_boxes_rotated_have_one_crease_per_edge at the defaults, ~50 s) and
    # mesh() said nothing.  Here a closed crease mesh, and the same with the triangles round a
    # crease vertex taken out: the hole's edges (counted here from the faces) are said.
    import dataclasses
    import warnings

    box = [[-1.5, 1.5]] * 3
    with warnings.catch_warnings():
        warnings.simplefilter("error", singmesh.CreaseWarning)
        m = singmesh.mesh(f"Max({SPH}, z)", box=box, coarse=16, fine=64)
    assert len(m.crease_open_edges()) == 0 and not m.crease_warnings()
    crease = np.concatenate([c.points for c in m.singular_curves])
    hole = np.linalg.norm(m.vertices - crease[len(crease) // 2], axis=1) < 0.3
    faces = m.faces[~hole[m.faces].any(axis=1)]
    edges, cnt = _edges(faces)
    assert (cnt == 1).sum() > 10
    cut = dataclasses.replace(m, faces=faces)
    assert len(cut.crease_open_edges()) == (cnt == 1).sum()
    assert any(f"open inside the box: {(cnt == 1).sum()} edge(s)" in n for n in cut.crease_warnings())
    assert any("open inside the box" in n for n in cut.notes())


def test_crease_tracing_takes_many_steps_per_pass_over_f():
    # Tracing a crease was a Python loop of single steps, each a dozen passes over F's graph
    # (Newton, tangent, the other kinks' values one by one, whether the kink is active): ~10 passes
    # per step, 40% of a cube's mesh and 17.6 s of 34 s on the rotated stack of boxes.  Steps are
    # now taken several at once (Newton on all of them in one pass) and checked in order.  Here the
    # passes over F (point_eval calls) per trace step of a float-rotated cube, and the creases
    # themselves: every vertex on one of the 12 edges, each edge followed from end to end.
    import singmesh.elementary as elementary
    from singmesh.skeleton.creases import crease_curves

    rot = _rotation(3)
    u, v, w = (_lin(row) for row in rot)
    surface = singmesh.Surface.parse(f"Max(Abs({u}), Abs({v}), Abs({w})) - 0.7")
    box = np.array([[-1.3, 1.3]] * 3)  # (the corners, 0.7 sqrt(3) from the centre, inside)
    cell = 2.6 / 256
    passes = [0]
    original = elementary.point_eval

    def counted(*args, **kwargs):
        passes[0] += 1
        return original(*args, **kwargs)

    elementary.point_eval = counted
    try:
        curves = crease_curves(surface, box, step=cell)
    finally:
        elementary.point_eval = original
    P, E = curves.points, curves.edges
    corners = np.array([[a, b, c] for a in (-0.7, 0.7) for b in (-0.7, 0.7) for c in (-0.7, 0.7)])
    ends = [(p, q) for i, p in enumerate(corners) for q in corners[i + 1:] if np.sum(p != q) == 1]
    a = np.linalg.solve(rot, np.array([e[0] for e in ends]).T).T
    b = np.linalg.solve(rot, np.array([e[1] for e in ends]).T).T
    assert _segment_distance(P, a, b).max() <= 1e-9 * 2.6
    mid = 0.5 * (P[E[:, 0]] + P[E[:, 1]])
    length = np.linalg.norm(P[E[:, 0]] - P[E[:, 1]], axis=1)
    for p, q in zip(a, b):
        on = _segment_distance(mid, p[None], q[None]) <= 1e-9 * 2.6
        assert abs(length[on].sum() - 1.4) <= 1e-9
    # Trace steps: CREASE_TRACE_STEP cells each, along the 12 edges of length 1.4.
    steps = 12 * 1.4 / (singmesh.tolerances.CREASE_TRACE_STEP * cell)
    assert passes[0] <= 4 * steps, (passes[0], steps)


def test_straight_creases_have_triangles_of_the_mesh_size():
    # Along a crease the tube is meshed on the fine lattice: a cube had 57k triangles at the
    # defaults, 44k of them within 12 fine cells of an edge, where its faces elsewhere have
    # triangles of the coarse lattice.  On flat faces and straight creases the fine triangles are
    # now merged (vertices removed, the rest kept in place).  Float-rotated cube, coarse 16, fine 128:
    # triangles within 12 fine cells of the edges (counted from the faces) at most 4 times what
    # triangles of the coarse cell's size would take there; closed, chi 2, vertices on F = 0,
    # crease samples from Newton on the two faces' equations on mesh edges, no angle below 5 (the
    # merging makes none below 10 degrees or below the smallest it replaces).
    rot = _rotation(3)
    u, v, w = (_lin(row) for row in rot)
    eq = f"Max(Abs({u}), Abs({v}), Abs({w})) - 0.7"
    box = np.array([[-1.3, 1.3]] * 3)
    m = singmesh.mesh(eq, box=box, coarse=16, fine=128)
    V, T = m.vertices, m.faces
    edges, cnt = _edges(T)
    assert np.all(cnt == 2)
    assert len(V) - len(edges) + len(T) == 2
    assert np.abs(np.abs(V @ rot.T).max(axis=1) - 0.7).max() <= 1e-10
    fine_cell, coarse_cell = 2.6 / m.stats["fine"], 2.6 / 16
    corners = np.array([[a, b, c] for a in (-0.7, 0.7) for b in (-0.7, 0.7) for c in (-0.7, 0.7)])
    ends = [(p, q) for i, p in enumerate(corners) for q in corners[i + 1:] if np.sum(p != q) == 1]
    a = np.linalg.solve(rot, np.array([e[0] for e in ends]).T).T
    b = np.linalg.solve(rot, np.array([e[1] for e in ends]).T).T
    band = 12 * fine_cell
    near = _segment_distance(V[T].mean(axis=1), a, b) <= band
    # Two faces meet at each edge: a band 2 * band wide on each, 1.4 long, 12 edges.
    allowed = 4 * (12 * 1.4 * 2 * band) / (coarse_cell ** 2 / 2)
    assert near.sum() <= allowed, (near.sum(), allowed)
    # Crease samples: Newton (one min-norm step: the equations are linear) on the two faces
    # u_i = +-0.7, u_j = +-0.7 from points off the edge; each lies on a mesh edge.
    rng = np.random.default_rng(5)
    samples = []
    for (p, q), pa, pb in zip(ends, a, b):
        i, j = np.nonzero(p == q)[0]
        g = rot[[i, j]]
        x = pa + rng.uniform(0.02, 0.98, (20, 1)) * (pb - pa) + rng.normal(scale=0.01, size=(20, 3))
        r = x @ g.T - np.array([p[i], p[j]])
        samples.append(x - r @ np.linalg.pinv(g).T)
    samples = np.concatenate(samples)
    assert _segment_distance(samples, V[edges[:, 0]], V[edges[:, 1]]).max() <= 1e-9
    P = V[T]
    ang = []
    for k in range(3):
        e1, e2 = P[:, (k + 1) % 3] - P[:, k], P[:, (k + 2) % 3] - P[:, k]
        ang.append(np.degrees(np.arccos(np.clip((e1 * e2).sum(1) / np.linalg.norm(e1, axis=1)
                                                / np.linalg.norm(e2, axis=1), -1, 1))))
    assert np.min(ang) >= 5.0


def test_stacked_boxes_rotated_are_closed():
    # The box standing on a larger one, joined by Min, float-rotated: a lattice line through the
    # small box's top face and the large box's bottom face (0.4 either side of the contact patch)
    # has the middle of its two roots on the patch, where F = 0 without sign change; read there as
    # +, both roots were taken for touchings, and the faces next to two edges had no events: their
    # strips were left out (321 open edges at fine 256, 602 after the retry at 512, ~50 s).  Between
    # two roots F has one sign: where it is zero to rounding at the middle, a quarter of the way
    # tells.  Closed, chi 2, vertices on F = 0, no triangle on the patch, the corners vertices and
    # crease samples (Newton on the pairs of face planes) on mesh edges with two triangles each.
    from scipy.spatial.transform import Rotation

    rot = np.array([[float(f"{c:.15g}") for c in row] for row in Rotation.random(random_state=1).as_matrix()])
    eq, corners, pairs, _, on = _stacked_boxes(rot)
    box = np.array([[-1.2, 1.2]] * 3)
    m = singmesh.mesh(eq, box=box, coarse=16, fine=128)
    V, T = m.vertices, m.faces
    edges, cnt = _edges(T)
    assert (cnt == 1).sum() == 0 and (cnt > 2).sum() == 0, np.bincount(cnt)
    assert len(V) - len(edges) + len(T) == 2
    F = _numpy(_expr(eq))
    assert np.abs(F(V)).max() <= 1e-10
    c = V[T].mean(axis=1) @ rot.T
    assert not np.any((np.abs(c[:, 2]) < 1e-9) & (np.abs(c[:, :2]).max(axis=1) < 0.3)), "triangles on the patch"
    _corners_and_creases(m, eq, pairs, box, corners, starts=400, least=50, on=on)
