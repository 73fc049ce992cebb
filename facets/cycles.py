"""Cycles of the link graph of each box.

Each leaf sees the links of the contact squares on its boundary: as given
on the squares it has on its +n faces, reversed on its -n faces (the
outward normal is then -n).  In a box every event has then one link in
and one out, so the links of a box form disjoint oriented cycles: the
boundaries of the pieces of surface in the box.  For a simple box each
cycle bounds one disc, a facet.

The graph is held as a networkx ``DiGraph`` per box only on request
(:func:`box_graph`); the cycles of all boxes are found at once on arrays.
"""

from __future__ import annotations

from dataclasses import dataclass

import networkx as nx
import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from singmesh.sorting import lexsort, unique_inverse


@dataclass
class Cycles:
    """Oriented cycles of events, one row block per cycle.

    Attributes
    ----------
    box : (C,) int64          leaf of each cycle
    offsets : (C+1,) int64    cycle c is ``events[offsets[c]:offsets[c+1]]``
    events : (S,) int64       event indices in cycle order
    squares : (S,) int64      contact square of the link leaving each event
    broken_boxes : (B,) int64 leaves whose links did not form cycles
    """

    box: np.ndarray
    offsets: np.ndarray
    events: np.ndarray
    squares: np.ndarray
    broken_boxes: np.ndarray

    def __len__(self) -> int:
        return len(self.box)


def box_links(links, group: np.ndarray | None = None):
    """Links as seen by each box: (box, from_event, to_event, square).

    Parameters
    ----------
    links : FaceLinks
    group : (N,) int64, optional
        Box id of every leaf.  Leaves sharing an id are one box (the star
        of a singular point); links on squares inside such a box are
        dropped, only its outer boundary counts.
    """
    minus = links.minus[links.link_square]
    plus = links.plus[links.link_square]
    if group is not None:
        minus = np.where(minus >= 0, group[np.maximum(minus, 0)], -1)
        plus = np.where(plus >= 0, group[np.maximum(plus, 0)], -1)
        inner = minus == plus
        minus = np.where(inner, -1, minus)
        plus = np.where(inner, -1, plus)
    has_minus, has_plus = minus >= 0, plus >= 0
    box = np.concatenate([minus[has_minus], plus[has_plus]])
    src = np.concatenate([links.start[has_minus], links.end[has_plus]])
    dst = np.concatenate([links.end[has_minus], links.start[has_plus]])
    sq = np.concatenate([links.link_square[has_minus], links.link_square[has_plus]])
    return box, src, dst, sq


def box_graph(box_links_arrays, box: int) -> nx.DiGraph:
    """The link graph of one leaf as a networkx DiGraph (for inspection)."""
    b, src, dst = box_links_arrays[:3]
    sel = b == box
    g = nx.DiGraph()
    g.add_edges_from(zip(src[sel].tolist(), dst[sel].tolist()))
    return g


def find_cycles(box: np.ndarray, src: np.ndarray, dst: np.ndarray, square: np.ndarray,
                n_events: int, key: np.ndarray | None = None) -> Cycles:
    """Orbits of the successor map of every box's links.

    With the events' vertex ``key`` (E,), a box whose links break at a
    lattice point first gets its two events there joined
    (:func:`_corner_bridges`).
    """
    node_src = box * n_events + src
    node_dst = box * n_events + dst
    nodes, inv = unique_inverse(np.concatenate([node_src, node_dst]))
    a, b = inv[: len(src)], inv[len(src):]
    n = len(nodes)
    out_deg = np.bincount(a, minlength=n)
    in_deg = np.bincount(b, minlength=n)
    node_box = nodes // n_events
    bad_node = (out_deg != 1) | (in_deg != 1)
    if key is not None and bad_node.any():
        more = _corner_bridges(nodes, a, b, out_deg, in_deg, square, n_events, key)
        if len(more[0]):
            return find_cycles(np.concatenate([box, more[0]]), np.concatenate([src, more[1]]),
                               np.concatenate([dst, more[2]]), np.concatenate([square, more[3]]), n_events)
    broken = np.unique(node_box[bad_node])
    good = ~np.isin(box, broken)
    a, b, square = a[good], b[good], square[good]
    if len(a) == 0:
        empty = np.zeros(0, np.int64)
        return Cycles(empty, np.zeros(1, np.int64), empty, empty, broken)
    nxt = np.full(n, -1, np.int64)
    nxt[a] = b
    out_square = np.full(n, -1, np.int64)
    out_square[a] = square
    graph = coo_matrix((np.ones(len(a)), (a, b)), shape=(n, n))
    _, label = connected_components(graph, directed=True, connection="weak")
    used = np.zeros(n, bool)
    used[a] = True
    # Walk every cycle from its smallest node, all cycles in step.
    roots = np.full(label.max() + 1, n, np.int64)
    np.minimum.at(roots, label[used], np.nonzero(used)[0])
    roots = roots[roots < n]
    position = np.full(n, -1, np.int64)
    cur = roots.copy()
    step = 0
    while len(cur):
        position[cur] = step
        cur = nxt[cur]
        cur = cur[position[cur] < 0]
        step += 1
    cyc = label[used]
    idx = np.nonzero(used)[0]
    order = lexsort((position[idx], cyc))
    idx, cyc = idx[order], cyc[order]
    # The first of each run of the (sorted) labels: np.unique's
    # return_index, without its sort.
    start = np.flatnonzero(np.r_[True, cyc[1:] != cyc[:-1]]) if len(cyc) else np.zeros(0, np.int64)
    offsets = np.append(start, len(idx))
    return Cycles(box=node_box[idx[start]], offsets=offsets, events=nodes[idx] % n_events,
                  squares=out_square[idx], broken_boxes=broken)


