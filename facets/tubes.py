"""Tubes: the leaves along curves of singular points, meshed as strips from the curve.

The leaves within ``CURVE_TUBE_RADIUS`` fine cells of a singular curve,
and the leaves next to them that failed the simplicity test (up to
``CURVE_TUBE_GROW`` cells away), are one box: the tube.  Outside it every
leaf is meshed as usual.  Each half-sheet of the surface through the curve
leaves the tube across its boundary along a path of face links, a *rail*;
inside the tube that half-sheet is the strip between its rail and the
curve.  Zipping each rail to the curve (each rail vertex joined to the
nearest curve vertex, the curve walked in between) meshes the strips:
every curve edge gets one triangle per half-sheet (4 on a double curve,
2 on a cuspidal edge, 6 on a triple curve), and no triangle joins two
sheets, since a strip lies on one.  Curve edges no strip reaches (an
isolated real line) are the one-dimensional part of the surface.
"""

from __future__ import annotations

import networkx as nx
import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from singmesh import tolerances as tol
from singmesh.boxes.octree import Octree


#: Special points of curves where sheets meet tangentially: the tube is
#: wider around them (``CURVE_BALL_GROW``).
BALL_KINDS = ("pinch point", "triple point", "crossing of curves", "change of type", "crossing of cuspidal edges")

#: Special points where the half-sheets of the curves meeting there stay
#: closer than a cell far out (where two cuspidal edges cross, the two
#: half-sheets between them are a lens as thin as the cube of the
#: distance): the whole ball of ``CURVE_MEET_BALL`` cells around them is
#: tube, its strips joining the rails where the sheets are apart to the
#: curves inside.
MEET_KINDS = ("crossing of cuspidal edges",)

#: Special points round which a half-sheet's rail turns back along the
#: curve it came along (the sheets of a double curve fold into one at a
#: pinch point): the rails' zigzags are not held near them.
TURN_KINDS = ("pinch point", "change of type", "end of the trace")


def balls(curves, kinds=BALL_KINDS) -> np.ndarray:
    """The special points of a :class:`~singmesh.skeleton.singular_curves.CurveSet` the tube widens around."""
    return np.array([sp.point for sp in curves.special if sp.kind in kinds]).reshape(-1, 3)


def ball_grow(fine_level: int) -> float:
    """How far (cells) the tube grows into non-simple leaves around pinch and triple points.

    ``CURVE_BALL_GROW`` up to ``CURVE_BALL_FINE`` cells per box, then as
    the square root of the cells per box (sheets meeting tangentially part
    as the square of the distance).
    """
    return tol.CURVE_BALL_GROW * max(1.0, float(np.sqrt((1 << fine_level) / tol.CURVE_BALL_FINE)))


def tangent_edges(curves) -> np.ndarray:
    """Which curve edges have branches that stay close far out (``CurveSet.wide``: tangent branches)."""
    # An empty CurveSet has no flags (and no edges).
    return curves.wide if len(curves.wide) == len(curves.edges) else np.zeros(len(curves.edges), bool)


def tangent_radius(curves) -> float:
    """The tube's radius (cells) along the wide edges."""
    return max(float(curves.wide_radius), tol.CURVE_TANGENT_RADIUS)


def tube_regions(box: np.ndarray, fine_level: int, curves) -> np.ndarray:
    """Boxes (k, 2, 3) the subdivision takes to the fine level: the tube and its margin.

    Along the curves ``CURVE_TUBE_GROW`` cells to spare (more where the
    sheets are tangent), and ``CURVE_BALL_GROW`` around pinch and triple points.
    """
    cell = (box[:, 1] - box[:, 0]) / (1 << fine_level)
    wide = tangent_edges(curves)
    b = balls(curves)
    reach = (ball_grow(fine_level) + 2) * cell
    m = balls(curves, MEET_KINDS)
    meet_reach = (tol.CURVE_MEET_BALL + 2) * cell
    return np.concatenate([
        _block_regions(box, fine_level, curves.points, curves.edges[~wide], pad=tol.CURVE_TUBE_GROW + 2),
        _block_regions(box, fine_level, curves.points, curves.edges[wide],
                       pad=tangent_radius(curves) + tol.CURVE_TUBE_GROW + 2, also=wide_vertices(curves)),
        np.stack([b - reach, b + reach], axis=1), np.stack([m - meet_reach, m + meet_reach], axis=1)])


def tube_leaves(tree: Octree, links, curves) -> np.ndarray:
    """Which leaves form the tube around the curves of a CurveSet: (N,) bool."""
    return _tube_leaves(tree, links, curves.points, curves.edges, balls(curves), tangent_edges(curves),
                        tangent_radius(curves), balls(curves, MEET_KINDS), wide_vertices(curves))


def tube_triangles(grouped, links, events, curves, tube_id: int, key0: int, cell: float, box: np.ndarray,
                   surface=None, traced=None):
    """The strips of the tube as triangles (keys (T, 3), points (T, 3, 3)); curve vertex j has key ``key0 + j``.

    With ``surface`` (F with kinks), a rail on a patch of F = 0 across
    which F keeps its sign (:func:`sign_kept`) gets no strip.
    """
    ends = np.array([v for v, sp in zip(curves.special_vertex.tolist(), curves.special)
                     if sp.kind == "end on the box"], np.int64)
    # The tube's links on the box's faces continue the rails where a
    # half-sheet leaves the tube through the box rather than through its
    # side (a curve running a few cells inside a face): away from where
    # the curves meet the box, whose half-sheets end on the box (below).
    # The whole tube's reach there (wider along tangent branches).
    radius = tangent_radius(curves) if tangent_edges(curves).any() else tol.CURVE_TUBE_RADIUS
    far = face_rail_events(events.point, curves.points, box, cell,
                           radius + tol.CURVE_TUBE_GROW + tol.CURVE_FACE_RAIL)
    if len(ends) and not far.all():
        # A half-sheet whose trace on a face runs from one curve end to
        # another inside the tube (a curve that dips a few cells into the
        # box and comes back out through the same face), or passes a
        # curve end without leaving it: that trace is its rail.
        every = rails(grouped, links, tube_id, np.ones(len(events.point), bool))
        far = face_chords(every, events.point, far, curves.points[ends], box, cell)
    # Along creases the rails' snaps never step back (see strip_triangles).
    steady = np.zeros(len(curves.points), bool)
    for c in curves.pieces:
        if c.type == "crease":
            steady[np.asarray(c.vertices)] = True
    # Round the ends of a curve's sheets (a pinch point, where the
    # double curve's sheets fold into one) a rail turns back along the
    # curve: no zigzag is held there (see _no_zigzags).
    turns = np.zeros(len(curves.points), bool)
    folds = np.array([v for v, sp in zip(curves.special_vertex.tolist(), curves.special) if sp.kind in TURN_KINDS],
                     np.int64)
    if len(folds):
        turns = cKDTree(curves.points[folds]).query(curves.points)[0] <= (
            tol.CURVE_TUBE_RADIUS + tol.CURVE_TUBE_GROW) * cell
    # The rails read the squares on the box's faces paired by tracing
    # (``traced``: grouped and links of boxes.faces.rail_links), the face
    # chords above the boxes' own pairing: a trace between two curve ends
    # that only tracing joins leaves the tube's side (fuzz s1-354).
    rail_list = rails(*(traced if traced is not None else (grouped, links)), tube_id, far)
    if surface is not None and rail_list:
        # Where two solids joined by Min touch along a face (two boxes
        # stacked), the contact patch is F = 0 with F < 0 on both sides:
        # not the union's boundary, which is meshed where F changes sign.
        # Its zeros on split planes still make links, and at the concave
        # rim round it a rail on the patch would be zipped to the rim's
        # crease as a third half-sheet.
        rail_list = _off_patches(rail_list, sign_kept(surface, events.point, cell))
    return strip_triangles(rail_list, events.point, events.key, curves.points,
                           curves.edges, key0 + np.arange(len(curves.points)), ends,
                           reach=4.0 * (tol.CURVE_BALL_GROW + 2) * cell, box=box,
                           steady=steady if steady.any() else None, turns=turns,
                           stub=tol.CURVE_RAIL_STUB * cell,
                           near=radius + tol.CURVE_TUBE_GROW + tol.CURVE_FACE_RAIL + tol.CURVE_FACE_GAP, cell=cell)


