"""Facets at a singular point: sectors between skeleton links, fanning into it.

Each link cycle around a singular point p bounds one branch.  The skeleton
links (face node -> traced points -> p) cut the branch into sectors; a
sector is the polygon p, trace of node k (outwards), node k, the cycle
from node k to node k+1, trace of node k+1 (inwards).  A cycle that no
skeleton curve reaches is one sector: p and the whole cycle.  Polygons
keep the cycle's orientation, so the fans agree with the rest of the mesh.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np


def sector_polygons(p_key: int, p: np.ndarray, cycle_keys: np.ndarray, cycle_points: np.ndarray,
                    links: list, next_key: int, cycle_squares: np.ndarray | None = None):
    """Sector polygons of one cycle of a singular point.

    Parameters
    ----------
    p_key, p : key and position of the singular vertex
    cycle_keys, cycle_points : the cycle's vertices in order
    links : list of :class:`singmesh.skeleton.curves.SkeletonLink`, ordered
        along the cycle
    next_key : first unused vertex key (for nodes and traced points)
    cycle_squares : (m,) int64, optional
        The contact square of the link leaving each cycle vertex.

    Returns
    -------
    polygons : (keys (S,), points (S, 3), sizes list of P ints)
        The polygons one after the other; the first vertex of each is p or
        a traced point (an inner vertex to fan from, if large)
    splits : dict
        ``(square, a, b) -> [(node_key, node_point), ...]`` for every cycle
        link a -> b (on that square) that received face nodes, in order
        from a to b: the polygon on the other side of that link must get
        them too.  Two links may join the same two vertices on different
        squares, hence the square in the key.
    next_key : int
    """
    (polygons,), (splits,), next_key = sector_polygons_many(
        [(p_key, p, cycle_keys, cycle_points, links, cycle_squares)], next_key)
    return polygons, splits, next_key


def sector_polygons_many(jobs: list, next_key: int):
    """:func:`sector_polygons` of many cycles, the keys of each after the previous one's.

    Parameters
    ----------
    jobs : list of (p_key, p, cycle_keys, cycle_points, links, cycle_squares)
    next_key : first unused vertex key

    Returns
    -------
    polygons : list, one (keys, points, sizes) per job
    splits : list, one dict per job
    next_key : int

    Notes
    -----
    The spokes of each cycle are laid out one by one (few Python steps);
    the distances the zippers compare and the flat-triangle test are
    computed for all cycles at once (each row with the bits of a cycle
    alone).  A cycle with flat triangles is built again with those spokes
    straight, in the next round, as one alone would be.
    """
    states, splits = [], []
    for job in jobs:
        state, split, next_key = _prepare(*job, next_key)
        states.append(state)
        splits.append(split)
    polygons = _sectors_many(states)
    return polygons, splits, next_key


def _prepare(p_key, p, cycle_keys, cycle_points, links, cycle_squares, next_key):
    """The cycle with its face nodes and the spokes of one cycle (see :func:`sector_polygons`).

    Returns
    -------
    state : tuple (spokes, p_key, p, keys, pts), or None for a collapsed cycle (no polygon)
    splits : dict
    next_key : int
    """
    m = len(cycle_keys)
    splits: dict = {}
    # A cycle small next to its distance from p (a sharp cusp): traced
    # points would crowd together near p; its spokes go straight.
    size = np.ptp(cycle_points, axis=0).max() if m else 0.0
    if size < 0.05 * np.linalg.norm(cycle_points - p, axis=1).min():
        links = [replace(s, trace=np.zeros((0, 3))) for s in links]
    # The cycle with the face nodes inserted; anchors are the places where
    # a spoke (skeleton link) meets it.
    keys, pts, spokes = [], [], []
    expanded = {}
    ckeys = np.asarray(cycle_keys).tolist()  # Python ints
    nodes_after: dict = {}  # the links ending on a new node, by the cycle link they cut, in order
    for s in links:
        if s.vertex is None:
            nodes_after.setdefault(s.after, []).append(s)
    for i in range(m):
        expanded[i] = len(keys)
        keys.append(ckeys[i])
        pts.append(cycle_points[i])
        for s in nodes_after.get(i, ()):
            node_key = next_key
            trace_keys = list(range(next_key + 1, next_key + 1 + len(s.trace)))
            next_key += 1 + len(s.trace)
            a, b = ckeys[i], ckeys[(i + 1) % m]
            sq = -1 if cycle_squares is None else int(cycle_squares[i])
            splits.setdefault((sq, a, b), []).append((node_key, s.node))
            spokes.append((len(keys), trace_keys, list(s.trace)))
            keys.append(node_key)
            pts.append(s.node)
    n = len(keys)
    for s in links:
        if s.vertex is not None:
            tk = list(range(next_key, next_key + len(s.trace)))
            next_key += len(s.trace)
            spokes.append((expanded[s.vertex], tk, list(s.trace)))
    spokes.sort(key=lambda sp: sp[0])
    if len(spokes) < 2:
        # Fewer than two skeleton links: anchor the sectors at cycle
        # vertices (with straight spokes) so that they still close around p.
        first = spokes[0][0] if spokes else 0
        extra = (first + n // 2) % n
        spokes = sorted(spokes + [(first, [], [])] * (not spokes) + [(extra, [], [])])
    if n < 3 or len({a for a, _, _ in spokes}) < 2:
        # A collapsed cycle: no area to fan.
        return None, splits, next_key
    spokes = _narrow_sectors(spokes, p, keys, pts)
    return (spokes, p_key, p, keys, pts), splits, next_key


def _sectors_many(states: list) -> list:
    """The polygons of each prepared cycle (None: collapsed, no polygon).

    Traced points are for shape only: a spoke whose points make a flat
    triangle with a neighbour's (two traces on one line of the skeleton)
    goes straight, and the cycle's sectors are built again (at most once
    per spoke, then the last build stays).
    """
    out = [(np.zeros(0, np.int64), np.zeros((0, 3)), []) for _ in states]
    todo = [c for c, st in enumerate(states) if st is not None]
    spokes = {c: states[c][0] for c in todo}
    rounds = {c: len(states[c][0]) + 1 for c in todo}
    while todo:
        built = _sectors_batch([(spokes[c],) + tuple(states[c][1:]) for c in todo])
        again = []
        for c, (polygons, flat) in zip(todo, built):
            out[c] = polygons
            rounds[c] -= 1
            if flat and rounds[c] > 0:
                spokes[c] = [(sp[0], [], []) if k in flat else sp for k, sp in enumerate(spokes[c])]
                again.append(c)
        todo = again
    return out


def _sectors_batch(cycles: list) -> list:
    """:func:`_sectors` of many cycles (spokes, p_key, p, keys, pts): a list of (polygons, flat)."""
    # One table of the vertices of all cycles: per cycle p, the cycle with
    # its nodes, then each spoke's traced points; triangles are rows of
    # indices into it.
    tab_k, tab_p, base, trace_of = [], [], [], []
    for spokes, p_key, p, keys, pts in cycles:
        base.append(len(tab_k))
        tab_k += [p_key] + list(keys)
        tab_p += [p] + list(pts)
        trace_at = []
        for _, tkeys, tpts in spokes:
            trace_at.append(list(range(len(tab_k), len(tab_k) + len(tkeys))))
            tab_k += tkeys
            tab_p += tpts
        trace_of.append(trace_at)
    tab_k, tab_p = np.array(tab_k, np.int64), np.array(tab_p).reshape(-1, 3)
    # Each sector's two spokes (p, traced points, end on the cycle) and the
    # lengths its zipper compares: every (spoke A point, spoke B point)
    # pair but p, as A point - B point.
    sectors, first, second = [], [], []
    for (spokes, _, _, keys, _), b, trace_at in zip(cycles, base, trace_of):
        for k, (at, _, _) in enumerate(spokes):
            nxt = (k + 1) % len(spokes)
            sa = [b] + trace_at[k][::-1] + [b + 1 + at]
            sb = [b] + trace_at[nxt][::-1] + [b + 1 + spokes[nxt][0]]
            sectors.append((sa, sb, len(first)))
            for i in sa[1:]:
                first += [i] * (len(sb) - 1)
                second += sb[1:]
    lengths = _lengths(tab_p[first] - tab_p[second]).tolist() if first else []
    tris, zips = [], []
    for sa, sb, at in sectors:
        zipped = _zip_spokes(sa, sb, lengths, at)
        zips.append((len(tris), len(zipped)))
        tris += zipped
    tris = np.array(tris, np.int64).reshape(-1, 3)
    is_flat = _flat_triangles(tab_p[tris])
    results, s = [], 0
    for (spokes, _, _, keys, _), b in zip(cycles, base):
        n = len(keys)
        flat = set()
        out, sizes = [], []
        for k, (at, tkeys, _) in enumerate(spokes):
            nxt_at, nkeys, _ = spokes[(k + 1) % len(spokes)]
            start, count = zips[s + k]
            if is_flat[start:start + count].any():
                flat |= {k for k, t in ((k, tkeys), ((k + 1) % len(spokes), nkeys)) if t}
            steps = (nxt_at - at) % n or n
            # The outer part: the cycle from A's end to B's end.  It joins the
            # zipper's last triangle (x, A's end, B's end): the polygon x, arc is
            # fanned from x, an inner vertex, when large.  Closed by the chord
            # alone, an arc along a flat sheet cut by one face of the star would
            # have no area.
            if steps >= 2:
                count -= 1
                last = tris[start + count].tolist()
                ends = (keys[at], keys[nxt_at])
                x = next(v for v in last if tab_k[v] not in ends)
                out.append(np.array([x] + [b + 1 + (at + j) % n for j in range(steps + 1)], np.int64))
                sizes.append(steps + 2)
            out.append(tris[start:start + count].reshape(-1))
            sizes += [3] * count
        s += len(spokes)
        out = np.concatenate(out)
        results.append(((tab_k[out], tab_p[out], sizes), flat))
    return results


def _flat_triangles(tri_pts: np.ndarray) -> np.ndarray:
    """Whether each triangle (T, 3, 3) is flat: twice its area at most 1e-6 of its longest edge squared.

    Row by row the same products as np.cross and np.linalg.norm of one
    vector (matmul of a row by a column is the BLAS dot product).
    """
    e = np.stack([tri_pts[:, 1] - tri_pts[:, 0], tri_pts[:, 2] - tri_pts[:, 1], tri_pts[:, 0] - tri_pts[:, 2]], 1)
    # np.cross(e[:, 0], -e[:, 2]) written out (its products and
    # differences, without its overhead of some 40 us a call).
    a0, a1, a2 = e[:, 0, 0], e[:, 0, 1], e[:, 0, 2]
    b0, b1, b2 = -e[:, 2, 0], -e[:, 2, 1], -e[:, 2, 2]
    c = np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=1)
    area2 = np.sqrt(np.matmul(c[:, None, :], c[:, :, None])[:, 0, 0])
    longest = np.matmul(e[:, :, None, :], e[:, :, :, None])[:, :, 0, 0].max(axis=1)
    return area2 <= 1e-6 * longest


def _lengths(v: np.ndarray) -> np.ndarray:
    """:func:`_length` of each row of ``v`` (K, 3): the square root of the same BLAS dot product."""
    return np.sqrt(np.matmul(v[:, None, :], v[:, :, None])[:, 0, 0])


def _length(v: np.ndarray) -> float:
    """np.linalg.norm of one vector (the same square root of the same dot product), without its overhead."""
    return math.sqrt(v.dot(v))


def _narrow_sectors(spokes: list, p: np.ndarray, keys: list, pts: list, max_angle: float = 2.0) -> list:
    """Add straight spokes to cycle vertices: at least three spokes, and no
    sector opening wider than ``max_angle`` (radians) at p, since a ring of
    triangles from p needs each sector to turn less than half a revolution."""
    n = len(keys)

    def first_point(spoke):
        at, _, tpts = spoke
        return tpts[-1] if tpts else pts[at]

    # Two spokes would bound both sectors: their zippers would join the
    # same points twice.  Split the longest sector until there are three.
    while len(spokes) < 3:
        gaps = [((spokes[(k + 1) % len(spokes)][0] - sp[0]) % n or n, k) for k, sp in enumerate(spokes)]
        steps, k = max(gaps)
        if steps < 2:
            break
        spokes = spokes[: k + 1] + [((spokes[k][0] + steps // 2) % n, [], [])] + spokes[k + 1:]
    for _ in range(4 * n):
        out, changed = [], False
        for k, sp in enumerate(spokes):
            nxt = spokes[(k + 1) % len(spokes)]
            out.append(sp)
            u, w = first_point(sp) - p, first_point(nxt) - p
            cos = np.dot(u, w) / max(_length(u) * _length(w), 1e-300)
            steps = (nxt[0] - sp[0]) % n or n
            if np.arccos(min(max(cos, -1.0), 1.0)) > max_angle and steps >= 2:
                out.append(((sp[0] + steps // 2) % n, [], []))
                changed = True
        spokes = out
        if not changed:
            break
    return spokes


def _zip_spokes(a: list, b: list, lengths: list, at: int) -> list:
    """Triangles between two spokes sharing their first vertex p.

    ``a`` and ``b`` are the spokes' vertices (indices into the vertex
    table) from p outwards; ``lengths[at + (i - 1) (len(b) - 1) + j - 1]``
    is the distance from a's i-th point to b's j-th (i, j >= 1).  Rings
    from p outwards, each step advancing on the spoke whose next point
    gives the shorter diagonal: no triangle lies along one spoke, so
    neighbouring sectors never pick the same sliver.

    Returns
    -------
    list of [i, j, k] vertex indices
    """
    nb = len(b) - 1

    def dist(i, j):
        return lengths[at + (i - 1) * nb + j - 1]

    tris = [[a[0], a[1], b[1]]]
    i = j = 1
    while i < len(a) - 1 or j < len(b) - 1:
        adv_a = j == len(b) - 1 or (i < len(a) - 1 and dist(i + 1, j) <= dist(i, j + 1))
        if adv_a:
            tris.append([a[i], a[i + 1], b[j]])
            i += 1
        else:
            tris.append([a[i], b[j + 1], b[j]])
            j += 1
    return tris


def insert_link_nodes(offsets: np.ndarray, keys: np.ndarray, points: np.ndarray,
                      squares: np.ndarray, splits: dict):
    """Insert face nodes into the other side of every subdivided link.

    The polygon across a shared face link traverses it as b -> a on the
    same square; it gets the nodes in reverse order, so both sides share
    the same vertices and the mesh has no T-junction.

    Parameters
    ----------
    squares : (S,) int64
        The square of the link leaving each polygon vertex (-1 where none).
    """
    if not splits:
        return offsets, keys, points
    n = len(keys)
    poly = np.repeat(np.arange(len(offsets) - 1), np.diff(offsets))
    nxt = np.arange(n) + 1
    nxt[offsets[1:] - 1] = offsets[:-1]
    split_squares = np.array(sorted({q for q, _, _ in splits}), dtype=np.int64)
    cand = np.nonzero(np.isin(squares, split_squares))[0]
    at, ins_k, ins_p, count = [], [], [], []
    # (The links as Python ints read in one go, not three conversions per vertex.)
    for i, link in zip(cand.tolist(), zip(squares[cand].tolist(), keys[nxt[cand]].tolist(), keys[cand].tolist())):
        ins = splits.get(link)  # other side: b -> a
        if ins:
            at.append(i)
            count.append(len(ins))
            for k, q in reversed(ins):
                ins_k.append(k)
                ins_p.append(q)
    if not at:
        return offsets, keys, points
    # All insertions at once, each after its vertex (np.insert puts values
    # for one place in the order given, before the next vertex).
    at, count = np.array(at, np.int64), np.array(count, np.int64)
    where = np.repeat(at + 1, count)
    sizes = np.diff(offsets) + np.bincount(poly[at], weights=count, minlength=len(offsets) - 1).astype(np.int64)
    return (np.concatenate([[0], np.cumsum(sizes)]), np.insert(keys, where, np.array(ins_k, np.int64)),
            np.insert(points, where, np.array(ins_p).reshape(-1, 3), axis=0))
