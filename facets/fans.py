"""Facets at a singular point: sectors between skeleton links, fanning into it.

Each link cycle around a singular point p bounds one branch.  The skeleton
links (face node -> traced points -> p) cut the branch into sectors; a
sector is the polygon p, trace of node k (outwards), node k, the cycle
from node k to node k+1, trace of node k+1 (inwards).  A cycle that no
skeleton curve reaches is one sector: p and the whole cycle.  Polygons
keep the cycle's orientation, so the fans agree with the rest of the mesh.
"""

from __future__ import annotations

import numpy as np


def sector_polygons(p_key: int, p: np.ndarray, cycle_keys: np.ndarray, cycle_points: np.ndarray,
                    links: list, next_key: int):
    """Sector polygons of one cycle of a singular point.

    Parameters
    ----------
    p_key, p : key and position of the singular vertex
    cycle_keys, cycle_points : the cycle's vertices in order
    links : list of :class:`singmesh.skeleton.curves.SkeletonLink`, ordered
        along the cycle
    next_key : first unused vertex key (for nodes and traced points)

    Returns
    -------
    polygons : list of (keys (k,), points (k, 3)); the first vertex is p
    splits : dict
        ``(a, b) -> [(node_key, node_point), ...]`` for every cycle link
        a -> b that received face nodes (in order from a to b): the polygon
        on the other side of that link must get them too.
    next_key : int
    """
    m = len(cycle_keys)
    splits: dict = {}
    # The cycle with the face nodes inserted; anchors are the places where
    # a spoke (skeleton link) meets it.
    keys, pts, spokes = [], [], []
    for i in range(m):
        keys.append(int(cycle_keys[i]))
        pts.append(cycle_points[i])
        for s in (s for s in links if s.after == i):
            node_key = next_key
            trace_keys = list(range(next_key + 1, next_key + 1 + len(s.trace)))
            next_key += 1 + len(s.trace)
            a, b = int(cycle_keys[i]), int(cycle_keys[(i + 1) % m])
            splits.setdefault((a, b), []).append((node_key, s.node))
            spokes.append((len(keys), trace_keys, list(s.trace)))
            keys.append(node_key)
            pts.append(s.node)
    n = len(keys)
    if len(spokes) < 2:
        # Fewer than two skeleton links: anchor the sectors at cycle
        # vertices (with straight spokes) so that they still close around p.
        first = spokes[0][0] if spokes else 0
        extra = (first + n // 2) % n
        spokes = sorted(spokes + [(first, [], [])] * (not spokes) + [(extra, [], [])])
    if n < 3 or len({a for a, _, _ in spokes}) < 2:
        return [], splits, next_key  # a collapsed cycle: no area to fan
    polygons = []
    for k, (at, tkeys, tpts) in enumerate(spokes):
        nxt_at, nkeys, npts = spokes[(k + 1) % len(spokes)]
        steps = (nxt_at - at) % n or n
        # Spoke A runs out from p to the cycle, spoke B back in from it.
        a_keys = [p_key] + tkeys[::-1] + [keys[at]]
        a_pts = [p] + tpts[::-1] + [pts[at]]
        b_keys = [p_key] + nkeys[::-1] + [keys[nxt_at]]
        b_pts = [p] + npts[::-1] + [pts[nxt_at]]
        polygons += _zip_spokes(a_keys, a_pts, b_keys, b_pts)
        # The outer part: the cycle from A's end to B's end, closed by the
        # zipper's last edge (nothing left when they are neighbours).
        if steps >= 2:
            polygons.append((np.array([keys[(at + j) % n] for j in range(steps + 1)], np.int64),
                             np.array([pts[(at + j) % n] for j in range(steps + 1)])))
    return polygons, splits, next_key


def _zip_spokes(a_keys, a_pts, b_keys, b_pts) -> list:
    """Triangles between two spokes sharing their first vertex p.

    Rings from p outwards, each step advancing on the spoke whose next
    point gives the shorter diagonal: no triangle lies along one spoke,
    so neighbouring sectors never pick the same sliver.
    """
    tris = []
    i = j = 1
    tris.append(([a_keys[0], a_keys[1], b_keys[1]], [a_pts[0], a_pts[1], b_pts[1]]))
    while i < len(a_keys) - 1 or j < len(b_keys) - 1:
        adv_a = j == len(b_keys) - 1 or (
            i < len(a_keys) - 1
            and np.linalg.norm(a_pts[i + 1] - b_pts[j]) <= np.linalg.norm(a_pts[i] - b_pts[j + 1]))
        if adv_a:
            tris.append(([a_keys[i], a_keys[i + 1], b_keys[j]], [a_pts[i], a_pts[i + 1], b_pts[j]]))
            i += 1
        else:
            tris.append(([a_keys[i], b_keys[j + 1], b_keys[j]], [a_pts[i], b_pts[j + 1], b_pts[j]]))
            j += 1
    return [(np.array(k, np.int64), np.array(q)) for k, q in tris]


def insert_link_nodes(offsets: np.ndarray, keys: np.ndarray, points: np.ndarray, splits: dict):
    """Insert face nodes into the other side of every subdivided link.

    The polygon across a shared face link traverses it as b -> a; it gets
    the nodes in reverse order, so both sides share the same vertices and
    the mesh has no T-junction.
    """
    if not splits:
        return offsets, keys, points
    n = len(keys)
    poly = np.repeat(np.arange(len(offsets) - 1), np.diff(offsets))
    nxt = np.arange(n) + 1
    nxt[offsets[1:] - 1] = offsets[:-1]
    ends = np.array(sorted({b for _, b in splits}), dtype=np.int64)
    cand = np.nonzero(np.isin(keys, ends))[0]
    insert_after = {}
    for i in cand.tolist():
        pair = (int(keys[nxt[i]]), int(keys[i]))  # other side: b -> a
        if pair in splits:
            insert_after[i] = splits[pair][::-1]
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