def _off_patches(rail_list: list, kept: np.ndarray) -> list:
    """The rails without their events on patches where F keeps its sign (``kept``, per event).

    A rail wholly on such a patch goes; one that runs onto it from a
    sheet of the surface (the patch's links join the side face's at the
    tube's boundary) is cut into its runs off the patch.
    """
    out = []
    for ev, closed in rail_list:
        k = kept[ev]
        if not k.any():
            out.append((ev, closed))
            continue
        if closed:
            # Start the loop on the patch, so that no run wraps round.
            first = int(np.argmax(k))
            ev, k = np.roll(ev, -first), np.roll(k, -first)
        off = np.nonzero(~k)[0]
        for run in np.split(off, np.nonzero(np.diff(off) > 1)[0] + 1):
            if len(run) > 1:
                out.append((ev[run], False))
    return out


def sign_kept(surface, points: np.ndarray, cell: float) -> np.ndarray:
    """(k,) bool: F has one sign a quarter cell to either side of the surface at the points (along grad F).

    A point on a patch of F = 0 without sign change (two solids of a Min
    touching along a face, F < 0 on both sides); where grad F is zero or
    undefined, False.
    """
    p = np.asarray(points, float).reshape(-1, 3)
    with np.errstate(all="ignore"):
        g = surface.gradient(p)
        n = g / np.linalg.norm(g, axis=1, keepdims=True)
        step = tol.SIGN_KEPT_STEP * cell * n
        a, b = surface(p + step), surface(p - step)
    ok = np.isfinite(n).all(axis=1) & np.isfinite(a) & np.isfinite(b)
    return ok & (((a < 0) & (b < 0)) | ((a > 0) & (b > 0)))


def face_rail_events(points: np.ndarray, curve_points: np.ndarray, box: np.ndarray, cell: float,
                     keep_off: float) -> np.ndarray:
    """Which events a rail may follow on the box's faces: (N,) bool.

    Not those within ``keep_off`` cells of a curve's point on the box:
    there its half-sheets' traces on the face leave the curve's end, and
    their rails end on the box.  Distances are in cells along each axis
    (the tube's own measure: the cells of a box are not cubes; in the
    largest cell, a curve 6 x-cells from a face along 20 y-cells was all
    within reach of its ends).
    """
    on_box = faces_of(curve_points, box).any(axis=1)
    far = np.ones(len(points), bool)
    if not on_box.any():
        return far
    axes = _axis_cells(box, cell)
    d_end = cKDTree(curve_points[on_box] / axes).query(points / axes, distance_upper_bound=keep_off)[0]
    return d_end > keep_off


def face_chords(rail_list, points: np.ndarray, far: np.ndarray, end_points: np.ndarray, box: np.ndarray,
                cell: float) -> np.ndarray:
    """``far`` with the events added of face traces that are whole half-sheets' rails near the curves' ends.

    ``rail_list`` are the tube's rails with every face link on them.  A run
    of their events on the box's faces, starting and ending within
    ``CURVE_FACE_GAP`` cells of two different curve ends, is the whole
    trace of a half-sheet that lies inside the tube between the curve and
    the face: it is a rail.  So is a stretch of such a run that is not
    flagged (near a curve end), has events of the rail before and after
    it, and comes no nearer than ``CURVE_FACE_GAP`` cells to any curve
    end: a trace that passes the end without leaving it (a sheet's trace
    on the face turning back beside the end, fuzz s3-410: its rail broke
    there, and both pieces were fanned to the end).
    """
    axes = _axis_cells(box, cell)
    tree = cKDTree(end_points / axes)
    out = far.copy()
    for ev, closed in rail_list:
        if closed or len(ev) < 2:
            continue
        run = faces_of(points[ev], box).any(axis=1)
        # Maximal runs of consecutive such events.
        edges = np.diff(np.concatenate([[0], run.astype(np.int8), [0]]))
        for a, b in zip(np.nonzero(edges == 1)[0].tolist(), np.nonzero(edges == -1)[0].tolist()):
            if b - a < 2:
                continue
            d, k = tree.query(points[ev[[a, b - 1]]] / axes)
            if len(end_points) > 1 and k[0] != k[1] and d.max() <= tol.CURVE_FACE_GAP:
                out[ev[a:b]] = True
        # Stretches of face events not flagged, inside the rail, away from every end.
        gap = run & ~far[ev]
        edges = np.diff(np.concatenate([[0], gap.astype(np.int8), [0]]))
        for a, b in zip(np.nonzero(edges == 1)[0].tolist(), np.nonzero(edges == -1)[0].tolist()):
            if a == 0 or b == len(ev):
                continue
            if tree.query(points[ev[a:b]] / axes)[0].min() > tol.CURVE_FACE_GAP:
                out[ev[a:b]] = True
    return out


def curve_samples(points: np.ndarray, edges: np.ndarray, spacing: float) -> np.ndarray:
    """Points along the curve graph's edges at most ``spacing`` apart, and all its points."""
    if len(edges) == 0:
        return np.asarray(points, float).reshape(-1, 3)
    a, b = points[edges[:, 0]], points[edges[:, 1]]
    n = np.maximum(1, np.ceil(np.linalg.norm(b - a, axis=1) / spacing).astype(np.int64))
    owner = np.repeat(np.arange(len(edges)), n)
    t = (np.arange(n.sum()) - np.repeat(np.cumsum(n) - n, n)) / np.repeat(n, n)
    return np.vstack([a[owner] + t[:, None] * (b - a)[owner], points])


