"""Face links: the curve F + eps = 0 on the faces between leaves.

A *contact square* is a face of a leaf across which the neighbouring cell
of the same size is not split further (it is a leaf as large or larger,
empty, or outside the domain).  Contact squares tile every face of every
leaf, so a face shared by one large box and four small ones is four
squares, each seen by both sides: the links agree on both sides by
construction.

On each square the events of its four edges are paired into links, each
oriented so that F + eps > 0 lies on its left seen from the square's +n
side.  Pairing: where a tangential derivative is of one sign the face
curve is a graph over the other axis, and sorting the events along that
axis pairs consecutive ones; otherwise (only in boxes that failed the
simplicity test) the events are paired along the boundary, each start with
the next end.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from singmesh import tolerances as tol
from singmesh.sorting import first_occurrences, lexsort, search_sorted
from singmesh.surface import Surface

from .edges import Events
from .octree import Octree, node_keys


@dataclass
class FaceLinks:
    """Oriented links on contact squares and the leaves on both sides.

    Attributes
    ----------
    square : (Q, 5) int64      (n, plane, u0, v0, size) of each square (every contact
                               square for tubes, else those with events: :func:`face_links`)
    minus, plus : (Q,) int64   leaf on the -n / +n side, or -1
    link_square : (K,) int64   square of each link
    start, end : (K,) int64    events joined, start -> end seen from +n
    ambiguous : (Q,) bool      squares with events paired along the boundary (no graph
                               axis; with two events, only for tubes: :func:`face_links`)
    inconsistent : (Q,) bool   squares whose events could not be paired
    """

    square: np.ndarray
    minus: np.ndarray
    plus: np.ndarray
    link_square: np.ndarray
    start: np.ndarray
    end: np.ndarray
    ambiguous: np.ndarray
    inconsistent: np.ndarray


def contact_squares(tree: Octree, leaves: np.ndarray | None = None):
    """Contact squares and, for each, a leaf and face index providing it.

    With ``leaves`` (indices), only the squares that are a whole face of
    one of them: all the squares between two of them (the smaller side of
    a square is its whole face), and some more.

    Returns
    -------
    squares : (Q, 5) int64   (n, plane, u0, v0, size)
    owner : (Q,) int64       a leaf having the square as a whole face
    owner_side : (Q,) int64  0 if it is the owner's -n face, 1 if its +n face
    """
    leaves = np.arange(len(tree.level)) if leaves is None else np.asarray(leaves, np.int64)
    size = tree.size[leaves]
    level = tree.level[leaves]
    corner = tree.corner[leaves]
    top = 1 << tree.fine_level
    rows, owners, sides = [], [], []
    for n in range(3):
        u, v = (n + 1) % 3, (n + 2) % 3
        for side in (0, 1):
            other = corner.copy()
            other[:, n] += size if side else -size
            inside = (other[:, n] >= 0) & (other[:, n] < top)
            keys = node_keys(level, np.clip(other, 0, top - 1) >> (tree.fine_level - level)[:, None])
            pos = np.minimum(search_sorted(tree.internal, keys), max(len(tree.internal) - 1, 0))
            split = inside & (len(tree.internal) > 0) & (tree.internal[pos] == keys) if len(tree.internal) else np.zeros(len(size), bool)
            keep = ~split
            rows.append(np.stack([
                np.full(keep.sum(), n), corner[keep, n] + side * size[keep],
                corner[keep, u], corner[keep, v], size[keep]], axis=1))
            owners.append(leaves[keep])
            sides.append(np.full(keep.sum(), side))
    rows = np.concatenate(rows)
    owners = np.concatenate(owners)
    sides = np.concatenate(sides)
    # One int64 per square (2 + 3 x 16 + 5 bits): a 1-D unique, not rows.
    size_bits = np.log2(rows[:, 4]).astype(np.int64)
    packed = (rows[:, 0] << 53) | (rows[:, 1] << 37) | (rows[:, 2] << 21) | (rows[:, 3] << 5) | size_bits
    first = first_occurrences(packed)
    return rows[first], owners[first], sides[first]


def graph_modes(surface: Surface, tree: Octree, squares, owner, owner_side,
                which: np.ndarray | None = None) -> np.ndarray:
    """0: the face curve is a graph over u; 1: over v; 2: neither is known.

    Read from the owner's face by ``surface.face_modes``: on the owners'
    rows of ``tree.data`` (each leaf owns at most one square per face),
    not on a gathered copy of their data, nor on every leaf.  With
    ``which`` (Q,) bool, only those squares are read; the others get 0.
    """
    mode = np.full(len(squares), 2, np.int64)
    if which is not None:
        mode[~which] = 0
    for a in range(3):
        for side in (0, 1):
            pick = (squares[:, 0] == a) & (owner_side == side)
            sel = np.nonzero(pick if which is None else pick & which)[0]
            if len(sel) == 0:
                continue
            mode[sel] = surface.face_modes(tree.data, a, np.full(len(sel), side, np.int64), rows=owner[sel])
    return mode


def square_events(events: Events, squares):
    """Events on the boundary of each square, with their place on it.

    Returns a dict of per-incidence arrays: ``sq``, ``ev``, ``is_start``
    (F + eps goes from + to - along the counter-clockwise boundary there),
    ``u``, ``v`` (lattice coordinates), ``tie_u``, ``tie_v`` (the side of
    a snapped event, along u resp. v), ``ccw`` (place along the boundary).
    """
    n, plane, u0, v0, size = squares.T
    u_ax, v_ax = (n + 1) % 3, (n + 2) % 3
    # The four edges counter-clockwise seen from +n: bottom (+u), right (+v),
    # top (-u), left (-v).
    e_axis = np.stack([u_ax, v_ax, u_ax, v_ax], 1)
    e_f1 = np.stack([v0, plane, v0 + size, plane], 1)
    e_f2 = np.stack([plane, u0 + size, plane, u0], 1)
    e_start = np.stack([u0, v0, u0, v0], 1)
    sigma = np.array([1, 1, -1, -1])
    seg, ev = events.on_segments(e_axis.ravel(), e_f1.ravel(), e_f2.ravel(),
                                 e_start.ravel(), (e_start + size[:, None]).ravel())
    sq, edge = seg // 4, seg % 4
    pos = events.pos[ev]
    side = events.side[ev].astype(float)
    along_u = edge % 2 == 0
    return dict(
        sq=sq, ev=ev,
        is_start=events.direction[ev] * sigma[edge] < 0,
        u=np.where(along_u, pos, np.where(edge == 1, u0[sq] + size[sq], u0[sq])),
        v=np.where(~along_u, pos, np.where(edge == 0, v0[sq], v0[sq] + size[sq])),
        tie_u=np.where(along_u, side, 0.0),
        tie_v=np.where(~along_u, side, 0.0),
        ccw=edge * 4.0 * (1 << 20) + sigma[edge] * pos,
        tie_ccw=sigma[edge] * side,
    )


def pair_events(inc: dict, mode: np.ndarray, n_squares: int):
    """Pair the events of each square according to its mode.

    In boundary mode (2) each start goes with the next end, unless two
    consecutive events are one corner of the square seen from its two
    edges (``inc["corner"]``, the same ``inc["key"]``): they are paired
    (see :func:`_corner_events`), and so the others with their neighbours
    on that parity.

    Returns
    -------
    link_square, start, end : (K,) int64
    bad : (Q,) bool   squares with an odd count or a pair not (start, end)
    """
    sq, m = inc["sq"], mode[inc["sq"]]
    key1 = np.select([m == 0, m == 1], [inc["u"], inc["v"]], inc["ccw"])
    key2 = np.select([m == 0, m == 1], [inc["tie_u"], inc["tie_v"]], inc["tie_ccw"])
    order = lexsort((key2, key1, sq))
    sq, ev, is_start = sq[order], inc["ev"][order], inc["is_start"][order]
    counts = np.bincount(sq, minlength=n_squares)
    offset = np.cumsum(counts) - counts
    bad = counts % 2 == 1
    # Graph modes pair (0,1), (2,3), ...; boundary mode pairs each start
    # with the next end, cyclically, so it starts at the first start.
    first_start = np.zeros(n_squares, bool)
    has = counts > 0
    first_start[has] = is_start[offset[has]]
    shift = np.where((mode == 2) & ~first_start & has, 1, 0)
    rank = np.arange(len(sq)) - offset[sq]
    if "corner" in inc:
        # The next incidence round the square's boundary (cyclically).
        corner, key = inc["corner"][order], inc["key"][order]
        nxt = offset[sq] + (rank + 1) % np.maximum(counts[sq], 1)
        pair = corner & corner[nxt] & (key == key[nxt]) & (nxt != np.arange(len(sq))) & (mode[sq] == 2)
        if "zero_side" in inc:
            # Two corners of one side on which F is zero (see :func:`_zero_side_events`).
            zs, u, v = inc["zero_side"][order], inc["u"][order], inc["v"][order]
            along_u = zs[:, 0] & zs[nxt, 0] & (v == v[nxt]) & (u != u[nxt])
            along_v = zs[:, 1] & zs[nxt, 1] & (u == u[nxt]) & (v != v[nxt])
            pair |= (along_u | along_v) & (key != key[nxt]) & (mode[sq] == 2)
        if pair.any():
            want = np.full(n_squares, -1, np.int64)
            np.maximum.at(want, sq[pair], rank[pair] % 2)
            other = np.full(n_squares, 2, np.int64)
            np.minimum.at(other, sq[pair], rank[pair] % 2)
            agree = (want >= 0) & (want == other)   # pairs asking for different parities: the rule
            shift = np.where(agree, want, shift)
    slot = (rank - shift[sq]) % np.maximum(counts[sq], 1)
    ok = ~bad[sq]
    sq, ev, is_start, slot = sq[ok], ev[ok], is_start[ok], slot[ok]
    order = lexsort((slot, sq))
    a, b = order[0::2], order[1::2]
    pair_bad = is_start[a] == is_start[b]
    bad[sq[a][pair_bad]] = True
    keep = ~bad[sq[a]]
    a, b = a[keep], b[keep]
    start = np.where(is_start[a], ev[a], ev[b])
    end = np.where(is_start[a], ev[b], ev[a])
    return sq[a], start, end, bad


def face_links(surface: Surface, tree: Octree, events: Events, group: np.ndarray | None = None,
               tubes: bool = True) -> FaceLinks:
    """Pair the events on every contact square into oriented links (``tree`` made for ``surface``).

    With ``group`` (N,), the box id of every leaf (leaves sharing one are
    meshed as one box, a star: :func:`singmesh.facets.stars.group_stars`),
    the squares between two leaves of one box are left out: the box's
    links are those on its boundary (:func:`singmesh.facets.cycles.box_links`
    drops the others), and inside a star the cone over its boundary
    replaces the surface.

    ``tubes``: the links are for tubes along curves, which need every
    square (the leaves' adjacency across them) and the graph axis of the
    squares with two events (their ``ambiguous`` flag: a link on the
    domain's boundary across a square with no graph axis may join two
    sheets).  Without, only the squares with events are kept (half of all
    squares have none), and the graph axis is read only on squares with
    more than two, which it pairs: the one link of a square with two
    events is the same either way (such squares are not ``ambiguous``).
    """
    squares, owner, owner_side = contact_squares(tree)
    inc = None
    if not tubes:
        inc = square_events(events, squares)
        has = np.bincount(inc["sq"], minlength=len(squares)) > 0
        squares, owner, owner_side = squares[has], owner[has], owner_side[has]
        inc = _of_squares(inc, has)
    minus, plus = _sides(tree, squares, owner, owner_side)
    if group is not None:
        inner = (minus >= 0) & (plus >= 0) & (group[np.maximum(minus, 0)] == group[np.maximum(plus, 0)])
        if inner.any():
            keep = ~inner
            squares, owner, owner_side, minus, plus = (a[keep] for a in (squares, owner, owner_side, minus, plus))
            if inc is not None:
                inc = _of_squares(inc, keep)
    if inc is None:
        inc = square_events(events, squares)
    counts = np.bincount(inc["sq"], minlength=len(squares))
    mode = graph_modes(surface, tree, squares, owner, owner_side, which=counts >= (2 if tubes else 3))
    inc["key"] = events.key[inc["ev"]]
    inc["corner"] = _corner_events(surface, events, squares, inc, (mode == 2) & (counts >= 4))
    inc["zero_side"] = _zero_side_events(surface, events, squares, inc, (mode == 2) & (counts >= 4))
    link_sq, start, end, bad = pair_events(inc, mode, len(squares))
    # A graph pairing that does not alternate start/end means rounding
    # defeated the sign test: pair those squares along the boundary instead.
    retry = bad & (mode != 2)
    if retry.any():
        mode = np.where(retry, 2, mode)
        link_sq, start, end, bad = pair_events(inc, mode, len(squares))
    return FaceLinks(square=squares, minus=minus, plus=plus, link_square=link_sq,
                     start=start, end=end, ambiguous=mode == 2, inconsistent=bad)


def rail_links(surface: Surface, tree: Octree, events: Events, links: FaceLinks, in_tube: np.ndarray,
               curve: np.ndarray | None = None, radius: float = 0.0) -> FaceLinks:
    """The links with the tube's squares on the box's faces that have no graph axis paired by tracing.

    On the box's faces a tube's rails follow the traces of its
    half-sheets: where two of them run less than a cell apart their
    squares have no graph axis, and the pairing along the boundary joins
    one sheet's trace to the other's (fuzz s1-610), so such links were
    left out of the rails and the traces broke.  The face curve is
    followed across those squares instead (:func:`traced_pairs`; a square
    with two events has one pairing, which it confirms: another trace may
    cross it unseen, between two roots on one edge closer than the root
    finder separates).  Only the rails read these links (``in_tube``:
    (N,) bool, the tube's leaves): the boxes' own cycles keep theirs.
    Squares with an event within ``radius`` of the points ``curve`` (k, 3)
    are left as they are: there the traces meet at the curve, and near a
    curve of higher corank its events are as far off F = 0 as its tiny
    gradient makes them (fuzz s1-704: a rail vertex 1.9e-9 of the box off).
    """
    leaf = np.where(links.minus >= 0, links.minus, links.plus)
    which = (links.ambiguous & ~links.inconsistent & ((links.minus < 0) | (links.plus < 0)) & (leaf >= 0)
             & in_tube[np.maximum(leaf, 0)])
    if not which.any():
        return links
    idx = np.nonzero(which)[0]
    sub = links.square[idx]
    inc = square_events(events, sub)
    counts = np.bincount(inc["sq"], minlength=len(sub))
    if curve is not None and len(curve):
        from scipy.spatial import cKDTree

        close = cKDTree(curve).query(events.point[inc["ev"]], distance_upper_bound=radius)[0] <= radius
        counts[inc["sq"][close]] = 0
    local = np.full(len(links.square), -1, np.int64)
    local[idx] = np.arange(len(idx))
    mine = which[links.link_square]
    l_sq, l_start, l_end, traced = traced_pairs(
        surface, tree, events, sub, inc, counts >= 2,
        (local[links.link_square[mine]], links.start[mine], links.end[mine]))
    link_square = np.concatenate([links.link_square[~mine], idx[l_sq]])
    start = np.concatenate([links.start[~mine], l_start])
    end = np.concatenate([links.end[~mine], l_end])
    order = np.argsort(link_square, kind="stable")
    ambiguous = links.ambiguous.copy()
    ambiguous[idx[traced]] = False
    return FaceLinks(square=links.square, minus=links.minus, plus=links.plus, link_square=link_square[order],
                     start=start[order], end=end[order], ambiguous=ambiguous, inconsistent=links.inconsistent)


def traced_pairs(surface: Surface, tree: Octree, events: Events, squares, inc: dict, which: np.ndarray, links):
    """The links of the squares ``which`` found by following the face curve from each start event.

    From each start event of such a square the curve F = 0 in the square's
    plane is followed (predictor along its tangent, F + eps > 0 on the
    left; corrector by Newton in the plane) with steps of the square's side
    over ``FACE_TRACE_STEPS``, halved where the corrector drifts or the
    curve turns (another trace near), until it leaves the square; the end
    event nearest where it leaves is its end.  A square is re-paired only
    where every start reaches a different end, none of its events is a
    lattice point (the rule F + eps there is not the curve followed), and
    the links do not cross: elsewhere its links stay as they were.

    Parameters
    ----------
    links : (link_square, start, end) of :func:`pair_events`

    Returns
    -------
    link_square, start, end : (K,) int64   the links, those of the re-paired squares replaced
    traced : (Q,) bool                     the squares re-paired
    """
    link_sq, start, end = links
    traced = np.zeros(len(squares), bool)
    on = which[inc["sq"]]
    snapped = np.zeros(len(squares), bool)
    snapped[inc["sq"][on & events.snapped[inc["ev"]]]] = True
    which = which & ~snapped
    on = which[inc["sq"]]
    if not on.any():
        return link_sq, start, end, traced
    sq_s = inc["sq"][on & inc["is_start"]]
    ev_s = inc["ev"][on & inc["is_start"]]
    n = squares[sq_s, 0]
    ua, va = (n + 1) % 3, (n + 2) % 3
    r = np.arange(len(sq_s))
    lo_u = tree.box[ua, 0] + squares[sq_s, 2] * tree.cell[ua]
    lo_v = tree.box[va, 0] + squares[sq_s, 3] * tree.cell[va]
    hi_u = lo_u + squares[sq_s, 4] * tree.cell[ua]
    hi_v = lo_v + squares[sq_s, 4] * tree.cell[va]
    h0 = np.minimum(hi_u - lo_u, hi_v - lo_v) / tol.FACE_TRACE_STEPS
    h = h0.copy()
    p = events.point[ev_s].astype(float)
    exit_at = np.full((len(sq_s), 3), np.nan)
    active = np.ones(len(sq_s), bool)

    def tangent(q, rows):
        g = surface.gradient(q)
        k = np.arange(len(rows))
        t = np.stack([g[k, va[rows]], -g[k, ua[rows]]], axis=1)
        norm = np.linalg.norm(t, axis=1, keepdims=True)
        return np.where(norm > 0, t / np.where(norm > 0, norm, 1.0), np.nan)

    with np.errstate(all="ignore"):
        for _ in range(tol.FACE_TRACE_MAX):
            idx = np.nonzero(active)[0]
            if len(idx) == 0:
                break
            t = tangent(p[idx], idx)
            q = p[idx].copy()
            q[np.arange(len(idx)), ua[idx]] += h[idx] * t[:, 0]
            q[np.arange(len(idx)), va[idx]] += h[idx] * t[:, 1]
            guess = q.copy()
            for _ in range(4):
                f, g = surface.value_gradient(q)
                gu, gv = g[np.arange(len(idx)), ua[idx]], g[np.arange(len(idx)), va[idx]]
                gg = gu * gu + gv * gv
                step = np.where(gg > 0, f / np.where(gg > 0, gg, 1.0), np.nan)
                q[np.arange(len(idx)), ua[idx]] -= step * gu
                q[np.arange(len(idx)), va[idx]] -= step * gv
            drift = np.linalg.norm(q - guess, axis=1)
            turn = np.einsum("ij,ij->i", tangent(q, idx), t)
            good = (drift <= tol.FACE_TRACE_DRIFT * h[idx]) & (turn >= 0.5)
            # A step that fails is halved; one too small gives the square up.
            h[idx[~good]] /= 2
            dead = idx[~good][h[idx[~good]] < 1e-3 * h0[idx[~good]]]
            active[dead] = False
            ok = idx[good]
            qo = q[good]
            u, v = qo[np.arange(len(ok)), ua[ok]], qo[np.arange(len(ok)), va[ok]]
            out = (u < lo_u[ok]) | (u > hi_u[ok]) | (v < lo_v[ok]) | (v > hi_v[ok])
            # Where the step leaves the square: its crossing of the boundary.
            a, b = p[ok], qo
            pu, pv = a[np.arange(len(ok)), ua[ok]], a[np.arange(len(ok)), va[ok]]
            du, dv = u - pu, v - pv
            s = np.ones(len(ok))
            for lim, x0, dx, sign in ((lo_u[ok], pu, du, -1), (hi_u[ok], pu, du, 1),
                                      (lo_v[ok], pv, dv, -1), (hi_v[ok], pv, dv, 1)):
                cross = sign * dx > 0
                s = np.where(cross, np.minimum(s, np.clip((lim - x0) / np.where(cross, dx, 1.0), 0, 1)), s)
            exit_at[ok[out]] = (a + s[:, None] * (b - a))[out]
            active[ok[out]] = False
            p[ok[~out]] = qo[~out]
    done = np.isfinite(exit_at).all(axis=1)
    # Each trace's end: the nearest end event of its square.
    on_e = on & ~inc["is_start"]
    sq_e, ev_e = inc["sq"][on_e], inc["ev"][on_e]
    matched = np.full(len(sq_s), -1, np.int64)
    for k in np.nonzero(done)[0].tolist():
        cand = ev_e[sq_e == sq_s[k]]
        if len(cand) == 0:
            continue
        d = np.linalg.norm(events.point[cand] - exit_at[k], axis=1)
        j = int(np.argmin(d))
        if d[j] <= h0[k]:
            matched[k] = cand[j]
    good_sq = which.copy()
    np.logical_and.at(good_sq, sq_s, matched >= 0)
    for q in np.nonzero(good_sq)[0].tolist():
        ends = matched[sq_s == q]
        if len(np.unique(ends)) != len(ends) or not _non_crossing(inc, q, ev_s[sq_s == q], ends):
            good_sq[q] = False
    if not good_sq.any():
        return link_sq, start, end, traced
    keep = ~good_sq[link_sq]
    new = good_sq[sq_s]
    link_sq = np.concatenate([link_sq[keep], sq_s[new]])
    start = np.concatenate([start[keep], ev_s[new]])
    end = np.concatenate([end[keep], matched[new]])
    order = np.argsort(link_sq, kind="stable")
    return link_sq[order], start[order], end[order], good_sq


def _non_crossing(inc: dict, q: int, starts: np.ndarray, ends: np.ndarray) -> bool:
    """Whether the chords (start, end) of square ``q`` do not cross, by their places round its boundary."""
    here = inc["sq"] == q
    place = dict(zip(inc["ev"][here].tolist(), (inc["ccw"][here] + 1e-9 * inc["tie_ccw"][here]).tolist()))
    chords = [tuple(sorted((place[a], place[b]))) for a, b in zip(starts.tolist(), ends.tolist())]
    for i, (a, b) in enumerate(chords):
        for c, d in chords[i + 1:]:
            if (a < c < b) != (a < d < b):
                return False
    return True


def _corner_events(surface: Surface, events: Events, squares, inc: dict, which: np.ndarray) -> np.ndarray:
    """Per incidence: an event at a corner of its square where F's gradient
    in the square's plane is not zero (only on the squares ``which``).

    A corner has two events in a square when F is zero there and negative
    along both edges from it (the rule F + eps of :mod:`.edges`); with a
    tangential gradient, F is then negative in the whole square near the
    corner (a sheet through a lattice line, tangent to a face along it), and
    F + eps = 0 is an arc round the corner from one event to the other:
    a link of its own.  Where that gradient vanishes (a singular point of
    the face's curve), branches may leave the corner into the square.
    """
    n, idx, g, rounding = _at_corners(surface, events, squares, inc, which)
    out = np.zeros(len(inc["sq"]), bool)
    tangential = (g > rounding) & (np.arange(3)[None, :] != n[idx, None])
    out[idx] = tangential.any(axis=1)
    return out


def _at_corners(surface: Surface, events: Events, squares, inc: dict, which: np.ndarray):
    """The incidences at a corner of their square (only on the squares ``which``).

    Returns the squares' normal axes n (K,), the indices idx of those
    incidences, |grad F| (len(idx), 3) at their events and its rounding
    level per component.
    """
    sq = inc["sq"]
    n, _, u0, v0, size = squares[sq].T
    at = (events.snapped[inc["ev"]] & which[sq]
          & ((inc["u"] == u0) | (inc["u"] == u0 + size)) & ((inc["v"] == v0) | (inc["v"] == v0 + size)))
    idx = np.nonzero(at)[0]
    p = events.point[inc["ev"][idx]]
    if len(idx) == 0:
        return n, idx, np.zeros((0, 3)), np.zeros((0, 3))
    g = np.abs(surface.gradient(p))
    rounding = tol.ZERO_ULPS * np.finfo(float).eps * surface.gradient_magnitude(p)
    return n, idx, g, rounding


def _zero_side_events(surface: Surface, events: Events, squares, inc: dict, which: np.ndarray) -> np.ndarray:
    """Per incidence (K, 2) bool: an event at a corner of its square where F
    is zero along the square's side in u (column 0) or in v (column 1) from
    it and not across it (only on the squares ``which``).

    A sheet through a lattice line, crossing the square's plane along it
    (fuzz s2-136: the z-axis, the sheet tangent to y = 0 along it), makes
    F zero on a side of the square and of one sign beside it.  Where that
    sign is negative, F + eps = 0 (the rule of :mod:`.edges`) is a thin arc
    along the side from one corner's event to the other's: a link of its
    own.  The boundary pairing would join each corner's event to the next
    event across the square instead (another sheet's trace there), and
    the boxes on the sheet's other side got polygons along the line: the
    lattice line's edges had four triangles.
    """
    n, idx, g, rounding = _at_corners(surface, events, squares, inc, which)
    out = np.zeros((len(inc["sq"]), 2), bool)
    if len(idx) == 0:
        return out
    rows = np.arange(len(idx))
    ua, va = (n[idx] + 1) % 3, (n[idx] + 2) % 3
    zu, zv = g[rows, ua] <= rounding[rows, ua], g[rows, va] <= rounding[rows, va]
    out[idx, 0] = zu & ~zv
    out[idx, 1] = zv & ~zu
    return out


def _of_squares(inc: dict, keep: np.ndarray) -> dict:
    """The incidences of :func:`square_events` on the squares ``keep`` (Q,) bool, numbered among
    those: what it gives for those squares alone (the same incidences in the same order)."""
    new = np.cumsum(keep) - 1
    on = keep[inc["sq"]]
    out = {k: v[on] for k, v in inc.items()}
    out["sq"] = new[out["sq"]]
    return out


@dataclass
class LeafSides:
    """The leaves on both sides of every contact square, without events.

    The adjacency of the leaves across faces (what :func:`star_cubes
    <singmesh.facets.stars.star_cubes>` grows stars along): the ``square``,
    ``minus`` and ``plus`` of :class:`FaceLinks`, at a fraction of its cost.
    """

    square: np.ndarray
    minus: np.ndarray
    plus: np.ndarray


def leaf_sides(tree: Octree, leaves: np.ndarray | None = None) -> LeafSides:
    """Contact squares and the leaves on their -n and +n sides (-1 where none).

    With ``leaves`` (indices), the squares of :func:`contact_squares` for
    them: every pair of them sharing a face is among the sides, which is
    all the adjacency among them (e.g. the leaves that failed the
    simplicity test, which the stars grow along) at a fraction of the cost.
    """
    squares, owner, owner_side = contact_squares(tree, leaves)
    minus, plus = _sides(tree, squares, owner, owner_side)
    return LeafSides(square=squares, minus=minus, plus=plus)


def _sides(tree: Octree, squares, owner, owner_side):
    """Leaves on the -n and +n sides of each square (-1 where none).

    The owner (:func:`contact_squares`) is on one side, the side its face
    looks in from; the leaf on the other side is looked up.
    """
    n, plane, u0, v0, size = squares.T
    other = np.zeros((len(squares), 3), np.int64)
    r = np.arange(len(squares))
    other[r, (n + 1) % 3] = 2 * u0 + size
    other[r, (n + 2) % 3] = 2 * v0 + size
    # The square's centre pushed half a cell off the face, away from the owner.
    other[r, n] = np.where(owner_side == 0, 2 * plane - 1, 2 * plane + 1)
    # The leaf across is as large as the owner or larger (the owner's face
    # is the whole square): the owner's level first.
    found = tree.find_leaves(other, guess=tree.level[owner])
    return np.where(owner_side == 0, found, owner), np.where(owner_side == 0, owner, found)
