"""The facet polygons of all boxes: one per link cycle, sectors in stars, strips in tubes.

A plain box's link cycle is one polygon of event keys; the star of a
singular point gives sectors fanning into it (:mod:`singmesh.facets.fans`),
its skeleton links traced for all star cycles at once; the tube along
singular curves gives strips (:mod:`singmesh.facets.tubes`).  The polygons
go to :func:`singmesh.facets.assemble.assemble` as flat arrays (offsets,
keys, points, apex flags).
"""

from __future__ import annotations

import numpy as np

from singmesh import tolerances as tol
from singmesh import topology
from singmesh.sorting import in_sorted
from singmesh.skeleton.curves import skeleton_links_many
from singmesh.skeleton.directions import skeleton_directions

from .fans import insert_link_nodes, sector_polygons_many
from .stars import face_slivers, stray_cycles
from .tubes import tube_triangles


def point_key(i):
    """Vertex key of singular point i (an int or an array of them): below all event keys (which are >= 0)."""
    return -1 - i


def curve_key0(events) -> int:
    """First vertex key of the curve vertices: above every event and sector node key.

    Sector nodes and traced points are numbered from the largest event key
    on (:func:`facet_polygons`); 2**40 keys later the curve points begin.
    """
    return (int(events.key.max()) + 1 if len(events.key) else 0) + (1 << 40)


