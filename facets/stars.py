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
from singmesh.boxes.octree import Octree, containing_leaves


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
    star_cycles = np.nonzero(np.isin(cycles.box, np.fromiter(stars, np.int64, len(stars))))[0]
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
    if not stars:
        return []
    # The cycles of the star boxes alone, counted by binary search in the
    # sorted boxes (not a dict of every box's count: ~10^4 boxes, 50 stars).
    ids = np.fromiter(stars, np.int64, len(stars))
    box = np.sort(np.asarray(cycles.box, np.int64)) if len(cycles) else np.zeros(0, np.int64)
    found = np.searchsorted(box, ids, side="right") - np.searchsorted(box, ids, side="left")
    return [i for (b, i), c in zip(stars.items(), found.tolist()) if expected[i] is not None and c < expected[i]]