def edge_samples(points: np.ndarray, edges: np.ndarray, spacing: float, also: np.ndarray | None = None) -> np.ndarray:
    """Points along the given edges at most ``spacing`` apart, with their ends and the points ``also`` (indices).

    For a part of the curve graph (the wide edges): :func:`curve_samples`
    adds every point of the graph, and a tube as wide as the wide edges'
    round every curve vertex swallows whole sheets between curves that
    are not wide (fuzz s4-750: a patch between three double curves, 15
    cells across, all tube and so without a rail or a strip).
    """
    extra = np.asarray(points, float)[np.asarray(also, np.int64)] if also is not None else np.zeros((0, 3))
    if len(edges) == 0:
        return extra
    used, inverse = np.unique(edges, return_inverse=True)
    return np.vstack([curve_samples(np.asarray(points, float)[used], inverse.reshape(edges.shape), spacing), extra])


def wide_vertices(curves) -> np.ndarray:
    """Indices of the curve points the wide tube goes round besides its edges: every vertex of a piece with a wide edge.

    A piece wide on a stretch only (its cusp's coefficient varying along
    it) has tangent half-sheets past that stretch too: the lens round the
    cuspidal edge of fuzz s3-925, thinner than a cell, needs the wide tube
    along the whole piece (else its tip is left out, 4 cells from the mesh).
    Pieces without a wide edge keep the usual tube.
    """
    wide = tangent_edges(curves)
    if not wide.any():
        return np.zeros(0, np.int64)
    n = len(curves.points)
    e = np.sort(curves.edges[wide], axis=1)
    keys = e[:, 0] * n + e[:, 1]
    out = [e.ravel()]
    for c in curves.pieces:
        # A wide edge of the piece's own, not a wide piece's end it shares
        # (a triple point where a wide edge meets double curves).
        v = np.asarray(c.vertices, np.int64) if c.vertices is not None else np.zeros(0, np.int64)
        pairs = np.sort(np.stack([v[:-1], v[1:]], axis=1), axis=1)
        if len(pairs) and np.isin(pairs[:, 0] * n + pairs[:, 1], keys).any():
            out.append(v)
    return np.unique(np.concatenate(out))


def untraced_points(curves, spacing: float) -> np.ndarray:
    """Points (k, 3) round which the tube's face squares keep their own pairing (not traced for the rails).

    The samples of every curve piece but the A1 double curves, and every
    special point (ends on the box, pinch and triple points): there the
    half-sheets' traces on a face meet, or F's gradient falls faster than
    the distance and the face events are as far off F = 0 as it makes
    them (fuzz s1-704, a corank 2 edge 0.7 cells inside a face).  Beside
    a double curve between its special points the gradient grows as the
    distance and the two sheets' traces on a face a cell or less away run
    apart: tracing parts them there (fuzz s3-726, two planes crossing
    along a line 0-3.3 cells inside a face: untraced, the squares within
    1.5 cells of it joined one sheet's trace to the other's and the rails
    broke, edges of six triangles).
    """
    keep = np.zeros(len(curves.edges), bool)
    if len(curves.edges):
        double = np.zeros(len(curves.points), bool)
        for c in curves.pieces:
            if c.type == "A1 double curve" and c.vertices is not None:
                double[np.asarray(c.vertices, np.int64)] = True
        keep = ~(double[curves.edges[:, 0]] & double[curves.edges[:, 1]])
    special = np.asarray(curves.points, float)[np.asarray(curves.special_vertex, np.int64)].reshape(-1, 3)
    if not keep.any():
        return special
    return np.vstack([curve_samples(curves.points, curves.edges[keep], spacing), special])


def _block_regions(tree_box: np.ndarray, fine_level: int, points: np.ndarray, edges: np.ndarray,
                   pad: float, block: int = 8, also: np.ndarray | None = None) -> np.ndarray:
    """Boxes (k, 2, 3) covering the curve with ``pad`` fine cells to spare.

    The blocks of ``block`` fine cells the curve passes through, widened:
    few regions for a long curve (the subdivision tests every box against
    every region).  With ``also`` (indices of points) the edges, their ends
    and those points only (:func:`edge_samples`), else every point of the
    graph too.
    """
    cell = (tree_box[:, 1] - tree_box[:, 0]) / (1 << fine_level)
    spacing = 0.5 * float(cell.min()) * block
    if also is not None:
        s = edge_samples(points, edges, spacing, also)
    else:
        s = curve_samples(points, edges, spacing) if len(edges) else np.zeros((0, 3))
    lattice = np.floor((s - tree_box[:, 0]) / (cell * block)).astype(np.int64)
    blocks = np.unique(lattice, axis=0)
    lo = tree_box[:, 0] + blocks * cell * block - pad * cell
    hi = lo + cell * block + 2 * pad * cell
    return np.stack([lo, hi], axis=1)


