"""Stars: the lattice cube around each singular point whose leaves are meshed as one.

Inside a star the surface is the cone from the singular point over the
link cycles on the cube's boundary (:mod:`singmesh.facets.fans` fans it).
The cube must hold the leaves near the point that failed the simplicity
test, so that every leaf outside it is a union of discs.  All points are
handled at once: leaf look-ups, region bounds and overlaps are array
operations, so hundreds of nodes cost no more than a few.
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.spatial import cKDTree
from scipy.sparse.csgraph import connected_components

from singmesh import tolerances as tol
from singmesh import topology
from singmesh.boxes.octree import Octree, containing_leaves

from .cycles import Cycles


def star_cubes(tree: Octree, links, points: np.ndarray, curve_points: np.ndarray | None = None) -> np.ndarray:
    """A lattice cube around each singular point: its star.

    The cube holds the connected set (across shared faces) of leaves that
    failed the simplicity test grown from the leaves around p, up to
    ``STAR_REACH`` of the domain and half-way to the nearest other point.  Cubes
    that still overlap (points a few cells apart) shrink to one fine cell
    around their points.

    Parameters
    ----------
    tree : Octree
    links : FaceLinks or LeafSides (its ``minus``/``plus`` leaves give the adjacency;
        only that among the leaves that failed the simplicity test is used)
    points : (k, 3) ndarray
    curve_points : (c, 3) ndarray, optional
        Points of the curves of singular points: a cube reaches at most
        half-way to them too (the cone over its boundary is the surface
        only without a curve in it; their tube takes the leaves round them).

    Returns
    -------
    (k, 2, 3) ndarray of (lo, hi) corners in space
    """
    points = np.asarray(points, float).reshape(-1, 3)
    k = len(points)
    n = len(tree.level)
    both = (links.minus >= 0) & (links.plus >= 0)
    a, b = links.minus[both], links.plus[both]
    grow = ~tree.simple[a] & ~tree.simple[b]
    adj = coo_matrix((np.ones(grow.sum()), (a[grow], b[grow])), shape=(n, n))
    n_labels, label = connected_components(adj, directed=False)
    big = np.iinfo(np.int64).max // 4
    lab_lo = np.full((n_labels, 3), big)
    lab_hi = np.full((n_labels, 3), -big)
    np.minimum.at(lab_lo, label, tree.corner)
    np.maximum.at(lab_hi, label, tree.corner + tree.size[:, None])
    owner, seed = containing_leaves(tree, points)
    lo = np.full((k, 3), big)
    hi = np.full((k, 3), -big)
    np.minimum.at(lo, owner, lab_lo[label[seed]])
    np.maximum.at(hi, owner, lab_hi[label[seed]])
    p = (points - tree.box[:, 0]) / tree.cell
    top = 1 << tree.fine_level
    radius = np.ones(k)
    has = np.bincount(owner, minlength=k) > 0
    radius[has] = np.clip(np.maximum(np.max(p - lo, axis=1), np.max(hi - p, axis=1))[has], 1.0, tol.STAR_REACH * top)
    if k > 1:
        # Room between neighbours: a cube reaches at most half-way to the
        # nearest other point (the non-simple regions of nearby nodes join
        # up, and would otherwise make every cube meet its neighbours').
        gap, _ = cKDTree(p).query(p, k=2, p=np.inf)
        radius = np.minimum(radius, np.maximum(1.0, (gap[:, 1] - 2.0) / 2.0))
    if curve_points is not None and len(curve_points) and k:
        # (fuzz s1-674: the double curve of a plane and a cone 0.36 from
        # its node ran 8 cells from it, through the star cube.)
        gap, _ = cKDTree((np.asarray(curve_points, float) - tree.box[:, 0]) / tree.cell).query(p, p=np.inf)
        radius = np.minimum(radius, np.maximum(1.0, (gap - 2.0) / 2.0))
    cubes = np.stack([np.clip(np.floor(p - radius[:, None]), 0, top),
                      np.clip(np.ceil(p + radius[:, None]), 0, top)], axis=1).astype(np.int64)
    small = np.stack([np.floor(p - 1), np.ceil(p + 1)], axis=1).astype(np.int64)
    shrunk = np.zeros(k, bool)
    for _ in range(k + 1):
        meet = _overlap(cubes)
        grow_out = meet.any(axis=1) & ~shrunk
        if not grow_out.any():
            break
        cubes[grow_out] = small[grow_out]
        shrunk |= grow_out
    return tree.box[:, 0] + cubes * tree.cell


def shrink_cubes(tree: Octree, cubes: np.ndarray, points: np.ndarray, which: list[int]) -> np.ndarray:
    """``cubes`` with those of ``which`` halved about their points (at least one cell)."""
    cubes = np.array(cubes, dtype=float)
    which = np.asarray(which, dtype=np.int64)
    p = (points[which] - tree.box[:, 0]) / tree.cell
    lo = (cubes[which, 0] - tree.box[:, 0]) / tree.cell
    hi = (cubes[which, 1] - tree.box[:, 0]) / tree.cell
    radius = np.maximum(np.maximum(np.max(p - lo, axis=1), np.max(hi - p, axis=1)) / 2, 1.0)[:, None]
    top = 1 << tree.fine_level
    cubes[which, 0] = tree.box[:, 0] + np.clip(np.floor(p - radius), 0, top) * tree.cell
    cubes[which, 1] = tree.box[:, 0] + np.clip(np.ceil(p + radius), 0, top) * tree.cell
    return cubes


def _overlap(cubes: np.ndarray) -> np.ndarray:
    """(k, k) whether the open lattice cubes i and j meet (i != j)."""
    lo, hi = cubes[:, 0], cubes[:, 1]
    meet = ((lo[:, None, :] < hi[None, :, :]) & (lo[None, :, :] < hi[:, None, :])).all(axis=2)
    np.fill_diagonal(meet, False)
    return meet


def group_stars(tree: Octree, cubes: np.ndarray, points: np.ndarray):
    """Group the leaves of each star cube into one box.

    Returns
    -------
    group : (N,) int64    box id of every leaf (N + i for the star of point i)
    stars : dict          box id -> index of the singular point
    clashes : list of int points left without a star (their cube meets another's)
    """
    n = len(tree.level)
    group = np.arange(n, dtype=np.int64)
    stars: dict[int, int] = {}
    clashes: list[int] = []
    if cubes is None or len(cubes) == 0:
        return group, stars, clashes
    lattice = np.rint((np.asarray(cubes) - tree.box[:, 0]) / tree.cell).astype(np.int64)
    leaf_lo = tree.corner
    leaf_hi = tree.corner + tree.size[:, None]
    by_x = np.argsort(leaf_lo[:, 0], kind="stable")
    xs = leaf_lo[by_x, 0]
    owner, _ = containing_leaves(tree, points)
    has_surface = np.bincount(owner, minlength=len(cubes)) > 0
    for i, (lo, hi) in enumerate(lattice):
        cand = by_x[np.searchsorted(xs, lo[0]):np.searchsorted(xs, hi[0])]
        ok = (leaf_lo[cand] >= lo) & (leaf_hi[cand] <= hi)  # (the axes and-ed: no reduction per row)
        inside = cand[ok[:, 0] & ok[:, 1] & ok[:, 2]]
        if len(inside) == 0 or not has_surface[i]:
            continue  # no surface around it: an isolated real point
        if (group[inside] >= n).any():
            clashes.append(i)
            continue
        group[inside] = n + i
        stars[n + i] = i
    return group, stars, clashes


def stray_cycles(cycles, events, stars: dict, expected: list) -> np.ndarray:
    """Cycles on a star's boundary that are not links of its point.

    The classifier knows how many branches meet at the point
    (``expected[i]`` for point i, None if unknown); a star cube can also cut
    off a small piece of surface that does not pass through the point (the
    thin sheet of an E8 or A5 grazing a corner of the cube).  Beyond the
    expected number, the smallest cycles are such pieces: they bound discs
    and are meshed as plain facets, not fanned into the point.
    """
    stray = np.zeros(len(cycles), bool)
    star_cycles = np.nonzero(np.isin(cycles.box, list(stars)))[0]
    for box in np.unique(cycles.box[star_cycles]).tolist():
        want = expected[stars[box]]
        mine = star_cycles[cycles.box[star_cycles] == box]
        if want is None or len(mine) <= want:
            continue
        extent = [np.ptp(events.point[cycles.events[cycles.offsets[c]:cycles.offsets[c + 1]]], axis=0).max()
                  for c in mine]
        order = np.argsort(extent, kind="stable")[::-1]
        stray[mine[order[want:]]] = True
    return stray


def short_stars(cycles, stars: dict, expected: list) -> list[int]:
    """Points whose star has fewer link cycles than the branches they have.

    Parameters
    ----------
    cycles : Cycles
        The link cycles of all boxes (a star is one box).
    stars : dict
        Box id of each star -> index of its singular point.
    expected : list
        Branches of each point by its classification (None if unknown).

    Returns
    -------
    list of int
        The points whose star cube is too large for the cone over its
        boundary (it joins branches): they shrink and are meshed again.
    """
    counts = dict(zip(*np.unique(cycles.box, return_counts=True))) if len(cycles) else {}
    return [i for box, i in stars.items() if expected[i] is not None and counts.get(box, 0) < expected[i]]


def part_branches(cycles, events, links, tree, stars: dict, points: list):
    """The cycles with those of a two-branch point just inside a face of the box parted by branch.

    The two branches of a node (or of an A_k with two sheets) lie on the
    two sides of the plane through p across its axis: they meet only at p.
    When p is less than a fine cell or two inside a face of the box, the
    branches' traces on that face pass less than a square apart (a
    hyperbola with its vertices within a cell of p), and the links there
    may join the trace of one branch to the other's: one star cycle
    through both branches, one fan instead of two.  Such a cycle is parted
    at the links where it goes from one side to the other (those must lie
    on the box's face): the events of each side, in cycle order, are a
    cycle of their own, closed along the face by a link from one side's
    run to its next.  A point within STAR_ON_BOX of the face is on it
    (:func:`singmesh.facets.polygons.apex_pieces` cuts its cycles there).

    Parameters
    ----------
    cycles : Cycles
    events : Events
    links : FaceLinks
    tree : Octree
    stars : dict
        Box id of each star -> index of its singular point in ``points``.
    points : list of SingularPoint

    Returns
    -------
    Cycles
        ``cycles`` itself when none is parted, else a copy with each parted
        cycle replaced by its parts (in place, in cycle order).
    """
    from .polygons import _square_bounds_many  # (polygons imports this module)

    box = tree.box
    size = float(np.max(box[:, 1] - box[:, 0]))
    cell = float(np.max(tree.cell))
    axes = {}
    for b, i in stars.items():
        kind = points[i].classification
        p = points[i].point
        if getattr(kind, "branches", None) != 2 or getattr(kind, "axis", None) is None:
            continue
        gap = np.minimum(p - box[:, 0], box[:, 1] - p).min()
        if topology.on_box_boundary(p[None], box, tol.STAR_ON_BOX)[0] or gap > tol.BRANCHES_NEAR_FACE * cell:
            continue
        axes[b] = (p, np.asarray(kind.axis, float))
    if not axes:
        return cycles
    parts = []
    changed = False
    for c in range(len(cycles)):
        span = slice(cycles.offsets[c], cycles.offsets[c + 1])
        ev, sq = cycles.events[span], cycles.squares[span]
        b = int(cycles.box[c])
        if b not in axes or len(ev) < 6:
            parts.append((b, ev, sq))
            continue
        p, axis = axes[b]
        side = (events.point[ev] - p) @ axis > 0
        cross = np.flatnonzero(side != np.roll(side, -1))  # link j leaves event j
        if len(cross) == 0:
            parts.append((b, ev, sq))
            continue
        # The links that cross must lie on a face of the box (a cycle
        # crossing elsewhere is no cone's there: left alone).
        n, lo, _ = _square_bounds_many(tree, links.square[sq[cross]])
        plane = lo[np.arange(len(cross)), n]
        on_face = (np.abs(plane - box[n, 0]) <= tol.STAR_ON_BOX * size) \
            | (np.abs(plane - box[n, 1]) <= tol.STAR_ON_BOX * size)
        if not on_face.all() or min(side.sum(), (~side).sum()) < 3:
            parts.append((b, ev, sq))
            continue
        # Each side from the event after a crossing on, in cycle order.
        start = (cross[0] + 1) % len(ev)
        order = np.roll(np.arange(len(ev)), -start)
        pos = [np.flatnonzero(side[order] == s) for s in (side[start], not side[start])]
        split = [order[k] for k in pos]
        # The new links (the last event of each run of a side to the first
        # of its next run, and the last to the first) must lie on one face
        # of the box, as the links they replace do (near an edge of the
        # box they may not: left alone).
        ends = []
        for k in pos:
            gap = np.flatnonzero(np.diff(k) != 1)
            ends.append(np.stack([np.append(k[gap], k[-1]), np.append(k[gap + 1], k[0])]))
        ends = order[np.concatenate(ends, axis=1)]
        q = events.point[ev[ends]]
        faces = (np.abs(q[..., None] - box[None, None]) <= tol.STAR_ON_BOX * size).reshape(2, -1, 6)
        if not (faces[0] & faces[1]).any(axis=1).all():
            parts.append((b, ev, sq))
            continue
        parts += [(b, ev[idx], sq[idx]) for idx in split]
        changed = True
    if not changed:
        return cycles
    sizes = [len(e) for _, e, _ in parts]
    return Cycles(box=np.array([b for b, _, _ in parts], np.int64),
                  offsets=np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64),
                  events=np.concatenate([e for _, e, _ in parts]).astype(np.int64),
                  squares=np.concatenate([q for _, _, q in parts]).astype(np.int64),
                  broken_boxes=cycles.broken_boxes)
