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

    def record(s, key):
        a, b = int(cycle_keys[s.after]), int(cycle_keys[(s.after + 1) % m])
        splits.setdefault((a, b), []).append((key, s.node))

    if len(links) < 2:
        keys = [p_key]
        pts = [p]
        for i in range(m):
            keys.append(int(cycle_keys[i]))
            pts.append(cycle_points[i])
            for s in links:
                if s.after == i:
                    record(s, next_key)
                    keys.append(next_key)
                    pts.append(s.node)
                    next_key += 1
        return [(np.array(keys), np.array(pts))], splits, next_key

    # Keys for each link's node and traced points (node first, then inwards).
    spokes = []
    for s in links:
        pts = np.concatenate([s.node[None], s.trace])
        keys = np.arange(next_key, next_key + len(pts))
        next_key += len(pts)
        spokes.append((keys, pts))
        record(s, int(keys[0]))
    polygons = []
    for k, s in enumerate(links):
        nxt = links[(k + 1) % len(links)]
        keys = [p_key] + spokes[k][0][::-1].tolist()
        pts = [p] + list(spokes[k][1][::-1])
        i = s.after
        # Walk the cycle from just after node k to just before node k+1.
        steps = (nxt.after - s.after) % m
        if steps == 0 and (k + 1) % len(links) != k and nxt.t <= s.t:
            steps = m
        for j in range(1, steps + 1):
            idx = (i + j) % m
            keys.append(int(cycle_keys[idx]))
            pts.append(cycle_points[idx])
        keys += spokes[(k + 1) % len(links)][0].tolist()
        pts += list(spokes[(k + 1) % len(links)][1])
        polygons.append((np.array(keys), np.array(pts)))
    return polygons, splits, next_key


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