def _tube_leaves(tree: Octree, links, points: np.ndarray, edges: np.ndarray,
                 balls: np.ndarray | None = None, wide: np.ndarray | None = None,
                 wide_radius: float = tol.CURVE_TANGENT_RADIUS, meets: np.ndarray | None = None,
                 wide_also: np.ndarray | None = None) -> np.ndarray:
    """Which leaves form the tube around the curve graph (points, edges).

    Around the points ``balls`` (pinch and triple points, where sheets
    meet tangentially and stay close further out) the non-simple leaves
    join up to :func:`ball_grow` cells away.  Along the edges flagged
    ``wide`` (tangent sheets: a tacnode edge, whose sheets part only as
    the square of the distance) the tube's radius is ``wide_radius``
    cells, so that the sheets are apart where they leave it.
    Around the points ``meets`` (cuspidal edges crossing) every leaf within
    ``CURVE_MEET_BALL`` cells is tube.  The wide tube goes round the wide
    edges, their ends and the points ``wide_also`` (indices), no other
    point (:func:`wide_vertices`).

    Returns
    -------
    (N,) bool
    """
    n = len(tree.level)
    inside = np.zeros(n, bool)
    if len(points) == 0 or n == 0:
        return inside
    centre = tree.corner + tree.size[:, None] / 2.0
    half = tree.size / 2.0
    wide = np.zeros(len(edges), bool) if wide is None else np.asarray(wide, bool)
    reach = np.zeros(n, bool)
    for flag, radius in ((False, tol.CURVE_TUBE_RADIUS), (True, wide_radius)):
        sel = wide == flag
        if not sel.any():
            continue
        # The wide tube round the wide edges (and wide_also) only; the
        # narrow one round every point of the graph too.
        spacing = 0.25 * float(tree.cell.min())
        s = edge_samples(points, edges[sel], spacing, wide_also) if flag else curve_samples(points, edges[sel], spacing)
        s = (s - tree.box[:, 0]) / tree.cell
        grow_to = radius - tol.CURVE_TUBE_RADIUS + tol.CURVE_TUBE_GROW
        dist, _ = cKDTree(s).query(centre, p=np.inf, distance_upper_bound=float(half.max()) + grow_to + 1)
        inside |= dist <= half + radius
        reach |= dist <= half + grow_to
    if balls is not None and len(balls):
        b = (np.asarray(balls, float).reshape(-1, 3) - tree.box[:, 0]) / tree.cell
        d_ball, _ = cKDTree(b).query(centre, p=np.inf)
        reach |= d_ball <= half + ball_grow(tree.fine_level)
    if meets is not None and len(meets):
        m = (np.asarray(meets, float).reshape(-1, 3) - tree.box[:, 0]) / tree.cell
        d_meet, _ = cKDTree(m).query(centre, p=np.inf)
        inside |= d_meet <= half + tol.CURVE_MEET_BALL
    # Leaves that failed the simplicity test next to the tube join it:
    # outside it every leaf must be a union of discs.
    both = (links.minus >= 0) & (links.plus >= 0)
    a, b = links.minus[both], links.plus[both]
    for _ in range(int(max(tol.CURVE_TUBE_GROW, ball_grow(tree.fine_level))) + 1):
        grow = np.zeros(n, bool)
        grow[b[inside[a]]] = True
        grow[a[inside[b]]] = True
        grow &= ~inside & ~tree.simple & reach
        if not grow.any():
            break
        inside |= grow
    return _fill_holes(tree, links, _fill_diagonal_edges(links, inside))


def _fill_holes(tree: Octree, links, inside: np.ndarray) -> np.ndarray:
    """The tube with its holes filled: small groups of leaves it encloses.

    A simple leaf among the non-simple ones the tube grew into (near a
    corner of creases in general position) stays outside the tube; the
    tube's boundary round it is a closed rail a cell or two across, whose
    strip to the curve covers what the rail of that half-sheet already
    covers (four triangles on the curve edges there).  A group of leaves
    outside the tube, joined by the surface's links, that meets neither
    the box's boundary nor more than ``TUBE_HOLE_CELLS`` cells of space
    is a hole: it joins the tube.
    """
    sq = links.link_square
    if len(sq) == 0 or not inside.any():
        return inside
    minus, plus = links.minus[sq], links.plus[sq]
    n = len(inside)
    out = ~inside
    both = (minus >= 0) & (plus >= 0)
    a, b = minus[both], plus[both]
    join = out[a] & out[b]
    _, label = connected_components(coo_matrix((np.ones(int(join.sum())), (a[join], b[join])), shape=(n, n)),
                                    directed=False)
    # Groups that reach the box's boundary (a link square with one side
    # outside the box) or hold no link at all are not holes.
    on_surface = np.zeros(n, bool)
    on_surface[minus[minus >= 0]] = True
    on_surface[plus[plus >= 0]] = True
    open_ = np.zeros(label.max() + 1, bool)
    edge = (minus < 0) | (plus < 0)
    open_[label[np.where(minus >= 0, minus, plus)[edge]]] = True
    lo = np.full((label.max() + 1, 3), np.iinfo(np.int64).max)
    hi = np.full((label.max() + 1, 3), np.iinfo(np.int64).min)
    sel = out & on_surface
    np.minimum.at(lo, label[sel], tree.corner[sel])
    np.maximum.at(hi, label[sel], tree.corner[sel] + tree.size[sel, None])
    small = (hi - lo).max(axis=1) <= tol.TUBE_HOLE_CELLS
    hole = sel & small[label] & ~open_[label]
    if not hole.any():
        return inside
    return inside | hole


def _fill_diagonal_edges(links, inside: np.ndarray, rounds: int = 4) -> np.ndarray:
    """The tube with the leaves added that make it meet itself only across faces at events.

    Where two tube leaves share only a lattice edge (the two other leaves
    round it outside the tube), an event on that edge has four links on
    the tube's boundary instead of two: two rails pass through it, and
    the strips zipping both to the curve share the edge from it to the
    curve (four triangles off the curve).  The two outer leaves round such
    an event (the outer sides of its boundary links) join the tube.
    """
    if len(links.link_square) == 0:
        return inside
    sq = links.link_square
    minus, plus = links.minus[sq], links.plus[sq]
    for _ in range(rounds):
        in_m = (minus >= 0) & inside[np.maximum(minus, 0)]
        in_p = (plus >= 0) & inside[np.maximum(plus, 0)]
        boundary = in_m != in_p
        if not boundary.any():
            break
        ends = np.concatenate([links.start[boundary], links.end[boundary]])
        events, count = np.unique(ends, return_counts=True)
        crowded = events[count > 2]
        if len(crowded) == 0:
            break
        at = boundary & (np.isin(links.start, crowded) | np.isin(links.end, crowded))
        outer = np.concatenate([minus[at & in_p], plus[at & in_m]])
        inside = inside.copy()
        inside[outer[outer >= 0]] = True
    return inside


def rails(box_links_arrays, links, tube_id: int, face_ok: np.ndarray | None = None) -> list[tuple[np.ndarray, bool]]:
    """The tube's rails: paths of the links on its boundary inside the domain.

    Parameters
    ----------
    box_links_arrays : (box, src, dst, square) from
        :func:`singmesh.facets.cycles.box_links` with the tube grouped
    links : FaceLinks
    tube_id : int
    face_ok : (E,) bool, optional
        Events a link on the domain's boundary may join: such a link
        whose two events are flagged belongs to the rails too, unless its
        square was paired along its boundary (no graph axis: two sheets
        may be joined there).

    Returns
    -------
    list of (events (k,) int64, closed)
    """
    box, src, dst, sq = box_links_arrays
    inner = (links.minus[sq] >= 0) & (links.plus[sq] >= 0)
    if face_ok is not None:
        inner |= face_ok[src] & face_ok[dst] & ~links.ambiguous[sq] & ~links.inconsistent[sq]
    mine = (box == tube_id) & inner
    src, dst = src[mine], dst[mine]
    if len(src) == 0:
        return []
    nodes, inv = np.unique(np.concatenate([src, dst]), return_inverse=True)
    a, b = inv[: len(src)], inv[len(src):]
    m = len(nodes)
    indeg = np.bincount(b, minlength=m)
    outdeg = np.bincount(a, minlength=m)
    # Every link in exactly one trail: an event where two rails touch (two
    # links out of it) continues one and starts the other, and a trail
    # that runs into an earlier one keeps its last link (no gap).
    order = np.argsort(a, kind="stable")
    first_out = np.concatenate([[0], np.cumsum(outdeg)])
    left = outdeg.copy()
    out = []
    starts = np.nonzero(outdeg > indeg)[0].tolist()
    for first in starts + np.nonzero(outdeg > 0)[0].tolist():
        while left[first] > 0:
            path = [first]
            cur = first
            while left[cur] > 0:
                link = order[first_out[cur] + outdeg[cur] - left[cur]]
                left[cur] -= 1
                cur = int(b[link])
                path.append(cur)
                if cur == first:
                    break
            closed = path[-1] == path[0]
            if closed:
                path = path[:-1]
            out.append((nodes[np.array(path)], closed))
    return out


