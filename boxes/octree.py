"""Octree subdivision of a box with pruning, level by level on stacked arrays.

Boxes are addressed on the integer lattice of the finest level: a box at
``level`` has its lower corner at ``corner`` (lattice units) and side
``2**(fine_level - level)``.  Exact zeros follow one rule everywhere
(simulation of simplicity): F is meshed as if it were F + eps for an
infinitesimal eps > 0.  A box is pruned only when the surface says F has
no zero in it at all (beyond rounding: ``Surface.excludes_zero``), so no
event can lie on its boundary.

The octree knows F only through the surface interface
(:class:`singmesh.surface.Surface`): ``enclose`` gives the root's ``data``,
``split`` its children's, ``excludes_zero`` prunes and ``simple_axis``
stops the refinement.  The stacks of ``data`` are opaque: they are only
indexed, concatenated and kept per leaf.

A box is *simple* when the surface in it is a union of discs, each bounded
by one cycle of face links (see ``Surface.simple_axis``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from singmesh import tolerances as tol
from singmesh.sorting import search_sorted
from singmesh.surface import CHILD_OFFSETS, Surface


#: Bits per lattice coordinate and the shift of the level in a node key.
_BITS = 16


def node_keys(level: np.ndarray, cell: np.ndarray) -> np.ndarray:
    """One int64 per octree node: its level and its cell index at that level."""
    cell = np.asarray(cell, dtype=np.int64)
    return (
        (np.asarray(level, dtype=np.int64) << (3 * _BITS))
        | (cell[..., 0] << (2 * _BITS))
        | (cell[..., 1] << _BITS)
        | cell[..., 2]
    )


@dataclass
class Octree:
    """Leaves of the subdivision and what the later stages need of the tree.

    Attributes
    ----------
    box : (3, 2) ndarray
        The domain ``[[x0, x1], [y0, y1], [z0, z1]]``.
    fine_level : int
        Lattice units are cells of the finest level, ``2**fine_level`` per axis.
    level : (N,) int64
        Level of each leaf.
    corner : (N, 3) int64
        Lower corner of each leaf in lattice units.
    data : (N, ...) float64
        The surface's bounds ``data`` on each leaf (``Surface.enclose``):
        for a polynomial its Bernstein tensors (from :func:`subdivide`
        a :class:`StackedRows` of the levels' stacks, from
        :func:`refine_stars` a :class:`KeptRows`: each indexed as the array).
    simple : (N,) bool
        Whether the leaf passed the simplicity test.
    internal : (M,) int64, sorted
        Keys (:func:`node_keys`) of the nodes that were split.
    """

    box: np.ndarray
    fine_level: int
    level: np.ndarray
    corner: np.ndarray
    data: np.ndarray
    simple: np.ndarray
    internal: np.ndarray

    @property
    def size(self) -> np.ndarray:
        """Side of each leaf in lattice units."""
        return np.left_shift(1, self.fine_level - self.level)

    @property
    def cell(self) -> np.ndarray:
        """Lattice spacing (x, y, z) of the finest level."""
        return (self.box[:, 1] - self.box[:, 0]) / (1 << self.fine_level)

    def lattice_to_space(self, lattice) -> np.ndarray:
        """Coordinates of lattice points (any float lattice coordinates)."""
        return self.box[:, 0] + np.asarray(lattice, dtype=float) * self.cell

    def leaf_keys(self) -> np.ndarray:
        return node_keys(self.level, self.corner >> (self.fine_level - self.level)[:, None])

    def sorted_leaf_keys(self) -> tuple[np.ndarray, np.ndarray]:
        """``order = np.argsort(leaf_keys())`` and the keys in that order, made once per tree.

        The leaf look-ups (:meth:`find_leaves`, :func:`containing_leaves`)
        each sorted the keys again: twice per tree in a mesh.  The keys are
        distinct, so the order is the same whichever sort made it.  Kept
        with the ``level`` and ``corner`` arrays they were made from (a tree
        given new ones makes them again).
        """
        kept = self.__dict__.get("_sorted_keys")
        if kept is None or kept[0] is not self.level or kept[1] is not self.corner:
            keys = self.leaf_keys()
            order = np.argsort(keys)
            sorted_keys = keys[order]
            order.setflags(write=False)
            sorted_keys.setflags(write=False)
            kept = (self.level, self.corner, order, sorted_keys)
            self.__dict__["_sorted_keys"] = kept
        return kept[2], kept[3]

    def find_leaves(self, doubled: np.ndarray, guess: np.ndarray | None = None) -> np.ndarray:
        """Index of the leaf containing each point, or -1.

        Parameters
        ----------
        doubled : (K, 3) int64
            Twice the lattice coordinates of the query points; a point must
            lie strictly inside one leaf (never on a face), as face centres
            pushed half a cell off the face do.
        guess : (K,) int64, optional
            A level to look at first for each point (where its leaf likely
            is); the others are looked at after, as without.  Leaves do not
            overlap: the same leaves either way, with fewer look-ups where
            the guesses are good.
        """
        order, sorted_keys = self.sorted_leaf_keys()
        found = np.full(len(doubled), -1, dtype=np.int64)
        todo = np.arange(len(doubled))
        if guess is not None and len(todo):
            # Each point at its own guessed level: one look-up of all keys.
            guess = np.asarray(guess, np.int64)
            q = node_keys(guess, doubled >> (self.fine_level - guess + 1)[:, None])
            pos = np.minimum(search_sorted(sorted_keys, q), len(sorted_keys) - 1)
            hit = sorted_keys[pos] == q
            found[hit] = order[pos[hit]]
            todo = todo[~hit]
        for lvl in np.unique(self.level).tolist():
            # Only the points no leaf of another level holds yet.
            shift = self.fine_level - lvl + 1
            q = node_keys(np.full(len(todo), lvl), doubled[todo] >> shift)
            pos = np.minimum(search_sorted(sorted_keys, q), len(sorted_keys) - 1)
            hit = sorted_keys[pos] == q
            found[todo[hit]] = order[pos[hit]]
            todo = todo[~hit]
        return found


def containing_leaves(tree: Octree, points: np.ndarray, rel: float = 1e-9) -> tuple[np.ndarray, np.ndarray]:
    """Leaves whose closed box contains each point (1 to 8 per point).

    A point on a face, edge or corner shared by several leaves gets all of
    them, so that it lies strictly inside their union.  All points at once:
    eight probes around each, looked up level by level in the sorted keys.

    Returns
    -------
    point, leaf : (K,) int64 pairs, sorted, without repeats
    """
    points = np.asarray(points, float).reshape(-1, 3)
    lattice = (points - tree.box[:, 0]) / tree.cell
    offsets = np.array(np.meshgrid([-1, 1], [-1, 1], [-1, 1], indexing="ij")).reshape(3, -1).T
    probes = (lattice[:, None, :] + rel * offsets[None]).reshape(-1, 3)
    owner = np.repeat(np.arange(len(points)), 8)
    top = 1 << tree.fine_level
    inside = ((probes >= 0) & (probes < top)).all(axis=1)
    probes, owner = probes[inside], owner[inside]
    order, sorted_keys = tree.sorted_leaf_keys()
    found = np.full(len(probes), -1, np.int64)
    for lvl in np.unique(tree.level).tolist():
        cell = np.floor(probes / (1 << (tree.fine_level - lvl))).astype(np.int64)
        q = node_keys(np.full(len(cell), lvl), cell)
        pos = np.minimum(search_sorted(sorted_keys, q), max(len(sorted_keys) - 1, 0))
        hit = (found < 0) & (len(sorted_keys) > 0) & (sorted_keys[pos] == q)
        found[hit] = order[pos[hit]]
    pairs = np.unique(np.stack([owner[found >= 0], found[found >= 0]], axis=1), axis=0)
    return pairs[:, 0], pairs[:, 1]


def star(tree: Octree, point: np.ndarray, rel: float = 1e-9) -> np.ndarray:
    """Leaves whose closed box contains ``point`` (1 to 8 of them, sorted)."""
    return containing_leaves(tree, point, rel)[1]


def _relation(box, fine_level, level, corner, regions, rel=1e-9):
    """Whether each box meets, and whether it lies inside, one of ``regions``.

    Boxes are taken closed and slightly widened for meeting (touching
    counts), slightly shrunk for lying inside.

    Returns
    -------
    meets, inside : (N,) bool
    """
    from scipy.spatial import cKDTree

    cell = (box[:, 1] - box[:, 0]) / (1 << fine_level)
    size = 1 << (fine_level - level)
    lo = box[:, 0] + corner * cell
    hi = lo + size * cell
    pad = rel * size * cell
    meets = np.zeros(len(corner), bool)
    inside = np.zeros(len(corner), bool)
    if len(corner) == 0 or len(regions) == 0:
        return meets, inside
    # Only pairs of a box and a region near it can meet: the boxes of the
    # level's lattice within a box of each region, looked up by key; or
    # (regions spanning many boxes) the pairs whose centres are within reach
    # (max norm, per axis), found by a k-d tree.  Either way a superset, not
    # a (boxes x regions) table, then the exact closed-box tests on those
    # pairs alone.
    found = _near_pairs(box, level, corner // size, regions, size * cell)
    if found is not None:
        owner, reg = found
    else:
        reach = (0.5 * size * cell + 0.5 * (regions[:, 1] - regions[:, 0]).max(axis=0) + pad) * (1 + 1e-6)
        reach = np.maximum(reach, 1e-300)
        pairs = cKDTree((lo + hi) / 2 / reach).sparse_distance_matrix(
            cKDTree(regions.mean(axis=1) / reach), 1.0, p=np.inf, output_type="ndarray")
        owner, reg = pairs["i"].astype(np.int64), pairs["j"].astype(np.int64)
    b_lo, b_hi = lo[owner], hi[owner]
    r_lo, r_hi = regions[reg, 0], regions[reg, 1]
    # (The three axes and-ed, not .all(axis=1): a reduction along an axis
    # of 3 costs a call per row.)
    meet = (b_lo - pad <= r_hi) & (b_hi + pad >= r_lo)
    within = (b_lo + pad >= r_lo) & (b_hi - pad <= r_hi)
    meets[owner[meet[:, 0] & meet[:, 1] & meet[:, 2]]] = True
    inside[owner[within[:, 0] & within[:, 1] & within[:, 2]]] = True
    return meets, inside


def _near_pairs(box, level, index, regions, side):
    """(box, region) pairs of the boxes (``index``: cell at ``level``, (N, 3))
    lying within one box of a region (closed); None when the regions cover
    more boxes than are given (the caller's k-d tree is then cheaper).

    Each region's range of lattice cells, widened by one on every side (so
    that rounding of the division cannot lose a box that touches it), is
    enumerated and looked up in the sorted keys of the boxes.
    """
    if not np.isfinite(regions).all() or len(index) == 0:
        return None
    top = (1 << level) - 1
    first = np.maximum(np.floor((regions[:, 0] - box[:, 0]) / side).astype(np.int64) - 1, 0)
    last = np.minimum(np.floor((regions[:, 1] - box[:, 0]) / side).astype(np.int64) + 1, top)
    span = np.maximum(last - first + 1, 0)
    count = span[:, 0] * span[:, 1] * span[:, 2]
    total = int(count.sum())
    if total > 4 * len(index) + 4096:
        return None
    reg = np.repeat(np.arange(len(regions)), count)
    local = np.arange(total) - np.repeat(np.cumsum(count) - count, count)
    dy, dz = span[reg, 1], span[reg, 2]
    cells = first[reg] + np.stack([local // (dy * dz), (local // dz) % dy, local % dz], axis=1)
    m = np.int64(top + 1)
    keys = (index[:, 0] * m + index[:, 1]) * m + index[:, 2]
    order = np.argsort(keys, kind="stable")
    sorted_keys = keys[order]
    if (sorted_keys[1:] == sorted_keys[:-1]).any():
        return None  # (a box given twice: each copy is its own row)
    q = (cells[:, 0] * m + cells[:, 1]) * m + cells[:, 2]
    pos = np.minimum(search_sorted(sorted_keys, q), len(sorted_keys) - 1)
    hit = sorted_keys[pos] == q
    return order[pos[hit]], reg[hit]


def _grow(surface, frontier, box, coarse_level, fine_level, keep_splitting=None, stars=None, refine=None,
          budget=None):
    """Subdivide boxes level by level from ``frontier`` [(level, data, corners), ...].

    Returns the leaves (lists of data, corners, levels, simple flags) and
    the keys of the nodes split, in the form :func:`subdivide` assembles.
    """
    leaves_d, leaves_c, leaves_l, leaves_s, internal = [], [], [], [], []
    start = {lvl: (d, c) for lvl, d, c in frontier}
    offsets = CHILD_OFFSETS  # child c of a split box: Surface.split's order
    data = corner = None
    for level in range(min(start), fine_level + 1):
        if level in start:
            # Children of split boxes come pruned; boxes starting here not yet.
            d, c = start[level]
            keep = ~surface.excludes_zero(d)
            d, c = d[keep], c[keep]
            data = d if data is None else np.concatenate([data, d])
            corner = c if corner is None else np.concatenate([corner, c])
        if data is None:
            continue
        if level >= coarse_level:
            # Boxes meeting a region are not simple whatever the test says:
            # the test (the costly part) runs on the others alone.
            forced = np.zeros(len(corner), bool)
            if keep_splitting is not None and len(keep_splitting):
                forced |= _relation(box, fine_level, level, corner, keep_splitting)[0]
            in_star = np.zeros(len(corner), bool)
            if stars is not None and len(stars):
                meets, in_star = _relation(box, fine_level, level, corner, stars)
                forced |= in_star | meets
            simple = np.zeros(len(corner), bool)
            test = np.nonzero(~forced)[0]
            simple[test] = surface.simple_axis(data[test]) >= 0
            stop = simple | in_star | (level == fine_level)
            if refine is not None and level < fine_level:
                # Simple boxes too large for the sizing (the curvature) go on.
                ask = np.nonzero(stop & ~in_star)[0]
                stop[ask[refine(level, corner[ask])]] = False
            leaves_d.append(data[stop])
            leaves_c.append(corner[stop])
            leaves_l.append(np.full(int(stop.sum()), level, dtype=np.int64))
            leaves_s.append(simple[stop])
            data, corner = data[~stop], corner[~stop]
        if level == fine_level or (len(data) == 0 and not any(k > level for k in start)):
            break
        if budget is not None:
            budget(level, sum(map(len, leaves_l)), len(corner))
        half = 1 << (fine_level - level - 1)
        internal.append(node_keys(np.full(len(corner), level), corner >> (fine_level - level)))
        data, corner = _split_pruned(surface, data, corner, half, offsets)
    return leaves_d, leaves_c, leaves_l, leaves_s, internal


def _split_pruned(surface, data, corner, half, offsets):
    """The children of the boxes that may hold a zero of F, with their corners.

    Split ``SPLIT_CHUNK`` boxes at a time and pruned at once: most children
    of a level are empty, and the whole level's children at once would be
    gigabytes written to be thrown away.
    """
    parts_d, parts_c = [], []
    for i in range(0, len(data), tol.SPLIT_CHUNK):
        d = surface.split(data[i:i + tol.SPLIT_CHUNK])  # (n, 8, ...)
        d = d.reshape((-1,) + d.shape[2:])
        c = (corner[i:i + tol.SPLIT_CHUNK, None, :] + half * offsets[None]).reshape(-1, 3)
        keep = ~surface.excludes_zero(d)
        parts_d.append(d[keep])
        parts_c.append(c[keep])
    if not parts_d:
        return data[:0], corner[:0]
    return np.concatenate(parts_d), np.concatenate(parts_c)


def refine_stars(surface: Surface, tree: Octree, stars: np.ndarray) -> Octree:
    """``tree`` with the leaves meeting the star regions split to the fine level.

    Leaves inside a star and leaves away from all stars stay as they are
    (what :func:`subdivide` would make of them again); only those meeting
    a star's boundary are split, from their own ``data``, so that the star's
    boundary is tiled by fine faces.  Inside leaves are flagged not simple.
    ``surface`` is the one ``tree`` was made for.
    """
    if stars is None or len(stars) == 0:
        return tree
    inside = np.zeros(len(tree.level), bool)
    touch = np.zeros(len(tree.level), bool)
    for lvl in np.unique(tree.level).tolist():
        sel = np.nonzero(tree.level == lvl)[0]
        touch[sel], inside[sel] = _relation(tree.box, tree.fine_level, lvl, tree.corner[sel], stars)
    grow = touch & ~inside & (tree.level < tree.fine_level)
    if not grow.any():
        simple = tree.simple & ~inside
        return Octree(tree.box, tree.fine_level, tree.level, tree.corner, tree.data, simple, tree.internal)
    frontier = [(lvl, tree.data[grow & (tree.level == lvl)], tree.corner[grow & (tree.level == lvl)])
                for lvl in np.unique(tree.level[grow]).tolist()]
    # Split what is grown (its own level is below the coarse level only if
    # the tree was never subdivided there: no such leaves exist).
    new_d, new_c, new_l, new_s, internal = _grow(surface, frontier, tree.box, 0, tree.fine_level, stars=stars)
    stay = ~grow
    return Octree(
        box=tree.box,
        fine_level=tree.fine_level,
        level=np.concatenate([tree.level[stay]] + new_l),
        corner=np.concatenate([tree.corner[stay]] + new_c),
        data=KeptRows(tree.data, stay, new_d),
        simple=np.concatenate([tree.simple[stay] & ~inside[stay]] + new_s),
        internal=np.sort(np.concatenate([tree.internal] + internal)),
    )


class _LazyRows:
    """What the lazy row stores below share: a length and a size in bytes from ``shape`` and ``dtype``."""

    shape: tuple
    dtype: np.dtype

    def __len__(self) -> int:
        return self.shape[0]

    @property
    def nbytes(self) -> int:
        return int(np.prod(self.shape)) * self.dtype.itemsize


class StackedRows(_LazyRows):
    """The ``data`` of a subdivision's leaves: the levels' stacks one after the other.

    Stands for ``np.concatenate(parts)`` without the copy (Barth's sextic:
    11.5 MB of Bernstein tensors in four levels, copied to be read at a few
    hundred rows): an index whose first entry is an integer array or a
    boolean mask over the rows gathers those rows from their parts alone;
    anything else reads the concatenation, made once (``np.asarray``).
    """

    def __init__(self, parts: list):
        self._parts = parts
        lengths = np.array([len(q) for q in parts], np.int64)
        self._ends = np.cumsum(lengths)
        self._starts = self._ends - lengths
        self._whole = None
        self.shape = (int(self._ends[-1]),) + parts[0].shape[1:]
        self.dtype, self.ndim = parts[0].dtype, parts[0].ndim

    def __array__(self, dtype=None, copy=None):
        if self._whole is None:
            self._whole = np.concatenate(self._parts)
        return self._whole if dtype is None else self._whole.astype(dtype, copy=False)

    def __getitem__(self, index):
        first, rest = (index[0], index[1:]) if isinstance(index, tuple) else (index, ())
        if self._whole is None and isinstance(first, (np.ndarray, list)):
            rows = np.asarray(first)
            if rows.dtype == bool and rows.shape == (len(self),):
                rows = np.flatnonzero(rows)
            if rows.dtype.kind in "iu" and rows.ndim == 1:
                rows = np.where(rows < 0, rows + len(self), rows)
                if len(rows) and (rows.min() < 0 or rows.max() >= len(self)):
                    raise IndexError(f"index out of bounds for {len(self)} rows")
                part = np.searchsorted(self._ends, rows, side="right")
                out = np.empty((len(rows),) + self.shape[1:], self.dtype)
                for k in np.unique(part).tolist():
                    at = part == k
                    out[at] = self._parts[k][rows[at] - self._starts[k]]
                # The other entries index the gathered rows as they would the whole.
                return out[(np.arange(len(rows)),) + tuple(rest)] if rest else out
        return np.asarray(self)[index]


class KeptRows(_LazyRows):
    """The ``data`` of a tree made from another: rows kept from the other's and new rows after them.

    Stands for ``np.concatenate([data[keep]] + more)`` without copying the
    kept rows (most of the leaves' data, tens of megabytes on a surface
    with many stars, copied for the few rows the later stages read): an
    index whose first entry is an integer array gathers those rows alone;
    anything else reads the concatenation, made once (``np.asarray``).
    """

    def __init__(self, data: np.ndarray, keep: np.ndarray, more: list):
        self._data, self._rows = data, np.flatnonzero(keep)
        self._more = np.concatenate(more) if more else np.empty((0,) + tuple(data.shape[1:]), data.dtype)
        self._whole = None
        self.shape = (len(self._rows) + len(self._more),) + data.shape[1:]
        self.dtype, self.ndim = data.dtype, data.ndim

    def __array__(self, dtype=None, copy=None):
        if self._whole is None:
            n = len(self._rows)
            out = np.empty(self.shape, self.dtype)
            if isinstance(self._data, np.ndarray):
                np.take(self._data, self._rows, axis=0, out=out[:n])
            else:
                out[:n] = self._data[self._rows]  # (StackedRows: gathered from its parts)
            out[n:] = self._more
            self._whole = out
        return self._whole if dtype is None else self._whole.astype(dtype, copy=False)

    def __getitem__(self, index):
        first, rest = (index[0], index[1:]) if isinstance(index, tuple) else (index, ())
        if self._whole is None and isinstance(first, (np.ndarray, list)):
            rows = np.asarray(first)
            if rows.dtype.kind in "iu" and rows.ndim == 1:
                n = len(self._rows)
                rows = np.where(rows < 0, rows + len(self), rows)
                old = rows < n
                out = np.empty((len(rows),) + self.shape[1:], self.dtype)
                out[old] = self._data[self._rows[rows[old]]]
                out[~old] = self._more[rows[~old] - n]
                # The other entries index the gathered rows as they would the whole.
                return out[(np.arange(len(rows)),) + tuple(rest)] if rest else out
        return np.asarray(self)[index]


def subdivide(surface: Surface, box, coarse_level: int, fine_level: int,
              keep_splitting: np.ndarray | None = None, stars: np.ndarray | None = None,
              refine=None, budget=None) -> Octree:
    """Subdivide ``box`` for the surface F = 0.

    Every box is split down to ``coarse_level``; below it only boxes that
    are not simple are split, down to ``fine_level``.  Empty boxes are
    pruned at every level.

    Parameters
    ----------
    surface : Surface
        F, through its bounds on boxes (``enclose``, ``split``,
        ``excludes_zero``, ``simple_axis``).
    box : (3, 2) array_like
    coarse_level, fine_level : int
        ``0 <= coarse_level <= fine_level``.
    keep_splitting : (k, 2, 3) ndarray, optional
        Regions (lo, hi corners in space) whose boxes are split down to the
        fine level whatever the test says: the cubes around singular
        points, which are then tiled exactly by leaves of the finest size.
    stars : (k, 2, 3) ndarray, optional
        Lattice-aligned regions meshed as one box each (the stars of
        singular points): a box inside one is a leaf at once (not simple,
        never split), boxes meeting one are split to the fine level, so
        that its boundary is tiled by fine faces and nothing is spent on
        its inside.
    refine : callable, optional
        ``refine(level, corners) -> (K,) bool``: boxes of ``level`` (lattice
        corners (K, 3)) that the simplicity test would stop but that are
        split further (too large for the sizing:
        :class:`singmesh.boxes.sizing.CurvatureSizing`).
    budget : callable, optional
        ``budget(level, leaves, frontier)``, called before each level is
        split with the numbers of leaves made and of boxes about to be
        split; it raises to stop a subdivision heading over the memory
        limit (:class:`singmesh.memory.Budget`).

    Returns
    -------
    Octree
    """
    box = np.asarray(box, dtype=float)
    root = surface.enclose(box)
    frontier = [(0, root, np.zeros((1, 3), dtype=np.int64))]
    leaves_d, leaves_c, leaves_l, leaves_s, internal = _grow(
        surface, frontier, box, coarse_level, fine_level, keep_splitting, stars, refine, budget)
    cat = lambda parts, empty: np.concatenate(parts) if parts else empty  # noqa: E731
    return Octree(
        box=box,
        fine_level=fine_level,
        level=cat(leaves_l, np.zeros(0, np.int64)),
        corner=cat(leaves_c, np.zeros((0, 3), np.int64)),
        data=StackedRows(leaves_d) if len(leaves_d) > 1 else cat(leaves_d, root[:0]),
        simple=cat(leaves_s, np.zeros(0, bool)),
        internal=np.sort(cat(internal, np.zeros(0, np.int64))),
    )