def facet_polygons(surf, tree, events, links, cycles, stars: dict, points: list, tube_id: int = -1, *,
                   expected: list):
    """Facet polygons (offsets, keys, points, apex flags) and branch counts.

    Plain boxes give one polygon per cycle; the star of a singular point
    gives sectors fanning into it (:mod:`singmesh.facets.fans`).

    Parameters
    ----------
    surf : Surface
    tree : Octree
    events : Events
    links : FaceLinks
    cycles : Cycles
        The link cycles of the boxes, stars and the tube each one box.
    stars : dict
        Box id of each star -> index of its singular point in ``points``.
    points : list of SingularPoint
    tube_id : int
        Box id of the tube (its cycles are meshed as strips, not here).
    expected : list
        Each point's branch count to tell its stray cycles by (None where
        unknown, as on a face of the box, where only the branches inside
        the box meet it).

    Returns
    -------
    offsets : (P+1,) int64
        Polygon i is ``keys[offsets[i]:offsets[i+1]]``.
    keys : (S,) int64
        Vertex keys (events, singular points :func:`point_key`, sector nodes).
    pts : (S, 3) float64
        The position of each entry of ``keys``.
    apex : (P,) bool
        Polygons whose first vertex is a singular point (fanned from it).
    branches : dict
        Point index -> number of its star's cycles fanned into it.
    splits : dict
        (square, a, b) -> the nodes [(key, point), ...] put on the star
        sectors' link a -> b (:func:`~singmesh.facets.fans.insert_link_nodes`;
        the tube's strips, made later, read it: :func:`add_strips`).
    """
    sizes = np.diff(cycles.offsets)
    plain = ~np.isin(cycles.box, np.fromiter(stars, np.int64, len(stars)))
    plain |= stray_cycles(cycles, events, stars, expected)
    plain |= face_slivers(surf, cycles, events, tree, stars, points)
    tube = cycles.box == tube_id  # meshed as strips
    plain &= ~tube
    ev = cycles.events
    owner = np.repeat(np.arange(len(cycles)), sizes)
    keep = plain[owner]
    parts_keys = [events.key[ev[keep]]]
    parts_pts = [events.point[ev[keep]]]
    parts_sq = [cycles.squares[keep]]
    parts_sizes = [sizes[plain]]
    apex = [np.zeros(plain.sum(), bool)]
    branches = {}
    splits = {}
    next_key = int(events.key.max()) + 1 if len(events.key) else 0
    star_cycles = np.nonzero(~plain & ~tube)[0].tolist()
    # A point on a face of the box: the star's boundary holds it, and a
    # cycle on the box's faces runs through it or passes it by.  Each piece
    # of such a cycle from the point back to it is its own fan.
    through, star_cycles = apex_pieces(cycles, events, links, tree, stars, points, star_cycles)
    for c, pieces in through:
        i = stars[cycles.box[c]]
        for cyc in pieces:
            parts_keys.append(np.concatenate([[point_key(i)], events.key[cyc]]))
            parts_pts.append(np.concatenate([points[i].point[None], events.point[cyc]]))
            parts_sq.append(np.full(len(cyc) + 1, -1, np.int64))
            parts_sizes.append([len(cyc) + 1])
            apex.append(np.ones(1, bool))
            branches[i] = branches.get(i, 0) + 1
    # The face squares of all star cycles' links at once; the Hessian and
    # the skeleton directions once per point (a node has two cycles).
    spans = [(int(cycles.offsets[c]), int(cycles.offsets[c + 1])) for c in star_cycles]
    sq_axis, sq_lo, sq_hi = _square_bounds_many(
        tree, links.square[np.concatenate([cycles.squares[a:b] for a, b in spans]) if spans else np.zeros(0, np.int64)])
    directions = {}
    # The Hessians of all star points in one call (each with the bits of a
    # call at that point alone).
    at = list(dict.fromkeys(stars[cycles.box[c]] for c in star_cycles))
    hessians = dict(zip(at, surf.hessian_each(np.array([points[i].point for i in at]).reshape(-1, 3))))
    # The skeleton curves of all star cycles are traced in one batch.
    jobs = []
    done = 0
    for c, (a, b) in zip(star_cycles, spans):
        i = stars[cycles.box[c]]
        p = points[i].point
        if i not in directions:
            hess = hessians[i]
            # A tip (F not differentiable there) has no Hessian and no skeleton.
            directions[i] = skeleton_directions(hess) if np.isfinite(hess).all() else np.zeros((0, 3))
        e = done + b - a
        squares = list(zip(sq_axis[done:e].tolist(), sq_lo[done:e], sq_hi[done:e]))
        done = e
        jobs.append((p, events.point[ev[a:b]], squares, directions[i]))
    all_spokes = skeleton_links_many(surf, jobs)
    star_keys, star_pts, star_sizes = [], [], []
    fans = []
    for c, spokes in zip(star_cycles, all_spokes):
        i = stars[cycles.box[c]]
        span = slice(cycles.offsets[c], cycles.offsets[c + 1])
        cyc = ev[span]
        fans.append((point_key(i), points[i].point, events.key[cyc], events.point[cyc], spokes, cycles.squares[span]))
        branches[i] = branches.get(i, 0) + 1
    # The sectors of all star cycles at once (the keys of each after the previous one's).
    all_polys, all_splits, next_key = sector_polygons_many(fans, next_key)
    for polys, split in zip(all_polys, all_splits):
        splits.update(split)
        star_keys.append(polys[0])
        star_pts.append(polys[1])
        star_sizes += polys[2]
    if star_sizes:
        # Large ones fan from their first vertex, p or a traced point.
        parts_keys.append(np.concatenate(star_keys))
        parts_pts.append(np.concatenate(star_pts))
        parts_sq.append(np.full(sum(star_sizes), -1, np.int64))
        parts_sizes.append(star_sizes)
        apex.append(np.ones(len(star_sizes), bool))
    sizes = np.concatenate([np.asarray(s, np.int64) for s in parts_sizes])
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    offsets, keys, pts = insert_link_nodes(offsets, np.concatenate(parts_keys), np.concatenate(parts_pts),
                                           np.concatenate(parts_sq), splits)
    offsets, keys, pts = split_lattice_edges(offsets, keys, pts, events, tree.fine_level)
    return offsets, keys, pts, np.concatenate([np.asarray(a, bool) for a in apex]), branches, splits


