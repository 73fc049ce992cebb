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
from scipy import ndimage
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


def face_slivers(surf, cycles, events, tree, stars: dict, points: list) -> np.ndarray:
    """Cycles of a star round a point on the box's boundary that lie flat on a face, cut off from the point.

    A star on a face of the box is as large as the leaves round its point
    that failed the simplicity test (up to STAR_REACH): round a D4 point
    that is many cells, and a sheet near the point's tangent plane can
    graze a face of the box inside the star away from the point, crossing
    it in a small closed curve there.  The star then has a cycle within a
    fraction of a cell of that face, all of it several cells from the
    point: a small disc cut off by the face, not a piece through the point
    (the sphere oracle finds no such piece on smaller spheres round it).
    Fanned into the point it is one fan too many (two for a D4 point on an
    edge of the box with one piece inside it); it is meshed as a plain
    facet instead, as a stray cycle is (:func:`stray_cycles`).  So is a
    cycle of two events there (a bubble across one lattice edge of a side
    of the star: two roots on it, a link each way), which has no area.

    A piece through the point that hugs the face looks the same on the
    star's boundary, but its trace on the face (F = 0 there) runs to the
    point: the trace is sampled at an eighth of a cell on the face round
    the point, and a cycle whose events on the face lie on a component of
    it that reaches within two cells of the point is kept.  A sheet
    through the point lying along the face (less than a cell off it) is
    cut by it into many flat cycles in a row from the point out: those
    chained to one near the point are kept too.

    Returns
    -------
    (C,) bool    the cycles to mesh as plain facets
    """
    out = np.zeros(len(cycles), bool)
    box = tree.box
    cell = float(np.max(tree.cell))
    size = float(np.max(box[:, 1] - box[:, 0]))
    planes = {}
    for b, i in stars.items():
        p = points[i].point
        on = np.abs(p[:, None] - box) <= tol.STAR_ON_BOX * size
        if on.any():
            planes[b] = (p, [(int(a), float(box[a, k])) for a, k in zip(*np.nonzero(on))])
    for b, (p, faces) in planes.items():
        mine = np.flatnonzero(cycles.box == b)
        pts = [events.point[cycles.events[cycles.offsets[c]:cycles.offsets[c + 1]]] for c in mine]
        far = np.array([np.linalg.norm(q - p, axis=1).min() > tol.SLIVER_FAR * cell for q in pts], bool)
        flat = np.array([any(np.abs(q[:, a] - v).max() <= tol.SLIVER_FLAT * cell for a, v in faces) for q in pts], bool)
        # A sheet through the point lying along the face is cut by it into
        # many flat cycles in a row from the point outwards: those chained
        # (events within SLIVER_CHAIN cells) to a flat cycle near the point
        # are kept.
        chain = np.flatnonzero(flat)
        near_p = np.zeros(len(mine), bool)
        if len(chain):
            owner = np.repeat(chain, [len(pts[k]) for k in chain])
            pairs = cKDTree(np.concatenate([pts[k] for k in chain])).query_pairs(tol.SLIVER_CHAIN * cell, output_type="ndarray")
            n = len(mine)
            adj = coo_matrix((np.ones(len(pairs)), (owner[pairs[:, 0]], owner[pairs[:, 1]])), shape=(n, n))
            _, label = connected_components(adj, directed=False)
            anchored = np.unique(label[chain[~far[chain]]])
            near_p[chain] = np.isin(label[chain], anchored)
        bubble = np.array([len(q) == 2 for q in pts], bool)
        for k in np.flatnonzero(far & ~near_p & (flat | bubble)).tolist():
            q = pts[k]
            # A bubble of the surface across one lattice edge of the star's
            # side (two roots on it, a link each way) has no area; a flat
            # cycle whose trace on the face runs to the point is kept.
            out[mine[k]] = len(q) == 2 or not any(
                _trace_reaches(surf, p, a, v, q[np.abs(q[:, a] - v) <= tol.STAR_ON_BOX * size], box, cell)
                for a, v in faces)
    return out


def _trace_reaches(surf, p, a: int, v: float, starts: np.ndarray, box: np.ndarray, cell: float) -> bool:
    """Whether F = 0 on the face x_a = v joins a point of ``starts`` to the point p (see :func:`face_slivers`)."""
    if not len(starts):
        return False
    u, w = [k for k in range(3) if k != a]
    reach = np.abs(starts[:, [u, w]] - p[[u, w]]).max() + cell
    h = cell / tol.SLIVER_SAMPLES
    axes = [np.arange(max(box[k, 0], p[k] - reach), min(box[k, 1], p[k] + reach) + 0.5 * h, h) for k in (u, w)]
    grid = np.zeros((len(axes[0]), len(axes[1]), 3))
    grid[..., a] = v
    grid[..., u], grid[..., w] = np.meshgrid(axes[0], axes[1], indexing="ij")
    pos = surf(grid) > 0
    # Squares of the sampling grid with both signs at their corners: the trace.
    crossed = ~((pos[:-1, :-1] == pos[1:, :-1]) & (pos[:-1, :-1] == pos[:-1, 1:]) & (pos[:-1, :-1] == pos[1:, 1:]))
    label, _ = ndimage.label(crossed, structure=np.ones((3, 3)))
    # The trace next to the point (two cells round it: the arcs of a
    # cusp there are closer than the sampling).
    ci, cj = np.meshgrid(axes[0][:-1] + 0.5 * h, axes[1][:-1] + 0.5 * h, indexing="ij")
    near = np.maximum(np.abs(ci - p[u]), np.abs(cj - p[w])) <= tol.SLIVER_NEAR * cell
    at_p = set(np.unique(label[near & crossed]).tolist()) - {0}
    si, sj = [np.clip(((starts[:, k] - axes[n][0]) // h).astype(np.int64), 0, crossed.shape[n] - 1)
              for n, k in enumerate((u, w))]
    return bool(at_p & set(label[si, sj].tolist()))


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