def strip_triangles(rail_list, event_points: np.ndarray, event_keys: np.ndarray, curve_points: np.ndarray,
                    curve_edges: np.ndarray, curve_keys: np.ndarray, box_ends: np.ndarray, reach: float,
                    box: np.ndarray | None = None, steady: np.ndarray | None = None,
                    turns: np.ndarray | None = None, stub: float | None = None, near: float | None = None,
                    cell: float | None = None):
    """Triangles zipping each rail to the curve.

    Parameters
    ----------
    rail_list : list of (event indices, closed)
    event_points, event_keys : positions and vertex keys of the events
    curve_points, curve_edges, curve_keys : the curve graph and its vertex keys
    box_ends : (k,) int64 curve vertices on the box's boundary
    reach : float
        A rail's end on the box is joined to a curve end on the box at most
        this far away.
    box : (3, 2) ndarray, optional
        The domain: only rail ends on its boundary are joined so.
    steady : (c,) bool, optional
        Curve vertices (of creases) at which a rail's snap never steps
        back onto the one or two vertices it just came from: a rail some
        cells off a curve in general position zigzags across the lattice,
        and its nearest curve vertex with it, which would zip one curve
        edge from one side twice.
    turns : (c,) bool, optional
        Curve vertices near which a rail may turn back along the curve
        (pinch points): its steps back there are not taken for zigzags
        (:func:`_no_zigzags`).
    stub : float, optional
        Rails with both ends on one face of the box, this close together,
        are pieces of a longer rail that ran along the face: each is joined
        to the nearest rail end on that face (:func:`_join_stubs`).
    near, cell : float, optional
        Rail ends on a face farther than ``near`` cells (``cell`` the
        largest side) from every curve end on the box are pieces of a
        half-sheet's trace along the face, joined across it
        (:func:`_chain_on_faces`; without them, farther than ``reach``).

    Returns
    -------
    keys : (T, 3) int64, points : (T, 3, 3) float
        Triangles as vertex keys and positions, oriented as the rails are
        (the side of F > 0 on the left seen from grad F).
    """
    if not rail_list or len(curve_points) == 0:
        return np.zeros((0, 3), np.int64), np.zeros((0, 3, 3))
    g = nx.Graph()
    g.add_nodes_from(range(len(curve_points)))
    d = np.linalg.norm(curve_points[curve_edges[:, 0]] - curve_points[curve_edges[:, 1]], axis=1)
    g.add_weighted_edges_from(zip(curve_edges[:, 0].tolist(), curve_edges[:, 1].tolist(), d.tolist()))
    tree = cKDTree(curve_points)
    _, piece = connected_components(coo_matrix((np.ones(len(curve_edges)), (curve_edges[:, 0], curve_edges[:, 1])),
                                               shape=(len(curve_points),) * 2), directed=False)
    end_tree = cKDTree(curve_points[box_ends]) if len(box_ends) else None
    if box is not None:
        rail_list = _chain_on_faces(rail_list, event_points, curve_points[box_ends], reach, box, near, cell)
        if stub is not None:
            rail_list = _join_stubs(rail_list, event_points, box, stub)
    tris: list[tuple] = []  # (vertex, vertex, vertex); vertex = ("e", event) or ("c", curve vertex)

    def walk(u: int, v: int) -> list[int]:
        if u == v:
            return [u]
        if g.has_edge(u, v):
            return [u, v]
        try:
            return nx.shortest_path(g, u, v, weight="weight")
        except nx.NetworkXNoPath:
            return [u, v]

    for events, closed in rail_list:
        r = event_points[events]
        dist, snap = tree.query(r)
        snap = _one_piece(snap, r, piece, curve_points)
        if steady is not None:
            if closed and len(events) > 2:
                # A closed rail starts where it is nearest the curve (along
                # a crease, not at the turn around a corner of creases,
                # whose zigzag across the wedge the held snaps must see).
                k0 = int(np.argmin(dist))
                events, r, snap = np.roll(events, -k0), np.roll(r, -k0, axis=0), np.roll(snap, -k0)
            snap = _steady_snaps(snap, steady, g, closed)
        snap = _no_zigzags(snap, g, turns)
        if not closed:
            snap = _no_excursions(snap, g, turns)
        m = len(events)
        steps = m if closed else m - 1
        zipped = set()  # the curve edges this rail's strip reaches
        for i in range(steps):
            j = (i + 1) % m
            w = walk(int(snap[i]), int(snap[j]))
            zipped.update(zip(w[:-1], w[1:]))
            ri, rj = ("e", int(events[i])), ("e", int(events[j]))
            k = len(w) - 1
            if k == 0:
                tris.append((ri, rj, ("c", w[0])))
                continue
            mid = (r[i] + r[j]) / 2
            jm = int(np.argmin(np.linalg.norm(curve_points[w] - mid, axis=1)))
            for l in range(k, jm, -1):
                tris.append((rj, ("c", w[l]), ("c", w[l - 1])))
            tris.append((ri, rj, ("c", w[jm])))
            for l in range(jm, 0, -1):
                tris.append((ri, ("c", w[l]), ("c", w[l - 1])))
        if closed or end_tree is None:
            continue
        # The rail's ends lie on the box: the strip reaches the curve's end
        # there (the cap edge from the rail's end to it is on the box).
        zipped |= {(b, a) for a, b in zipped}
        for end, s in ((0, int(snap[0])), (m - 1, int(snap[-1]))):
            if box is not None and not _on_boundary(r[end], box):
                continue
            w = _end_walk(walk, end_tree, box_ends, r[end], s, zipped, reach)
            if w is None:
                continue
            e = w[-1]
            re_ = ("e", int(events[end]))
            # Rail end and curve end on two faces of the box (the curve
            # leaves near a box edge): the strip's cap edge turns at the
            # surface's crossing of that box edge.
            corner = None if box is None else _corner_event(r[end], curve_points[e], event_points, box, reach)
            if end == 0:   # ... s_0 -> ... -> e_0 -> r_0 -> r_1 ...
                for l in range(len(w) - 1):
                    tris.append((re_, ("c", w[l]), ("c", w[l + 1])))
                if corner is not None:
                    tris.append((re_, ("c", e), ("e", corner)))
            else:          # ... r_m -> e_m -> ... -> s_m ...
                w = w[::-1]
                for l in range(len(w) - 1):
                    tris.append((re_, ("c", w[l]), ("c", w[l + 1])))
                if corner is not None:
                    tris.append((re_, ("e", corner), ("c", e)))
    if not tris:
        return np.zeros((0, 3), np.int64), np.zeros((0, 3, 3))
    kind = np.array([[v[0] == "e" for v in t] for t in tris])
    idx = np.array([[v[1] for v in t] for t in tris], np.int64)
    keys = np.where(kind, event_keys[np.where(kind, idx, 0)], curve_keys[np.where(kind, 0, idx)])
    pts = np.where(kind[..., None], event_points[np.where(kind, idx, 0)], curve_points[np.where(kind, 0, idx)])
    # Two rails of one half-sheet can snap to the same vertices: a triangle
    # made twice is kept once; one whose corners coincide is dropped.
    good = (keys[:, 0] != keys[:, 1]) & (keys[:, 1] != keys[:, 2]) & (keys[:, 0] != keys[:, 2])
    if box is not None:
        # A triangle with its three corners on one face of the box lies in
        # the face, not on the surface: a face rail's link next to a curve
        # end on that face, zipped to the end (fuzz s1-186: 18 of them, two
        # vertices closer than 1e-9 of the box; 4 without face rails).  The
        # strip's edge from the end to the rail is then on the box.
        good &= ~faces_of(pts, box).all(axis=1).any(axis=1)
    return keys[good], pts[good]