def apex_pieces(cycles, events, links, tree, stars: dict, points: list, star_cycles: list):
    """The star cycles that pass their point on the box's boundary, cut there.

    A singular point on a face of the box lies on its star's boundary.  At
    the star's scale the surface is its tangent cone (as for every star),
    whose cut by that face is a few rays from the point: each run of the
    cycle's links on the face comes in along one ray and leaves along
    another.  The links follow F + eps = 0, which joins the rays near the
    point, through a root event at it (a box edge lying in the cone) or past
    it, as the pairing of each square decides; near the point that pairing
    has no derivative to go by and may join the rays either way (and two
    rays less than a square apart may be joined far from it).  So only the
    parts of the cycle off the face count: each run on the face is cut out,
    and each piece between two runs is a fan from the point.  The events
    inside a run lie on the rays, in line with the point (a fan over them
    has no area), and only the star sees them (beyond the face is no box):
    the pieces keep the events where the runs meet the star's other faces.

    Parameters
    ----------
    cycles : Cycles
    events : Events
    links : FaceLinks
    tree : Octree
    stars : dict
        Box id of each star -> index of its singular point in ``points``.
    points : list of SingularPoint
    star_cycles : list of int
        The cycles of the stars.

    Returns
    -------
    through : list of (cycle, pieces)
        The cut cycles; ``pieces`` lists arrays of event indices in cycle
        order, each fanned from the point (a cycle all on the face near the
        point has none).
    rest : list of int
        The other cycles of ``star_cycles``.
    """
    through, rest = [], []
    box = tree.box
    size = float(np.max(box[:, 1] - box[:, 0]))
    for c in star_cycles:
        p = points[stars[cycles.box[c]]].point
        if not topology.on_box_boundary(p[None], box, tol.STAR_ON_BOX)[0]:
            rest.append(c)
            continue
        span = slice(cycles.offsets[c], cycles.offsets[c + 1])
        ev = cycles.events[span]
        n = len(ev)
        flat = np.abs(events.point[ev] - p) <= tol.STAR_ON_BOX * size
        on_axes = (np.abs(p - box[:, 0]) <= tol.STAR_ON_BOX * size) | (np.abs(p - box[:, 1]) <= tol.STAR_ON_BOX * size)
        if (flat.all(axis=0) & on_axes).any():
            # All of it on a face of the box through the point (a sliver of
            # the surface along the face, crossing a side of the star): a
            # fan over it would lie in the face, with no area off it.
            through.append((c, []))
            continue
        # Link j leaves event j, on its contact square.
        axis, lo, hi = _square_bounds_many(tree, links.square[cycles.squares[span]])
        on_face = np.abs(lo[np.arange(n), axis] - p[axis]) <= tol.STAR_ON_BOX * size
        if not on_face.any():
            rest.append(c)
            continue
        # A piece starts after the last link of a run on the face.
        starts = (np.flatnonzero(on_face & ~np.roll(on_face, -1)) + 1) % n
        # Events between two links on the face are on the rays.
        keep = ~(on_face & np.roll(on_face, 1))
        pieces = []
        for a, b in zip(starts, np.roll(starts, -1)):
            idx = np.arange(a, b if b > a else b + n) % n
            piece = ev[idx[keep[idx]]]
            if len(piece) >= 2:
                pieces.append(piece)
        through.append((c, pieces))
    return through, rest


def _square_bounds_many(tree, squares: np.ndarray):
    """(axis, lo, hi) in space of contact square rows (n, plane, u0, v0, size): (K,), (K, 3), (K, 3)."""
    squares = np.asarray(squares, np.int64).reshape(-1, 5)
    n, plane, u0, v0, size = squares.T
    rows = np.arange(len(n))
    lo = np.zeros((len(n), 3), np.int64)
    lo[rows, n], lo[rows, (n + 1) % 3], lo[rows, (n + 2) % 3] = plane, u0, v0
    hi = lo.copy()
    hi[rows, (n + 1) % 3] += size
    hi[rows, (n + 2) % 3] += size
    return n, tree.lattice_to_space(lo), tree.lattice_to_space(hi)


def add_strips(offsets, keys, pts, apex, grouped, links, events, curves, tube_id: int, key0: int,
               cell: float, box: np.ndarray, surface=None, traced=None, splits: dict | None = None):
    """The polygons with the tube's strips (triangles from rails to the curve) appended.

    ``offsets, keys, pts, apex`` as from :func:`facet_polygons`; the strips
    are :func:`singmesh.facets.tubes.tube_triangles` of the tube's links
    (``grouped``: :func:`singmesh.facets.cycles.box_links` with the tube as
    box ``tube_id``), the curve points keyed from ``key0`` on; ``surface`` as in
    :func:`~singmesh.facets.tubes.tube_triangles`, as is ``traced``.

    ``splits`` (from :func:`facet_polygons`): a rail edge b -> a across a
    star's sector link a -> b that got nodes gets them too (fuzz s2-2: a
    cone's star next to the tube, a triangle's hole at the node).
    """
    tri_keys, tri_pts = tube_triangles(grouped, links, events, curves, tube_id, key0, cell, box, surface, traced)
    n = len(tri_keys)
    s_off = 3 * np.arange(n + 1)
    s_keys, s_pts = tri_keys.ravel(), tri_pts.reshape(-1, 3)
    if splits and n:
        # The triangles have no squares: a rail edge b -> a reads the
        # square of the sector's link a -> b.
        square = {(b, a): q for q, a, b in splits}
        nxt = np.arange(3 * n) + np.tile([1, 1, -2], n)
        sq = np.array([square.get(ab, -1) for ab in zip(s_keys.tolist(), s_keys[nxt].tolist())], np.int64)
        s_off, s_keys, s_pts = insert_link_nodes(s_off, s_keys, s_pts, sq, splits)
    offsets = np.concatenate([offsets, offsets[-1] + s_off[1:]])
    keys = np.concatenate([keys, s_keys])
    pts = np.concatenate([pts, s_pts])
    apex = np.concatenate([apex, np.zeros(n, bool)])
    return offsets, keys, pts, apex