def _corner_bridges(nodes: np.ndarray, a: np.ndarray, b: np.ndarray, out_deg: np.ndarray, in_deg: np.ndarray,
                    square: np.ndarray, n_events: int, key: np.ndarray):
    """Links (box, src, dst, square) joining a box's two events at one lattice point where its links break.

    F = 0 at a lattice point P is an event on each lattice line through P
    that F crosses there, each put in a cell beside P (its ``side``); the
    face square holding both pairs them with a link of length zero.  Where
    that square is missing from the box's boundary (it faces a cell with
    no surface inside, pruned, against a larger leaf: the y-axis on
    ``x y^5 + z^5 + ...``, fuzz s6-601) the box's cycle stops at one event
    of P and starts again at the other.  Where a box has exactly one event
    with no link out and one with no link in at the same vertex key, the
    missing link joins them, from the first to the second, in the square
    of the link arriving at the first.
    """
    gap = in_deg - out_deg
    loose = np.flatnonzero((np.abs(gap) == 1) & (np.maximum(in_deg, out_deg) == 1))
    empty = np.zeros(0, np.int64)
    if len(loose) == 0:
        return empty, empty, empty, empty
    lbox, lev = nodes[loose] // n_events, nodes[loose] % n_events
    order = lexsort((gap[loose], key[lev], lbox))
    loose, lbox, lev = loose[order], lbox[order], lev[order]
    same = (lbox[1:] == lbox[:-1]) & (key[lev[1:]] == key[lev[:-1]])
    # Neighbours in this order at one (box, key), no third there: the one
    # with no link in (gap -1) first.
    alone = np.ones(len(loose) - 1, bool) if len(loose) > 1 else np.zeros(0, bool)
    if len(alone) > 1:
        alone[1:] &= ~same[:-1]
        alone[:-1] &= ~same[1:]
    pair = np.flatnonzero(same & alone & (gap[loose[:-1]] == -1) & (gap[loose[1:]] == 1))
    start, end = loose[pair], loose[pair + 1]  # no link in; no link out
    # The square of the link arriving at ``end``.
    arrive = np.full(len(nodes), -1, np.int64)
    arrive[b] = square
    return lbox[pair], nodes[end] % n_events, nodes[start] % n_events, arrive[end]


def lens_leaves(cycles: Cycles, level: np.ndarray, corner: np.ndarray, fine_level: int,
                lattice: np.ndarray, on_box: np.ndarray, snapped: np.ndarray) -> np.ndarray:
    """Leaves above the fine level holding a piece of surface cut off by the box's boundary
    that no polygon stands for.

    A cycle whose events all lie on one face of its leaf has its polygon
    in that face (or none: two events on one edge), while the piece of
    surface it bounds bulges into the leaf, meeting no edge off that face.
    Inside the box the neighbours' polygons across the face cover the
    piece up to the bulge, and those bulges are many and shallow (Barth's
    sextic, the half ball), left as they are.  Where the piece meets the
    box's boundary there are no such neighbours there: a sliver cut off by
    an edge of the box (fuzz s4-26, 25 cells long), a cap cut off by a face
    of the box across one leaf edge (s3-905: 6 cells across, in two coarse
    leaves each with two events on their shared edge) is dropped without a
    word, or cut short by up to the leaf's width where a neighbour is
    finer (s4-141, 6 cells).  Such a leaf is to be split: its children see
    the piece on more edges.  A cycle of lattice points alone is not such
    a piece but a line of the surface along a lattice line (the x-axis of
    the D4 y x^2 - y^3 - z^2, which the sheet touches): split, the leaf's
    children see it the same way.

    Parameters
    ----------
    cycles : Cycles
    level : (N,) int64
        Level of every leaf; box ids from ``N`` on (stars, tubes) are not leaves.
    corner : (N, 3) int64
        Lower corner of every leaf (lattice units).
    fine_level : int
    lattice : (E, 3) float64
        Lattice coordinates of the events (:meth:`Events.lattice`; the two
        of a lattice line exact integers).
    on_box : (E,) bool
        Per event: whether it lies on a face of the box.
    snapped : (E,) bool
        Per event: whether it is a lattice point.

    Returns
    -------
    (K,) int64
        Sorted leaf indices.
    """
    if len(cycles) == 0:
        return np.zeros(0, np.int64)
    runs = cycles.offsets[:-1]
    box = np.repeat(cycles.box, np.diff(cycles.offsets))
    b = np.where(box < len(level), box, 0)
    lo = corner[b].astype(float)
    hi = lo + np.left_shift(1, fine_level - level[b])[:, None].astype(float)
    p = lattice[cycles.events]
    on_face = np.concatenate([p == lo, p == hi], axis=1)  # (S, 6): on each face of its leaf
    flat = np.logical_and.reduceat(on_face, runs, axis=0).any(axis=1)
    touches = np.logical_or.reduceat(on_box[cycles.events], runs)
    lattice_only = np.logical_and.reduceat(snapped[cycles.events], runs)
    out = cycles.box[flat & touches & ~lattice_only & (cycles.box < len(level))]
    return np.unique(out[level[out] < fine_level])