def _end_walk(walk, end_tree: cKDTree, box_ends: np.ndarray, p: np.ndarray, s: int, zipped: set, reach: float):
    """The curve's walk from a rail end's snap ``s`` to the curve end on the box it is fanned to, or None.

    The nearest curve end within ``reach`` of the rail end ``p``, unless
    its walk goes over curve edges the rail's own strip reaches
    (``zipped``: pairs both ways): then, of the ends at most twice as far,
    the one whose walk goes over fewest.  A rail beside a curve that runs
    a few cells from the box over all its length (its trace on a face, an
    arc from a face back to it) has both ends near both curve ends: each
    of its ends is fanned to the curve end it points to, not back over the
    rail's own strip, not even partly: a rail beside a curve running from
    one face to the next within 4 cells of the first (fuzz s3-818) ends
    nearer the far curve end, whose walk went back over some of the edges
    its strip zipped (edges of three and five triangles).
    """
    found = end_tree.query(p, k=min(4, len(box_ends)), distance_upper_bound=reach)
    dist, which = np.atleast_1d(found[0]), np.atleast_1d(found[1])
    walks = []
    for d, k in zip(dist.tolist(), which.tolist()):
        if np.isfinite(d):
            w = walk(s, int(box_ends[k]))
            walks.append((sum((a, b) in zipped for a, b in zip(w[:-1], w[1:])), d, w))
    if not walks:
        return None
    over, d0, w = walks[0]
    if over == 0:
        return w
    return min((c for c in walks if c[1] <= 2.0 * d0), key=lambda c: (c[0], c[1]))[2]


def _one_piece(snap: np.ndarray, r: np.ndarray, piece: np.ndarray, curve_points: np.ndarray) -> np.ndarray:
    """The rail's snaps with its short excursions onto another curve re-snapped to the curve it runs along.

    A rail on the tube's wall between two curves some cells apart (their
    tubes nearly meet) can come nearer the other curve for an event or
    two and go back: a strip stepping from one curve to another, which
    the curve graph does not join, makes a triangle across the gap from
    a vertex of one curve to one of the other (fuzz s1-614, s1-302: open
    and non-manifold edges between two double curves 12 cells apart).
    A run of snaps on another piece of the curve graph, between two runs
    on one piece and at most ``CURVE_ZIGZAG_STEPS`` events long, goes to
    the nearest vertex of that piece, when such runs are at most a quarter
    of the rail: a rail that alternates between two curves all along (a
    half-sheet between them poking out of the tubes) is left as it is.
    """
    lab = np.array(piece[snap])
    change = np.nonzero(lab[1:] != lab[:-1])[0] + 1
    if len(change) < 2:
        return snap
    out = np.array(snap)
    bounds = np.concatenate([[0], change, [len(snap)]])
    moved = 0
    for k in range(1, len(bounds) - 2):
        a, b = int(bounds[k]), int(bounds[k + 1])
        around = lab[a - 1]
        if lab[b] != around or b - a > tol.CURVE_ZIGZAG_STEPS:
            continue
        mine = np.nonzero(piece == around)[0]
        d = np.linalg.norm(r[a:b, None, :] - curve_points[mine][None], axis=2)
        out[a:b] = mine[np.argmin(d, axis=1)]
        lab[a:b] = around
        moved += b - a
    return out if 4 * moved <= len(snap) else snap


def _steady_snaps(snap: np.ndarray, steady: np.ndarray, g: nx.Graph, closed: bool = False) -> np.ndarray:
    """The rail's snaps, with a step whose walk would start back along the last one held (``steady`` vertices).

    Along a crease a rail never walks back over the curve edges it just
    zipped: such a step is a zigzag of the rail (across the lattice, or
    across the bisector of the wedge at a corner of creases), not a turn.
    A closed rail goes round twice and keeps the second round: its first
    events are held against the last ones (a rail that starts inside a
    zigzag would zip the closing step's curve edge twice, once reversed).
    """
    if closed and len(snap) > 2:
        return _steady_snaps(np.concatenate([snap, snap]), steady, g)[len(snap):]
    snap = np.array(snap)
    cur, came_from = int(snap[0]), -1
    for i in range(1, len(snap)):
        s = int(snap[i])
        if s == cur:
            continue
        try:
            path = nx.shortest_path(g, cur, s, weight="weight")
        except nx.NetworkXNoPath:
            path = [cur, s]
        if steady[s] and steady[cur] and path[1] == came_from:
            snap[i] = cur
            continue
        cur, came_from = s, int(path[-2])
    return snap