def split_lattice_edges(offsets: np.ndarray, keys: np.ndarray, points: np.ndarray, events, fine_level: int):
    """The polygons with the events inserted at the lattice points between the ends of an edge along a lattice line.

    Where the surface contains a lattice line (a parabolic cylinder
    touching a split plane along it: fuzz s1-314), every lattice point on
    it is a zero of F, an event with the point's key, and a box's links run
    along the line from one of its corners to the next.  Boxes of
    different sizes round the line have edges along it of different
    lengths: the smaller boxes' polygons go through the lattice points
    between the larger one's corners, its polygon does not, and the edges
    on the line have one triangle each (65 open edges).  An edge of a
    polygon from an event at a lattice point to one at another on the same
    lattice line gets the events at the lattice points between them, in
    order: every polygon along the line goes through the same vertices.

    Parameters
    ----------
    offsets, keys, points : the polygons (as from :func:`facet_polygons`)
    events : Events
    fine_level : int   the lattice's level (keys of lattice points: :mod:`singmesh.boxes.edges`)
    """
    m = (1 << fine_level) + 1
    on_lattice = events.key < m ** 3
    if len(keys) == 0 or not on_lattice.any():
        return offsets, keys, points
    lk, first = np.unique(events.key[on_lattice], return_index=True)
    lp = events.point[on_lattice][first]

    def lattice(k):
        return np.stack([k // (m * m), (k // m) % m, k % m], axis=-1)

    n = len(keys)
    sizes = np.diff(offsets)
    nxt = np.arange(n) + 1
    nxt[offsets[1:][sizes > 0] - 1] = offsets[:-1][sizes > 0]
    a, b = keys, keys[nxt]
    # Lattice point keys are below m^3 (events on lines, nodes and traced
    # points above): only those ends are looked up.
    cand = (a < m ** 3) & (b < m ** 3)
    low = np.flatnonzero(cand)
    cand[low] = in_sorted(a[low], lk) & in_sorted(b[low], lk)
    if not cand.any():
        return offsets, keys, points
    ca, cb = lattice(a[cand]), lattice(b[cand])
    along = ((ca == cb).sum(axis=1) == 2) & (np.abs(ca - cb).sum(axis=1) > 1)
    idx = np.nonzero(cand)[0][along]
    if len(idx) == 0:
        return offsets, keys, points
    cl = lattice(lk)
    poly = np.repeat(np.arange(len(offsets) - 1), sizes)
    insert_after = {}
    for i, p, q in zip(idx.tolist(), ca[along], cb[along]):
        axis = int(np.nonzero(p != q)[0][0])
        o = [k for k in range(3) if k != axis]
        t = cl[:, axis]
        between = (cl[:, o[0]] == p[o[0]]) & (cl[:, o[1]] == p[o[1]]) & (t > min(p[axis], q[axis])) \
            & (t < max(p[axis], q[axis]))
        if between.any():
            sel = np.nonzero(between)[0]
            sel = sel[np.argsort(t[sel] if q[axis] > p[axis] else -t[sel])]
            insert_after[i] = sel
    if not insert_after:
        return offsets, keys, points
    out_k, out_p, sizes = [], [], sizes.copy()
    last = 0
    for i in sorted(insert_after):
        out_k += [keys[last:i + 1], lk[insert_after[i]]]
        out_p += [points[last:i + 1], lp[insert_after[i]]]
        sizes[poly[i]] += len(insert_after[i])
        last = i + 1
    out_k.append(keys[last:])
    out_p.append(points[last:])
    return np.concatenate([[0], np.cumsum(sizes)]), np.concatenate(out_k), np.concatenate(out_p)
