"""Octree subdivision of a box with pruning, level by level on stacked arrays.

Boxes are addressed on the integer lattice of the finest level: a box at
``level`` has its lower corner at ``corner`` (lattice units) and side
``2**(fine_level - level)``.  Exact zeros follow one rule everywhere
(simulation of simplicity): F is meshed as if it were F + eps for an
infinitesimal eps > 0.  A box is pruned only when its coefficients are
all clearly positive or all clearly negative (beyond rounding): then F has
no zero in it at all, and no event can lie on its boundary.

A box is *simple* when the surface in it is a union of discs, each bounded
by one cycle of face links.  The test used: some partial derivative F_a is
of one sign on the box (so each line parallel to axis a meets the surface
at most once and the surface is a graph over the faces normal to a), and on
both faces normal to a the face curve has no closed loop (a tangential
derivative of one sign there, or no curve at all).  A hole in the graph's
domain would be bounded by a closed loop of the top or bottom face curve,
because the two face curves cannot cross when F is monotone along a;
excluding such loops leaves discs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from singmesh import tolerances as tol

from .bernstein import bernstein_on_box, derivative, sign_definite, split

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
    tensors : (N, n0+1, n1+1, n2+1) float64
        Bernstein coefficients of F on each leaf.
    simple : (N,) bool
        Whether the leaf passed the simplicity test.
    internal : (M,) int64, sorted
        Keys (:func:`node_keys`) of the nodes that were split.
    """

    box: np.ndarray
    fine_level: int
    level: np.ndarray
    corner: np.ndarray
    tensors: np.ndarray
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

    def find_leaves(self, doubled: np.ndarray) -> np.ndarray:
        """Index of the leaf containing each point, or -1.

        Parameters
        ----------
        doubled : (K, 3) int64
            Twice the lattice coordinates of the query points; a point must
            lie strictly inside one leaf (never on a face), as face centres
            pushed half a cell off the face do.
        """
        keys = self.leaf_keys()
        order = np.argsort(keys)
        sorted_keys = keys[order]
        found = np.full(len(doubled), -1, dtype=np.int64)
        for lvl in np.unique(self.level):
            shift = self.fine_level - int(lvl) + 1
            q = node_keys(np.full(len(doubled), lvl), doubled >> shift)
            pos = np.searchsorted(sorted_keys, q)
            pos = np.minimum(pos, len(sorted_keys) - 1)
            hit = (sorted_keys[pos] == q) & (found < 0)
            found[hit] = order[pos[hit]]
        return found


def star(tree: Octree, point: np.ndarray, rel: float = 1e-9) -> np.ndarray:
    """Leaves whose closed box contains ``point`` (1 to 8 of them, sorted).

    A point on a face, edge or corner shared by several leaves gets all of
    them, so that the point lies strictly inside their union.
    """
    lattice = (np.asarray(point, float) - tree.box[:, 0]) / tree.cell
    offsets = np.array(np.meshgrid([-1, 1], [-1, 1], [-1, 1], indexing="ij")).reshape(3, -1).T
    probes = lattice[None, :] + rel * offsets
    keys = tree.leaf_keys()
    order = np.argsort(keys)
    found = set()
    top = 1 << tree.fine_level
    for q in probes:
        if (q < 0).any() or (q >= top).any():
            continue
        for lvl in np.unique(tree.level):
            cell = np.floor(q / (1 << (tree.fine_level - int(lvl)))).astype(np.int64)
            key = node_keys(np.array(lvl), cell)
            pos = np.searchsorted(keys[order], key)
            if pos < len(keys) and keys[order][pos] == key:
                found.add(int(order[pos]))
                break
    return np.array(sorted(found), dtype=np.int64)


def empty_boxes(tensors: np.ndarray) -> np.ndarray:
    """Boxes where F certainly has no zero: all coefficients > slack, or all < -slack.

    The slack (``PRUNE_SLACK`` of the largest coefficient) keeps boxes where
    F may vanish up to rounding, e.g. exactly at a corner: pruning such a
    box would leave a hole in the faces that carry the events found there.
    """
    flat = tensors.reshape(len(tensors), -1)
    slack = tol.PRUNE_SLACK * np.abs(flat).max(axis=1)
    return (flat.min(axis=1) > slack) | (flat.max(axis=1) < -slack)