def _no_zigzags(snap: np.ndarray, g: nx.Graph, turns: np.ndarray | None = None) -> np.ndarray:
    """The rail's snaps without its excursions back along the curve and forward again.

    Where the tube's wall is not straight (the non-simple leaves joined to
    the balls round pinch and triple points, a wall in general position) a
    rail can run a few cells back along the curve and then forward past
    where it turned: its nearest curve vertices go back and forth, and the
    strip zips the same curve edges two or three times from one side
    (edges of 6 or 8 triangles where two sheets cross).  A step back
    along the edge the rail last came along is held at the vertex it
    left when the rail comes forward past that vertex again within
    ``CURVE_ZIGZAG_STEPS`` steps; otherwise it is a turn (round the end of
    a curve, or onto another curve through a crossing) and is kept, as
    is every step back from a vertex flagged in ``turns``.
    """
    snap = np.array(snap)
    n = len(snap)

    def first_step(a: int, b: int) -> int:
        try:
            return nx.shortest_path(g, a, b, weight="weight")[1]
        except nx.NetworkXNoPath:
            return b

    cur, came_from = int(snap[0]), -1
    i = 1
    while i < n:
        s = int(snap[i])
        if s == cur:
            i += 1
            continue
        try:
            path = nx.shortest_path(g, cur, s, weight="weight")
        except nx.NetworkXNoPath:
            path = [cur, s]
        if came_from >= 0 and path[1] == came_from and not (turns is not None and turns[cur]):
            ahead = [j for j in range(i + 1, min(n, i + 1 + tol.CURVE_ZIGZAG_STEPS))
                     if int(snap[j]) != cur and first_step(cur, int(snap[j])) != came_from]
            if ahead:
                snap[i:ahead[0]] = cur
                i = ahead[0]
                continue
        cur, came_from = s, int(path[-2])
        i += 1
    return snap


def _no_excursions(snap: np.ndarray, g: nx.Graph, turns: np.ndarray | None = None) -> np.ndarray:
    """An open rail's snaps without its excursions, through a crossing of curves, out along a branch and back.

    A rail on the ball round a crossing of curves runs ten cells or so
    from them, where the nearest curve vertex need not be on a branch its
    half-sheet bounds: beside f1's singular point a cell from the crossing
    of fuzz s2-66 a sheet's rail went from one branch past the crossing
    out along a third branch and back, then onto a fourth and back, before
    the branch it ends along (those edges zipped twice by one half-sheet:
    six triangles).  The walk over the curve graph that the snaps make is
    reduced (each step straight back along the edge just walked cancels
    it) and every event snapped to the vertex of the reduced walk it was
    on.  Only for rails whose walk passes a vertex where curves meet (three
    or more edges); a step back from a turn (``turns``: round a pinch
    point a rail comes back along the curve) or a curve's end is kept,
    the rail's other excursions still cancelled.
    """
    snap = np.asarray(snap)
    if len(snap) < 3:
        return snap
    walk, at = [int(snap[0])], [0]
    for s in snap[1:].tolist():
        cur = walk[-1]
        if s != cur:
            try:
                path = nx.shortest_path(g, cur, s, weight="weight")
            except nx.NetworkXNoPath:
                return snap
            walk += path[1:]
        at.append(len(walk) - 1)
    if not any(g.degree(v) >= 3 for v in walk):
        return snap
    stack, depth, cancelled = [], [], False
    for v in walk:
        # A step back from a turn or a curve's end is the rail's own way
        # round it (round a pinch point a rail comes back along the
        # curve): kept, while an excursion elsewhere on the same rail is
        # still cancelled (fuzz s4-850: a rail round the pinch point of
        # f2's double line also went out past the triple point where f1
        # crosses it and back, six triangles on those edges).
        if len(stack) >= 2 and stack[-2] == v and not (g.degree(stack[-1]) <= 1
                                                       or (turns is not None and turns[stack[-1]])):
            stack.pop()
            cancelled = True
        else:
            stack.append(v)
        depth.append(len(stack))
    if not cancelled:
        return snap
    # An event keeps the part of its stack that is never popped after it.
    lowest = np.minimum.accumulate(np.asarray(depth)[::-1])[::-1]
    return np.array([stack[int(lowest[k]) - 1] for k in at], dtype=snap.dtype)


def _chain_on_faces(rail_list, event_points: np.ndarray, ends: np.ndarray, reach: float, box: np.ndarray,
                    near: float | None = None, cell: float | None = None):
    """Rails that end on a face of the box away from the curves' ends, joined end to start across it.

    A half-sheet that leaves the tube through the box near a curve that
    stays inside it (a few cells or less from a face) comes back onto the
    tube's side further on: its trace on the face between, in squares
    that hold two sheets, is not a rail.  Each such rail end is joined to
    the nearest such rail start on the same face (the chord between them
    lies in the face: an edge on the box), and the two rails become one
    (closed when it is the rail's own start).

    "Away" is farther than ``near`` cells along each axis (``cell`` the
    largest side; without them, than ``reach``): the ends of the traces of
    a curve end's half-sheets lie within the tube's reach of it, the rest
    of a half-sheet's trace along the face does not (a curve running a
    cell or a few from a face between its ends on two other faces: fuzz
    s1-746, s1-690).  A rail end is joined only to a start the chord
    between them goes on to, seen in the face from both: the two half-
    sheets between such a curve and the face run along it in opposite
    senses, their pieces side by side.
    """
    open_ = [k for k, (ev, closed) in enumerate(rail_list) if not closed and len(ev) >= 2]
    if not open_:
        return rail_list
    axes = _axis_cells(box, cell) if near is not None and cell is not None else None

    def free(p):
        if not _on_boundary(p, box):
            return False
        if len(ends) == 0:
            return True
        if axes is None:
            return float(np.linalg.norm(ends - p, axis=1).min()) > reach
        return float(np.linalg.norm((ends - p) / axes, axis=1).min()) > near

    heads = [k for k in open_ if free(event_points[rail_list[k][0][0]])]
    tails = [k for k in open_ if free(event_points[rail_list[k][0][-1]])]
    if not heads or not tails:
        return rail_list
    # Nearest pairs first (distances are distinct in general position;
    # ties by index, so the same input gives the same rails).
    pairs = []
    for a in tails:
        pa = event_points[rail_list[a][0][-1]]
        ea = event_points[rail_list[a][0][-min(4, len(rail_list[a][0]))]]
        for b in heads:
            pb = event_points[rail_list[b][0][0]]
            eb = event_points[rail_list[b][0][min(4, len(rail_list[b][0])) - 1]]
            shared = faces_of(pa, box) & faces_of(pb, box)
            if shared.any():
                d = float(np.linalg.norm(pa - pb))
                if d <= reach and (axes is None or _goes_on(pb - pa, pa - ea, eb - pb, shared)):
                    pairs.append((d, a, b))
    return _assemble_chains(rail_list, pairs)


def _goes_on(chord: np.ndarray, came: np.ndarray, goes: np.ndarray, faces: np.ndarray) -> bool:
    """Whether a chord in the faces flagged goes on the way a rail came and the next one goes, seen in the face."""
    keep = ~faces.reshape(3, 2).any(axis=1)
    return bool(np.dot(chord[keep], came[keep]) >= 0 and np.dot(chord[keep], goes[keep]) >= 0)


