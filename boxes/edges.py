"""Crossings of the surface with the edges of the leaves.

Roots are computed once per *lattice line* (an axis-parallel line through
lattice points that carries leaf edges), never per box, so every box and
face that shares a piece of that line sees the same crossings: no cracks,
also between boxes of different sizes.

The rule for exact zeros is that of :mod:`singmesh.boxes.octree`: the
surface meshed is F + eps = 0.  Near a root r of F on a line, F + eps
crosses zero just left of r (event ``r-``) when F < 0 just left of r, and
just right of it (``r+``) when F < 0 just right of it.  So a simple root
gives one event, an edge tangency from below gives two (at the same place),
one from above none.  A root at a lattice point (F zero there to rounding)
is snapped onto it, so that every line through that point agrees.

Each event carries the direction in which F + eps changes sign along the
line (+1 for - to +), which orients the face links.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from singmesh import tolerances as tol
from singmesh.sorting import lexsort, search_sorted
from singmesh.surface import Surface

from .octree import Octree

#: Edges of a unit cube: (axis, offset in the two other axes (cyclic order)).
_EDGE_OFFSETS = [(a, du, dv) for a in range(3) for du in (0, 1) for dv in (0, 1)]
#: Stride of the integer key (line, lattice cell) that finds the events of
#: a segment; lattice coordinates stay below 2**(MAX_LEVEL + 1).
_LINE_STRIDE = np.int64(1) << (tol.MAX_LEVEL + 2)


@dataclass
class Events:
    """All crossing events on all lattice lines, sorted by line then position.

    Attributes
    ----------
    line : (E,) int64      line index (into ``lines``)
    pos : (E,) float64     position along the line, lattice units
    side : (E,) int8       -1 for ``r-``, +1 for ``r+``, 0 for a plain crossing
    snapped : (E,) bool    whether the root is a lattice point
    direction : (E,) int8  +1 if F + eps goes from - to + along the line axis
    key : (E,) int64       vertex identity (lattice point, or root on a line)
    point : (E, 3) float64 position in space
    cell_key : (E,) int64  sorted ``line * stride + cell``: the lattice cell
                           ``[c, c + 1)`` along the line holding the event
    lines : (L, 3) int64   (axis, u, v) of each line, u/v its fixed coordinates
    line_keys : (L,) int64 sorted :func:`line_keys` of ``lines``
    """

    line: np.ndarray
    pos: np.ndarray
    side: np.ndarray
    snapped: np.ndarray
    direction: np.ndarray
    key: np.ndarray
    point: np.ndarray
    cell_key: np.ndarray
    lines: np.ndarray
    line_keys: np.ndarray

    def lattice(self) -> np.ndarray:
        """(E, 3) float64: lattice coordinates of the events (the line's two fixed ones exact)."""
        return _line_xyz(self.lines[self.line], self.pos)

    def on_segments(self, axis, u, v, start, end):
        """Events on axis-parallel lattice segments ``[start, end)``.

        The same as ``searchsorted`` of the segments' ends in ``cell_key``,
        without its random look-ups: a line carries a few events (a
        polynomial's line meets F = 0 at most degree times), so the events
        of a segment's line below its start and end are counted in a few
        stacked steps.  Segments on lines with many events (periodic
        surfaces) are looked up with ``searchsorted``.

        Returns
        -------
        seg : (K,) int64   index of the segment each event lies on
        ev : (K,) int64    event index
        """
        axis, u, v, start, end = (np.asarray(a, np.int64) for a in (axis, u, v, start, end))
        ids = self.line_ids(axis, u, v)
        n_lines = len(self.line_keys)
        # The events of line l are cell_key[bounds[l]:bounds[l + 1]]: their
        # keys l * stride + cell lie in [l * stride - 1, l * stride + top]
        # (a snapped event at 0 on its - side is in cell -1).
        bounds = np.searchsorted(self.cell_key, np.arange(n_lines + 1, dtype=np.int64) * _LINE_STRIDE - 1)
        # Events per line, 0 for no line (-1 reads the last entry, 0).
        per_line = np.append(np.diff(bounds), 0)
        if len(ids) <= _SEGMENT_CHUNK:
            return self._on_segments(ids, start, end, bounds, per_line, 0)
        # In chunks: the dozen temporaries of a chunk stay in the cache and
        # in memory the allocator reuses (Barth: 227,000 segments made 12 MB
        # of fresh pages, 3,000 page faults); each segment's events do not
        # depend on the others, so the chunks' results in order are the whole's.
        parts = [self._on_segments(ids[a:a + _SEGMENT_CHUNK], start[a:a + _SEGMENT_CHUNK],
                                   end[a:a + _SEGMENT_CHUNK], bounds, per_line, a)
                 for a in range(0, len(ids), _SEGMENT_CHUNK)]
        return np.concatenate([q[0] for q in parts]), np.concatenate([q[1] for q in parts])

    def _on_segments(self, ids, start, end, bounds, per_line, offset):
        """:meth:`on_segments` of segments on lines ``ids`` (``offset``: the first one's index)."""
        # Only the segments on lines with events go on (half of a surface's
        # contact squares' edges have none): the rest have no event.
        on = np.flatnonzero(per_line[ids])
        line = ids[on]
        n_ev = per_line[line]
        lo_line = bounds[line]
        lo, hi = lo_line.copy(), lo_line.copy()
        k_lo = line * _LINE_STRIDE + start[on]
        k_hi = line * _LINE_STRIDE + end[on]
        many = n_ev > _FEW_EVENTS
        if many.any():
            lo[many] = search_sorted(self.cell_key, k_lo[many], side="left")
            hi[many] = search_sorted(self.cell_key, k_hi[many], side="left")
        # The j-th event of every line at once (whole arrays, masked where
        # a line has fewer: no gather and scatter of the segments still going).
        few = np.where(many, 0, n_ev)
        last = len(self.cell_key) - 1
        for j in range(int(few.max(initial=0))):
            key = self.cell_key[np.minimum(lo_line + j, last)] if j else self.cell_key[lo_line]
            has = few > j
            lo += (key < k_lo) & has
            hi += (key < k_hi) & has
        counts = hi - lo
        seg = np.repeat(on + offset, counts)
        first = np.repeat(lo - np.cumsum(counts) + counts, counts)
        ev = first + np.arange(counts.sum())
        return seg, ev

    def line_ids(self, axis, u, v) -> np.ndarray:
        """Index into ``lines`` of the lines (axis, u, v), -1 where none.

        A dense table over the lattice's (axis, u, v) when it is small (a
        gather instead of a binary search per query), else ``searchsorted``
        in ``line_keys``.
        """
        axis, u, v = (np.asarray(a, np.int64) for a in (axis, u, v))
        n_lines = len(self.line_keys)
        if n_lines == 0:
            return np.full(axis.shape, -1, np.int64)
        lo = min(int(u.min(initial=0)), int(v.min(initial=0)))
        m = max(int(self.lines[:, 1:].max()), int(u.max(initial=0)), int(v.max(initial=0))) + 1
        if lo >= 0 and 3 * m * m <= _DENSE_LINES:
            table = np.full(3 * m * m, -1, np.int32)
            table[(self.lines[:, 0] * m + self.lines[:, 1]) * m + self.lines[:, 2]] = np.arange(n_lines)
            return table[(axis * m + u) * m + v].astype(np.int64)
        q = line_keys(axis, u, v)
        ids = np.minimum(search_sorted(self.line_keys, q), n_lines - 1)
        return np.where(self.line_keys[ids] == q, ids, -1)


#: Lines with more events than this are looked up by binary search in
#: :meth:`Events.on_segments` (a polynomial line has at most 2 * degree).
_FEW_EVENTS = 16
#: Segments per chunk in :meth:`Events.on_segments` (temporaries of 128 kB).
_SEGMENT_CHUNK = 16384
#: Largest dense (axis, u, v) table of :meth:`Events.line_ids` and of the
#: lines of the leaf edges (entries; 16 MB of int32): lattices up to 1024
#: boxes per axis.
_DENSE_LINES = 1 << 22
#: Largest table of flags (bytes) for the distinct values of keys in a range.
_DENSE_KEYS = 1 << 25


def line_keys(axis, u, v) -> np.ndarray:
    return (np.asarray(axis, np.int64) << 40) | (np.asarray(u, np.int64) << 20) | np.asarray(v, np.int64)


def leaf_edges(tree: Octree):
    """All 12 edges of every leaf: (axis, u, v, start, end) in lattice units."""
    size = tree.size
    rows = []
    for a, du, dv in _EDGE_OFFSETS:
        ua, va = (a + 1) % 3, (a + 2) % 3
        rows.append(np.stack([
            np.full(len(size), a),
            tree.corner[:, ua] + du * size,
            tree.corner[:, va] + dv * size,
            tree.corner[:, a],
            tree.corner[:, a] + size,
        ], axis=1))
    return np.concatenate(rows) if rows else np.zeros((0, 5), np.int64)


def compute_events(surface: Surface, tree: Octree) -> Events:
    """Crossing events of F + eps on every lattice line carrying leaf edges."""
    edges = leaf_edges(tree)
    m = (1 << tree.fine_level) + 1  # lattice coordinates 0 .. 2**fine_level
    uniq, inverse, lines = _lines_of(edges, m)
    n_lines = len(uniq)
    lo = np.full(n_lines, np.iinfo(np.int64).max)
    hi = np.full(n_lines, np.iinfo(np.int64).min)
    np.minimum.at(lo, inverse, edges[:, 3])
    np.maximum.at(hi, inverse, edges[:, 4])

    # Lattice points at which F is zero: candidates for snapping.  Every
    # leaf corner is an end point of leaf edges on all three lines through it.
    # One int64 per (line, s), sorted as the rows (axis, u, v, s) are (the
    # lines are in the order of their keys): the distinct ones read back.
    packed = np.concatenate([inverse, inverse]) * m + np.concatenate([edges[:, 3], edges[:, 4]])
    packed = _distinct(packed, n_lines * m)
    corners = np.concatenate([lines[packed // m], (packed % m)[:, None]], axis=1)
    zero_line, zero_pos = _zero_lattice_points(surface, tree, corners, uniq)

    cell = tree.cell
    all_line, all_pos, all_snap = [], [], []
    for a in range(3):
        sel = np.nonzero(lines[:, 0] == a)[0]
        if len(sel) == 0:
            continue
        ua, va = (a + 1) % 3, (a + 2) % 3
        fixed = np.stack([tree.box[ua, 0] + lines[sel, 1] * cell[ua],
                          tree.box[va, 0] + lines[sel, 2] * cell[va]], axis=1)
        # The line's extent widened by one cell each side, so the sign
        # samples beyond the outermost roots see no other root.
        s0 = tree.box[a, 0] + (lo[sel] - 1) * cell[a]
        s1 = tree.box[a, 0] + (hi[sel] + 1) * cell[a]
        row, s = surface.line_roots(a, fixed, s0, s1)
        pos = (s - tree.box[a, 0]) / cell[a]
        all_line.append(sel[row])
        all_pos.append(pos)
        all_snap.append(np.zeros(len(row), bool))
    all_line.append(zero_line)
    all_pos.append(zero_pos.astype(float))
    all_snap.append(np.ones(len(zero_line), bool))
    line_of = np.concatenate(all_line)
    pos = np.concatenate(all_pos)
    snap = np.concatenate(all_snap)

    line_of, pos, snap = _cluster(line_of, pos, snap, lines, tree)
    return _events_from_roots(surface, tree, lines, uniq, line_of, pos, snap)


def _zero_lattice_points(surface, tree, corners, uniq):
    """(line, position) of every leaf corner where F is zero, on each line through it."""
    xyz = _corner_xyz(corners)
    # A lattice point is a corner on up to three lines: F is read once
    # there.  Every leaf corner is the end of one of the leaf's edges along
    # x, so the corners on the lines along x are all the distinct points;
    # the (few) zeros among them are looked up for the other lines.
    b = tol.MAX_LEVEL + 1
    packed = (xyz[:, 0] << (2 * b)) | (xyz[:, 1] << b) | xyz[:, 2]
    along_x = corners[:, 0] == 0
    zero_keys = np.sort(packed[along_x][surface.is_zero(tree.lattice_to_space(xyz[along_x]))])
    if len(zero_keys) == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    at = np.minimum(np.searchsorted(zero_keys, packed), len(zero_keys) - 1)
    zero = zero_keys[at] == packed
    xyz = xyz[zero]
    a = corners[zero, 0]
    u = xyz[np.arange(len(a)), (a + 1) % 3]
    v = xyz[np.arange(len(a)), (a + 2) % 3]
    ids = search_sorted(uniq, line_keys(a, u, v))
    return ids, xyz[np.arange(len(a)), a]


def _distinct(keys: np.ndarray, bound: int) -> np.ndarray:
    """The distinct values of a 1-D int64 array of values in [0, bound), sorted.

    A table of ``bound`` flags when that is small (no sort), else a plain
    sort (``np.unique`` would use a hash table, slower on many values).
    """
    if bound <= _DENSE_KEYS:
        present = np.zeros(bound, bool)
        present[keys] = True
        return np.flatnonzero(present)
    keys = np.sort(keys)
    return keys[np.concatenate([[True], keys[1:] != keys[:-1]])] if len(keys) else keys


def _lines_of(edges: np.ndarray, m: int):
    """The lattice lines carrying ``edges`` (axis, u, v, start, end) on a lattice of ``m`` points per axis.

    Returns
    -------
    keys : (L,) int64   sorted :func:`line_keys`
    inverse : (E,) int64 the line of each edge
    lines : (L, 3) int64 (axis, u, v) of each line
    """
    dense = (edges[:, 0] * m + edges[:, 1]) * m + edges[:, 2]  # ordered as line_keys
    if 3 * m * m <= _DENSE_LINES:
        ids = _distinct(dense, 3 * m * m)
        rank = np.zeros(3 * m * m, np.int32)
        rank[ids] = np.arange(len(ids))
        inverse = rank[dense].astype(np.int64)
    else:
        ids, inverse = np.unique(dense, return_inverse=True)
        inverse = inverse.ravel()
    lines = np.stack([ids // (m * m), ids // m % m, ids % m], axis=1)
    return line_keys(lines[:, 0], lines[:, 1], lines[:, 2]), inverse, lines


def _unpack(packed: np.ndarray, fields: int, bits: int) -> np.ndarray:
    """Rows of ``fields`` non-negative ints of ``bits`` bits each, packed first field highest."""
    mask = (np.int64(1) << bits) - 1
    return np.stack([(packed >> (bits * (fields - 1 - i))) & mask for i in range(fields)], axis=1)


def _line_xyz(rows: np.ndarray, pos: np.ndarray) -> np.ndarray:
    """Lattice (x, y, z) (k, 3) of the points at positions ``pos`` along lines (axis, u, v) ``rows``."""
    xyz = np.zeros((len(pos), 3))
    r = np.arange(len(pos))
    xyz[r, rows[:, 0]] = pos
    xyz[r, (rows[:, 0] + 1) % 3] = rows[:, 1]
    xyz[r, (rows[:, 0] + 2) % 3] = rows[:, 2]
    return xyz


def _corner_xyz(corners):
    """Lattice (x, y, z) of rows (axis, u, v, s) describing a point on a line."""
    a = corners[:, 0]
    xyz = np.zeros((len(corners), 3), np.int64)
    idx = np.arange(len(corners))
    xyz[idx, a] = corners[:, 3]
    xyz[idx, (a + 1) % 3] = corners[:, 1]
    xyz[idx, (a + 2) % 3] = corners[:, 2]
    return xyz


def _cluster(line_of, pos, snap, lines, tree):
    """Merge roots of one line closer than the cluster tolerance.

    A cluster containing a zero lattice point, or within SNAP_LATTICE of
    one, becomes that lattice point.
    """
    order = lexsort((pos, line_of))
    line_of, pos, snap = line_of[order], pos[order], snap[order]
    if len(pos) == 0:
        return line_of, pos, snap
    length = np.float64(1 << tree.fine_level)
    close = (np.diff(line_of) == 0) & (np.diff(pos) <= max(tol.ROOT_CLUSTER * length, tol.SNAP_LATTICE))
    group = np.concatenate([[0], np.cumsum(~close)])
    n = group[-1] + 1
    g_line = np.zeros(n, np.int64)
    g_line[group] = line_of
    g_snap = np.zeros(n, bool)
    np.logical_or.at(g_snap, group, snap)
    total = np.zeros(n)
    np.add.at(total, group, pos)
    g_pos = total / np.bincount(group, minlength=n)
    snapped_pos = np.zeros(n)
    np.maximum.at(snapped_pos, group, np.where(snap, pos, -np.inf))
    g_pos = np.where(g_snap, snapped_pos, g_pos)
    return g_line, g_pos, g_snap


def _events_from_roots(surface, tree, lines, uniq, line_of, pos, snap) -> Events:
    """Turn root clusters into events using the signs of F between them."""
    # Sign samples: half-way to the neighbouring root on the same line, or
    # half a cell beyond the outermost root.
    left, right = _side_signs(surface, tree, lines, line_of, pos)
    line_of, pos, snap, left, right = _drop_false_touchings(surface, tree, lines, line_of, pos, snap, left, right)

    # Events: r- where F < 0 on the left, r+ where F < 0 on the right; a
    # plain (unsnapped) sign change is one event at the root itself.
    simple = ~snap & (left * right < 0)
    minus = ~simple & (left < 0)
    plus = ~simple & (right < 0)
    idx = np.concatenate([np.nonzero(simple)[0], np.nonzero(minus)[0], np.nonzero(plus)[0]])
    side = np.concatenate([np.zeros(simple.sum()), -np.ones(minus.sum()), np.ones(plus.sum())]).astype(np.int8)
    direction = np.concatenate([
        np.where(right[simple] > 0, 1, -1), np.ones(minus.sum()), -np.ones(plus.sum()),
    ]).astype(np.int8)

    ev_line = line_of[idx]
    ev_pos = pos[idx]
    ev_snap = snap[idx]
    order_pos = ev_pos + np.where(ev_snap, side * 1e-3, 0.0)
    order = lexsort((side, order_pos, ev_line))
    ev_line, ev_pos, ev_snap, side, direction, idx = (
        ev_line[order], ev_pos[order], ev_snap[order], side[order], direction[order], idx[order])
    # Exact integer membership: a float key mixing line and position would
    # round a root 1e-8 below a lattice point onto it (and into the next
    # segment).  A snapped event sits a fraction of a cell to its side.
    cell_key = ev_line * _LINE_STRIDE + np.floor(order_pos[order]).astype(np.int64)

    ln = lines[ev_line]
    xyz = _line_xyz(ln, ev_pos)
    point = tree.lattice_to_space(xyz)
    # A root within SNAP_DISTANCE (of the box) of a lattice point: the
    # roots of the other lines through that point are as close; apart,
    # they would be vertices 1e-11 apart with zero-area slivers between
    # (a thin cusp, a sheet grazing a lattice point).  They share the
    # point's key and one position, the lattice point moved onto the
    # surface.  The events keep their places on their lines (and so
    # their segments): only the vertex is shared.
    lattice = np.rint(xyz)
    size = float(np.max(tree.box[:, 1] - tree.box[:, 0]))
    near = np.nonzero(~ev_snap & (np.abs(ev_pos - np.rint(ev_pos)) * tree.cell[ln[:, 0]]
                                  <= tol.SNAP_DISTANCE * size))[0]
    top = 1 << tree.fine_level
    free = (lattice[near] > 0) & (lattice[near] < top)   # axes along which the point may move
    if len(near):  # usually none: no Newton steps on empty arrays
        q, ok = _onto_surface(surface, tree.lattice_to_space(lattice[near]), free, 4 * tol.SNAP_DISTANCE * size)
        near = near[ok]
        point[near] = q[ok]
    m = (1 << tree.fine_level) + 1
    lattice_key = (lattice[:, 0].astype(np.int64) * m + lattice[:, 1].astype(np.int64)) * m \
        + lattice[:, 2].astype(np.int64)
    shared = ev_snap.copy()
    shared[near] = True
    key = np.where(shared, lattice_key, m ** 3 + idx)
    return Events(line=ev_line, pos=ev_pos, side=side, snapped=ev_snap, direction=direction,
                  key=key, point=point, cell_key=cell_key, lines=lines, line_keys=uniq)


def _drop_false_touchings(surface, tree, lines, line_of, pos, snap, left, right):
    """The roots without those where F < 0 on both sides but F is not zero at the root itself.

    Such a root (a touching from below: two events at one place) comes
    from eigenvalues a +- ib with b below ``ROOT_IMAG``: a double root, or
    a pair of complex roots of a line that passes beside the surface.
    Where F at a is not zero to its rounding (``Surface.is_zero``) the
    line misses the surface (fuzz s1-472: F = -1.85e-17 there against
    terms of 3e-16, the surface 1.4e-5 of the box away), and a vertex
    there would be off it.
    """
    touch = np.flatnonzero(~snap & (left < 0) & (right < 0))
    if len(touch) == 0:
        return line_of, pos, snap, left, right
    false = touch[~surface.is_zero(tree.lattice_to_space(_line_xyz(lines[line_of[touch]], pos[touch])))]
    if len(false) == 0:
        return line_of, pos, snap, left, right
    keep = np.ones(len(pos), bool)
    keep[false] = False
    return line_of[keep], pos[keep], snap[keep], left[keep], right[keep]


def _onto_surface(surface, points: np.ndarray, free: np.ndarray, reach: float):
    """Lattice points moved onto the surface, along the axes they are free to move.

    A point on a face (edge) of the domain moves in that face (along that
    edge), so that it stays on the domain's boundary; a corner cannot move.
    Newton steps along the free part of grad F.

    Returns
    -------
    points : (K, 3)
    ok : (K,) bool   the point reached the surface within ``reach``
    """
    start = points.copy()
    points = surface.project(points, free, iterations=3)
    ok = surface.is_zero(points) & (np.linalg.norm(points - start, axis=1) <= reach)
    return points, ok


def _side_signs(surface, tree, lines, line_of, pos):
    """Signs of F + eps (zero counts as +) half-way to the neighbouring roots of a line, or
    half a cell beyond the outermost: (left, right) of each root, roots sorted by line and position."""
    same_prev = np.concatenate([[False], line_of[1:] == line_of[:-1]])
    same_next = np.concatenate([line_of[:-1] == line_of[1:], [False]])[:len(pos)]
    prev = np.where(same_prev, np.roll(pos, 1), pos - 1.0)[:len(pos)]
    # The sample right of a root is the one left of the next root on its
    # line (the same midpoint, to the bit): F is read once there, in one
    # call with the samples beyond each line's last root.
    last = np.flatnonzero(~same_next)
    rows = lines[np.concatenate([line_of, line_of[last]])]
    a = np.concatenate([prev, pos[last]])
    b = np.concatenate([pos, pos[last] + 1.0])
    both, zero = _signs(surface, tree, rows, (a + b) / 2, zeros=True)
    # F zero to rounding at the middle between two roots, where it is not
    # zero a quarter of the way to either: the middle lies on a patch of
    # F = 0 without sign change (two boxes joined by Min touching along a
    # face: a line through the top face of one and the bottom face of the
    # other, at the same distance from the patch, has its midpoint on it).
    # Read as +, both roots were touchings and the strips next to the two
    # faces had no events (the float-rotated stack of boxes: 602 open
    # edges).  Between two roots F has one sign: the quarters tell it.
    for frac in (0.25, 0.75):
        redo = np.flatnonzero(zero)
        if not len(redo):
            break
        sign, z = _signs(surface, tree, rows[redo], a[redo] + frac * (b[redo] - a[redo]), zeros=True)
        both[redo[~z]] = sign[~z]
        zero[redo[~z]] = False
    left = both[:len(pos)]
    right = np.empty_like(left)
    right[last] = both[len(pos):]
    inner = np.flatnonzero(same_next)
    right[inner] = left[inner + 1]
    # Between two roots F has one sign only where it is continuous: across
    # a pole (tan(2x) + 1.5 between its roots at x = -0.49 and 1.08, with
    # the pole at pi/4 between) it changes sign without a zero, and the
    # midpoint's sign may be that of the far side.  Both samples of such a
    # root read +: a touching, no event, and the boxes on both sides of the
    # line lost their cycles, far from the pole (tan(2x) + tan(2y) - z: 874
    # open edges away from the poles on main).  Each root reads its own
    # side instead, at a sample moved towards it until F is continuous
    # between (also past an end of F's domain, where the midpoint is NaN).
    prev_mid = (prev + pos) / 2
    next_mid = np.empty_like(pos)
    next_mid[last] = pos[last] + 0.5
    next_mid[inner] = prev_mid[inner + 1]
    for sample, out in ((prev_mid, left), (next_mid, right)):
        moved, at = _towards_continuity(surface, tree, lines[line_of], pos, sample)
        if len(moved):
            out[moved] = _signs(surface, tree, lines[line_of[moved]], at)
    return left, right


def _towards_continuity(surface, tree, rows, pos, sample):
    """Samples (lattice positions on lines ``rows``) moved towards their roots ``pos`` until F is continuous
    between: (which, new positions) of those moved, at most ``SIGN_SAMPLE_HALVINGS`` halvings each.

    Then half-way again: the first sample with F continuous up to the root
    may lie a rounding error beside the pole (1 / cos(2.1 x) + 2 between
    its roots +-0.997 has the pole 0.748 three quarters of the way from
    the midpoint 0), where F is 1e15 and zero relative to its terms; the
    point half-way to the root is as far from the pole as from the root.
    """
    def gap(which, at):
        p = tree.lattice_to_space(_line_xyz(rows[which], pos[which]))
        q = tree.lattice_to_space(_line_xyz(rows[which], at))
        return ~surface.continuous_on(np.minimum(p, q), np.maximum(p, q))

    bad = np.flatnonzero(gap(np.arange(len(pos)), sample))
    at = sample[bad].copy()
    todo = np.arange(len(bad))
    for _ in range(tol.SIGN_SAMPLE_HALVINGS):
        if not len(todo):
            break
        at[todo] = pos[bad[todo]] + 0.5 * (at[todo] - pos[bad[todo]])
        todo = todo[gap(bad[todo], at[todo])]
    done = np.ones(len(bad), bool)
    done[todo] = False
    at[done] = pos[bad[done]] + 0.5 * (at[done] - pos[bad[done]])
    return bad, at


def _signs(surface, tree, lines_rows, pos, zeros: bool = False):
    """Sign of F + eps at positions on lines: F zero to its rounding counts as +.

    As at the lattice points (snapped, ``Surface.is_zero``): along a line
    that lies in the surface (a plane with rational coefficients through
    lattice lines) F is rounding noise of either sign, and read as is it
    would make r- and r+ events at random lattice points along it.
    With ``zeros``, also which of them are zero to rounding: (signs, zero).
    """
    points = tree.lattice_to_space(_line_xyz(lines_rows, pos))
    f = surface(points)
    negative = f < 0
    zero = np.zeros(len(f), bool)
    if zeros:
        # Every negative value, as below; of the others only those far
        # below the largest (rounding noise is).
        ask = negative | (np.abs(f) <= tol.SIGN_ZERO_PREFILTER * max(float(np.nanmax(np.abs(f), initial=0.0)), 1e-300))
        if ask.any():
            zero[ask] = surface.is_zero(points[ask])
        negative &= ~zero
    elif negative.any():
        negative[negative] = ~surface.is_zero(points[negative])
    signs = np.where(negative, -1, 1)
    return (signs, zero) if zeros else signs