def face_without_loops(face: np.ndarray) -> np.ndarray:
    """Whether the curve F + eps = 0 on stacked faces (N, a, b) has no closed loop.

    True when a tangential derivative is of one sign (the curve is a graph)
    or when there is no curve at all.
    """
    return (
        sign_definite(np.diff(face, axis=1), (1, 2))
        | sign_definite(np.diff(face, axis=2), (1, 2))
        | (face.min(axis=(1, 2)) >= 0)
        | (face.max(axis=(1, 2)) < 0)
    )


def monotone_axis(tensors: np.ndarray) -> np.ndarray:
    """First axis a for which the box passes the simplicity test, else -1."""
    result = np.full(len(tensors), -1, dtype=np.int64)
    for a in range(2, -1, -1):
        mono = sign_definite(derivative(tensors, a), (1, 2, 3))
        lo = np.take(tensors, 0, axis=1 + a)
        hi = np.take(tensors, -1, axis=1 + a)
        ok = mono & face_without_loops(lo) & face_without_loops(hi)
        result[ok] = a
    return result


def _meets_any(box, fine_level, level, corner, regions, rel=1e-9):
    """Whether each box (closed, slightly widened) meets one of ``regions``."""
    cell = (box[:, 1] - box[:, 0]) / (1 << fine_level)
    size = 1 << (fine_level - level)
    lo = box[:, 0] + corner * cell
    hi = lo + size * cell
    pad = rel * size * cell
    meets = ((lo - pad)[:, None, :] <= regions[None, :, 1, :]) & ((hi + pad)[:, None, :] >= regions[None, :, 0, :])
    return meets.all(axis=2).any(axis=1)


def subdivide(coeffs: np.ndarray, box, coarse_level: int, fine_level: int,
              keep_splitting: np.ndarray | None = None) -> Octree:
    """Subdivide ``box`` for the polynomial with monomial tensor ``coeffs``.

    Every box is split down to ``coarse_level``; below it only boxes that
    are not simple are split, down to ``fine_level``.  Empty boxes are
    pruned at every level.

    Parameters
    ----------
    coeffs : (n0+1, n1+1, n2+1) ndarray
    box : (3, 2) array_like
    coarse_level, fine_level : int
        ``0 <= coarse_level <= fine_level``.
    keep_splitting : (k, 2, 3) ndarray, optional
        Regions (lo, hi corners in space) whose boxes are split down to the
        fine level whatever the test says: the cubes around singular
        points, which are then tiled exactly by leaves of the finest size.

    Returns
    -------
    Octree
    """
    box = np.asarray(box, dtype=float)
    tensors = bernstein_on_box(coeffs, box)[None]
    corner = np.zeros((1, 3), dtype=np.int64)
    leaves_t, leaves_c, leaves_l, leaves_s = [], [], [], []
    internal = []
    for level in range(fine_level + 1):
        keep = ~empty_boxes(tensors)
        tensors, corner = tensors[keep], corner[keep]
        if level >= coarse_level:
            simple = monotone_axis(tensors) >= 0
            if keep_splitting is not None and len(keep_splitting):
                simple &= ~_meets_any(box, fine_level, level, corner, keep_splitting)
            stop = simple | (level == fine_level)
            leaves_t.append(tensors[stop])
            leaves_c.append(corner[stop])
            leaves_l.append(np.full(int(stop.sum()), level, dtype=np.int64))
            leaves_s.append(simple[stop])
            tensors, corner = tensors[~stop], corner[~stop]
        if level == fine_level or len(tensors) == 0:
            break
        half = 1 << (fine_level - level - 1)
        internal.append(node_keys(np.full(len(corner), level), corner >> (fine_level - level)))
        children = split(tensors)
        tensors = children.reshape((-1,) + tensors.shape[1:])
        offsets = np.array(np.meshgrid([0, 1], [0, 1], [0, 1], indexing="ij")).reshape(3, -1).T
        corner = (corner[:, None, :] + half * offsets[None]).reshape(-1, 3)
    shape = (0,) + tuple(s for s in coeffs.shape)
    cat = lambda parts, empty: np.concatenate(parts) if parts else empty  # noqa: E731
    return Octree(
        box=box,
        fine_level=fine_level,
        level=cat(leaves_l, np.zeros(0, np.int64)),
        corner=cat(leaves_c, np.zeros((0, 3), np.int64)),
        tensors=cat(leaves_t, np.zeros(shape)),
        simple=cat(leaves_s, np.zeros(0, bool)),
        internal=np.sort(cat(internal, np.zeros(0, np.int64))),
    )