def _join_stubs(rail_list, event_points: np.ndarray, box: np.ndarray, gap: float):
    """Short rails with both ends on one face of the box, chained to each other and to a rail end there.

    Where the tube reaches a face of the box near a curve's end, a
    half-sheet's trace on the tube's side can run along the face (no
    rail there) and come back for a few links: a stub, both of whose ends
    are on the box.  Zipped alone, both its ends are fanned to the curve's
    end, in opposite senses, and the half-sheet's strip is made twice.
    A stub's end is joined to the start of another stub or rail on the
    same face within ``gap``, and a rail's end to a stub's start, nearest
    pairs first, when the chord between them goes on the way both run
    there; a chain holds at most one rail that is not a stub (the two
    sheets through a curve at a small angle leave stubs side by side,
    interleaved along the face: rotated planes at 5 degrees, seed 4).
    A short run with its ends on two faces is a stub too: a rail along a
    face stopped by a box edge, whose half-sheet goes on round the edge
    onto the next face (a line 3 cells inside x = -1 at 4 degrees ending
    on y = 1: both pieces fanned to the curve's end, edges of six).
    """
    open_ = [k for k, (ev, closed) in enumerate(rail_list) if not closed and len(ev) >= 2]
    stubs = set()
    for k in open_:
        p = event_points[rail_list[k][0]]
        a, b = p[0], p[-1]
        # Both ends on the box: on one face, or (a short run round a box
        # edge, its start by the end of the rail it continues on one face
        # and its end on the next) on two.
        if not (faces_of(a, box).any() and faces_of(b, box).any()):
            continue
        if not (faces_of(a, box) & faces_of(b, box)).any() and \
                float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum()) > 2 * gap:
            continue
        # Ends close together, or a short run as a whole (rotated planes
        # at 6 degrees, seed 4: 4 links a little over 3 cells end to end,
        # its start 0.3 cells from the end of the rail it continues).
        if float(np.linalg.norm(a - b)) <= gap or float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum()) <= 2 * gap:
            stubs.add(k)
    if not stubs:
        return rail_list
    # Each open rail's ends on the box and the way it runs there.
    tails, heads = {}, {}
    for k in open_:
        p = event_points[rail_list[k][0]]
        m = min(len(p), 4)
        if faces_of(p[-1], box).any():
            tails[k] = (p[-1], p[-1] - p[-m])
        if faces_of(p[0], box).any():
            heads[k] = (p[0], p[m - 1] - p[0])
    pairs = []
    for a, (pa, ua) in tails.items():
        for b, (pb, ub) in heads.items():
            if a == b or (a not in stubs and b not in stubs) or not (faces_of(pa, box) & faces_of(pb, box)).any():
                continue
            c = pb - pa
            d = float(np.linalg.norm(c))
            if d <= gap and float(np.dot(c, ua)) >= 0 and float(np.dot(c, ub)) >= 0:
                pairs.append((d, a, b))
    # Nearest first; a pair that would close a chain on itself or hold two
    # rails is skipped.
    comp = {k: k for k in open_}

    def root(k):
        while comp[k] != k:
            k = comp[k]
        return k

    has_rail = {k: k not in stubs for k in open_}
    keep = []
    used_tail, used_head = set(), set()
    for d, a, b in sorted(pairs):
        if a in used_tail or b in used_head:
            continue
        ra, rb = root(a), root(b)
        if ra == rb or (has_rail[ra] and has_rail[rb]):
            continue
        comp[rb] = ra
        has_rail[ra] = has_rail[ra] or has_rail[rb]
        used_tail.add(a)
        used_head.add(b)
        keep.append((d, a, b))
    return _assemble_chains(rail_list, keep)


def _assemble_chains(rail_list, pairs):
    """Rails joined end to start along ``pairs`` (distance, a, b), nearest first: rail b continues rail a."""
    nxt: dict[int, int] = {}
    taken = set()
    for _, a, b in sorted(pairs):
        if a not in nxt and b not in taken:
            nxt[a] = b
            taken.add(b)
    if not nxt:
        return rail_list
    out = [rail_list[k] for k in range(len(rail_list)) if k not in nxt and k not in taken]
    done = set()
    prev = {b: a for a, b in nxt.items()}
    for k in sorted(set(nxt) | taken):
        if k in done:
            continue
        # Walk back to the first rail of the chain (or once round a loop).
        first = k
        while first in prev and prev[first] != k:
            first = prev[first]
        chain, cur = [], first
        while cur not in done:
            done.add(cur)
            chain.append(cur)
            if cur not in nxt:
                break
            cur = nxt[cur]
        closed = chain[-1] in nxt and nxt[chain[-1]] == chain[0]
        out.append((np.concatenate([rail_list[c][0] for c in chain]), closed))
    return out


def _on_boundary(p: np.ndarray, box: np.ndarray) -> bool:
    size = float(np.max(box[:, 1] - box[:, 0]))
    return bool(np.any((np.abs(p - box[:, 0]) <= 1e-9 * size) | (np.abs(p - box[:, 1]) <= 1e-9 * size)))


def _axis_cells(box: np.ndarray, cell: float) -> np.ndarray:
    """(3,) the fine cell's side along each axis, ``cell`` its largest (the cells of a box need not be cubes)."""
    return (box[:, 1] - box[:, 0]) / float(np.max(box[:, 1] - box[:, 0])) * cell


def faces_of(p: np.ndarray, box: np.ndarray) -> np.ndarray:
    """(..., 6) bool: which faces of the box (x-, x+, y-, y+, z-, z+) the points (..., 3) lie on."""
    size = float(np.max(box[:, 1] - box[:, 0]))
    return np.stack([np.abs(p - box[:, 0]) <= 1e-9 * size, np.abs(p - box[:, 1]) <= 1e-9 * size], axis=-1).reshape(
        p.shape[:-1] + (6,))


def _corner_event(r: np.ndarray, e: np.ndarray, event_points: np.ndarray, box: np.ndarray, reach: float):
    """The event on the box edge between the faces of r and of e, if they share no face; else None."""
    fr, fe = faces_of(r, box), faces_of(e, box)
    if (fr & fe).any() or not fr.any() or not fe.any():
        return None
    near = np.nonzero(np.linalg.norm(event_points - (r + e) / 2, axis=1) <= reach)[0]
    if len(near) == 0:
        return None
    flags = faces_of(event_points[near], box)
    on_edge = (flags & fr).any(axis=1) & (flags & fe).any(axis=1)
    if not on_edge.any():
        return None
    cand = near[on_edge]
    return int(cand[np.argmin(np.linalg.norm(event_points[cand] - (r + e) / 2, axis=1))])
