"""Triangulate facet polygons into well-shaped triangles.

A facet is a small polygon of surface points (its vertices lie on the
surface, the polygon is nearly planar).  For up to
``MAX_TEMPLATE_POLYGON`` vertices every triangulation is tried at once on
all polygons of that size, and the one whose smallest angle is largest
wins (triangles facing against the surface normal count as worst, flat
ones, which :func:`singmesh.facets.assemble.assemble` drops, worse still).  Larger
polygons get a centre vertex, projected onto the surface, and a fan.
"""

from __future__ import annotations

from functools import lru_cache
from itertools import combinations
from typing import Callable

import numpy as np

from singmesh import tolerances as tol


@lru_cache(maxsize=None)
def polygon_triangulations(n: int) -> np.ndarray:
    """All triangulations of a convex n-gon, shape (Catalan(n-2), n-2, 3)."""

    def tri(i: int, j: int):
        if j - i < 2:
            return [[]]
        out = []
        for k in range(i + 1, j):
            for left in tri(i, k):
                for right in tri(k, j):
                    out.append(left + [(i, k, j)] + right)
        return out

    return np.array(tri(0, n - 1), dtype=np.int64).reshape(-1, n - 2, 3)


#: Quality of a triangle facing against the polygon's normal: kept, but
#: worse than any facing with it.
AGAINST_QUALITY = -1.0
#: Quality of a flat triangle (``ZERO_AREA``: the one :func:`assemble`
#: drops): below a triangle facing away, since dropping it leaves a hole
#: (fuzz s4-36: a coarse box's facet along a line in the surface carries its
#: finer neighbours' vertices on that line, every triangulation has a
#: triangle facing away, and the first, chosen on that tie, two flat ones
#: among those vertices: open edges).  Above ``FORBIDDEN_QUALITY``.
FLAT_QUALITY = -1.5
#: Quality of a triangle that :func:`_choose_template` forbids.
FORBIDDEN_QUALITY = -2.0


def triangle_quality(p: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """Smallest angle (radians) of triangles (..., 3, 3); ``AGAINST_QUALITY`` if facing against
    ``normal``, ``FLAT_QUALITY`` if flat (doubled area at most ``ZERO_AREA`` times the longest
    side squared)."""
    return _quality([p[..., 0, a] for a in range(3)], [p[..., 1, a] for a in range(3)],
                    [p[..., 2, a] for a in range(3)], [normal[..., a] for a in range(3)])


def _quality(q0, q1, q2, normal) -> np.ndarray:
    """:func:`triangle_quality` of the triangles with corners q0, q1, q2, each a list of the x, y, z arrays.

    Written out per coordinate (no axis of 3 to reduce or contract, which
    costs a call per triangle row): each length, dot and cross product is
    the same sum in the same order as ``np.linalg.norm``, ``einsum`` and
    ``np.cross`` on rows would make it, so the qualities are the same to the bit.
    """
    e0 = [b - a for a, b in zip(q0, q1)]
    e1 = [b - a for a, b in zip(q1, q2)]
    e2 = [b - a for a, b in zip(q2, q0)]
    # Each side's length once (|-e| is |e| to the bit: the same squares).
    s0, s1, s2 = (e[0] * e[0] + e[1] * e[1] + e[2] * e[2] for e in (e0, e1, e2))
    n0, n1, n2 = np.sqrt(s0), np.sqrt(s1), np.sqrt(s2)

    def angle(a, b, na, nb):
        # The angle between a and -b; einsum's sum over an axis of 3 adds
        # the first and the last term first.
        c = (-(a[0] * b[0]) - a[2] * b[2]) - a[1] * b[1]
        return np.arccos(np.clip(c / np.maximum(na * nb, 1e-300), -1.0, 1.0))

    ang = np.minimum(np.minimum(angle(e0, e2, n0, n2), angle(e1, e0, n1, n0)), angle(e2, e1, n2, n1))
    # (e0 x -e2) . normal
    m2 = [-x for x in e2]
    cross = (e0[1] * m2[2] - e0[2] * m2[1], e0[2] * m2[0] - e0[0] * m2[2], e0[0] * m2[1] - e0[1] * m2[0])
    facing = (cross[0] * normal[0] + cross[2] * normal[2]) + cross[1] * normal[1]
    # Flat as :func:`singmesh.facets.flips.area_and_longest` and
    # ``assemble`` measure it (the same cross product and squared sides).
    area2 = np.sqrt((cross[0] * cross[0] + cross[1] * cross[1]) + cross[2] * cross[2])
    flat = area2 <= tol.ZERO_AREA * np.maximum(np.maximum(s0, s1), s2)
    return np.where(flat, FLAT_QUALITY, np.where(facing > 0, ang, AGAINST_QUALITY))


def triangulate_polygons(
    polygons: list[np.ndarray] | tuple[np.ndarray, np.ndarray],
    points: np.ndarray,
    normals: np.ndarray,
    project: Callable[[np.ndarray], np.ndarray] | None = None,
    fan_from_first: np.ndarray | None = None,
):
    """Triangulate polygons given as vertex-index lists.

    Parameters
    ----------
    polygons : (offsets, indices)
        Polygon i is ``indices[offsets[i]:offsets[i+1]]``, counter-clockwise
        around its normal.  Consecutive repeats must already be removed.
    points : (V, 3) ndarray
    normals : (V, 3) ndarray
        Surface normals at the points (orientation reference).
    project : callable, optional
        Maps points near the surface onto it; used for centre vertices.
    fan_from_first : (P,) bool, optional
        Large polygons to fan from their first vertex instead (a singular
        point, where a centre vertex would not lie on a disc).

    Returns
    -------
    faces : (T, 3) int64
    new_points : (K, 3) ndarray
        Centre vertices added; they are numbered from ``len(points)``.
    face_polygon : (T,) int64
        The polygon each triangle comes from.
    """
    offsets, indices = polygons
    sizes = np.diff(offsets)
    faces, new_points, owner = [], [], []
    templated = []  # (slot in faces, polygons, their indices) for re-choosing
    for n in np.unique(sizes):
        sel = np.nonzero(sizes == n)[0]
        poly = indices[offsets[sel][:, None] + np.arange(n)]
        if n <= tol.MAX_TEMPLATE_POLYGON:
            if n > 3:
                # The triangles' qualities are kept for choosing again.
                quality = _template_quality(poly, points, normals)
                templated.append((len(faces), poly, quality))
                faces.append(_choose_template(poly, quality))
            else:
                faces.append(poly)
            owner.append(np.repeat(sel, n - 2))
            continue
        if fan_from_first is not None and fan_from_first[sel].any():
            f = fan_from_first[sel]
            apex = poly[f]
            k = np.arange(1, n - 1)
            faces.append(np.stack([np.repeat(apex[:, :1], n - 2, 1), apex[:, k], apex[:, k + 1]], -1).reshape(-1, 3))
            owner.append(np.repeat(sel[f], n - 2))
            sel, poly = sel[~f], poly[~f]
            if len(sel) == 0:
                continue
        # Large polygon: fan around a projected centre vertex.
        centre = points[poly].mean(axis=1)
        if project is not None:
            centre = project(centre)
        ids = len(points) + sum(len(p) for p in new_points) + np.arange(len(sel))
        new_points.append(centre)
        nxt = np.roll(poly, -1, axis=1)
        faces.append(np.stack([poly, nxt, np.broadcast_to(ids[:, None], poly.shape)], -1).reshape(-1, 3))
        owner.append(np.repeat(sel, n))
    if not faces:
        return np.zeros((0, 3), np.int64), np.zeros((0, 3)), np.zeros(0, np.int64)
    # Two facets may pick the same triangle with opposite orientations (the
    # two sheets of a thin lens that the perturbation collapsed): forbid
    # such triangles and choose again, for the facets concerned only.
    # Likewise two facets on either side of a face may both cut across it
    # along the same diagonal (the surface pierces the face in two arcs,
    # one piece on each side: a tube, which the shared diagonal pinches):
    # an edge of more than two triangles that is a diagonal of a facet is
    # forbidden to the facets concerned, and they choose again.
    n_vertices = len(points) + sum(len(p) for p in new_points)
    crowded = np.zeros(0, np.int64)
    distinct = False  # whether the triangles are known to be distinct triples
    for _ in range(3):
        every = np.concatenate(faces)
        dup = _duplicated(every, n_vertices)
        fresh = np.setdiff1d(_crowded_edges(every, n_vertices), crowded)
        if len(dup) == 0 and len(fresh) == 0:
            distinct = True
            break
        crowded = np.union1d(crowded, fresh)
        # Only the facets with two corners at such an edge or triangle
        # choose again (edges along a singular curve are crowded by right).
        involved = np.zeros(n_vertices, bool)
        involved[np.concatenate([crowded // max(n_vertices, 1), crowded % max(n_vertices, 1)])] = True
        involved[_triple_vertices(dup)] = True
        for slot, poly, quality in templated:
            again = involved[poly].sum(axis=1) >= 2
            if not again.any():
                continue
            tri = faces[slot].reshape(len(poly), -1, 3).copy()
            tri[again] = _choose_template(poly[again], quality[again], forbidden=dup, n_vertices=n_vertices,
                                          forbidden_edges=crowded).reshape(int(again.sum()), -1, 3)
            faces[slot] = tri.reshape(-1, 3)
    faces = np.concatenate(faces)
    owner = np.concatenate(owner)
    # What is left doubled (two identical 3-gons) is a pillow of zero
    # volume: both copies go.
    if distinct:  # no triple twice (the last check): nothing to drop, no second sort
        keep = np.ones(len(faces), bool)
    else:
        keys = _triple_keys(faces, n_vertices)
        _, inv, counts = np.unique(keys, return_inverse=True, return_counts=True)
        keep = counts[inv] == 1
    new_points = np.concatenate(new_points) if new_points else np.zeros((0, 3))
    return faces[keep], new_points, owner[keep]


def _triple_keys(tri: np.ndarray, n_vertices: int) -> np.ndarray:
    """One int64 per unordered vertex triple (exact while n_vertices < 2**21)."""
    # The three sorted by min, max and the rest (exact on ints): np.sort
    # along an axis of 3 is a call per row.
    tri = np.asarray(tri, np.int64)
    a, b, c = tri[..., 0], tri[..., 1], tri[..., 2]
    lo = np.minimum(np.minimum(a, b), c)
    hi = np.maximum(np.maximum(a, b), c)
    t = np.stack([lo, a + b + c - lo - hi, hi], axis=-1)
    if n_vertices >= 1 << 21:  # pragma: no cover - meshes of 2M vertices
        t = t % (1 << 21)
    return (t[..., 0] << 42) | (t[..., 1] << 21) | t[..., 2]


def _triple_vertices(keys: np.ndarray) -> np.ndarray:
    """The vertex indices of triple keys (:func:`_triple_keys`; exact below 2**21 vertices)."""
    mask = (1 << 21) - 1
    return np.concatenate([(keys >> 42) & mask, (keys >> 21) & mask, keys & mask]).astype(np.int64)


def _duplicated(faces: np.ndarray, n_vertices: int) -> np.ndarray:
    keys = _triple_keys(faces, n_vertices)
    uniq, counts = np.unique(keys, return_counts=True)
    return uniq[counts > 1]


def edge_keys(a: np.ndarray, b: np.ndarray, n_vertices: int) -> np.ndarray:
    """One int64 per unordered vertex pair."""
    # In place on the one fresh array np.minimum makes: each temporary of a
    # mesh's 10^5 half-edges is a megabyte of new pages.
    lo = np.minimum(a, b).astype(np.int64, copy=False)
    lo *= max(int(n_vertices), 1)
    lo += np.maximum(a, b)
    return lo


def _crowded_edges(faces: np.ndarray, n_vertices: int) -> np.ndarray:
    """Keys (:func:`edge_keys`) of the edges of more than two triangles."""
    keys = edge_keys(faces, np.roll(faces, -1, axis=1), n_vertices).ravel()
    uniq, counts = np.unique(keys, return_counts=True)
    return uniq[counts > 2]


def _template_quality(poly: np.ndarray, points: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """Quality (:func:`triangle_quality`) of every triangle of the polygons' vertices: (P, C(n, 3))."""
    combos = _combos(poly.shape[1])
    # The vertices' normals summed in order (what .sum(axis=1) of the
    # (P, n, 3) gather adds, one vertex after the other: the same bits).
    normal = normals[poly[:, 0]] + normals[poly[:, 1]]
    for k in range(2, poly.shape[1]):
        normal += normals[poly[:, k]]
    # Gathered per coordinate, (P, n) then (P, C): a third of the index work
    # of the (P, C, 3, 3) corner table.
    xyz = [np.ascontiguousarray(points[:, a])[poly] for a in range(3)]
    corners = [[c[:, combos[:, k]] for c in xyz] for k in range(3)]
    return _quality(*corners, [normal[:, None, a] for a in range(3)])


@lru_cache(maxsize=None)
def _combos(n: int) -> np.ndarray:
    """All vertex triples (i < j < k) of an n-gon: (C(n, 3), 3)."""
    out = np.array(list(combinations(range(n), 3)))
    out.flags.writeable = False
    return out


@lru_cache(maxsize=None)
def _template_combos(n: int) -> np.ndarray:
    """The triangles of each triangulation of an n-gon as rows of :func:`_combos`: (T, n - 2)."""
    lookup = {tuple(c): i for i, c in enumerate(_combos(n).tolist())}
    out = np.array([[lookup[tuple(sorted(t))] for t in tr] for tr in polygon_triangulations(n).tolist()])
    out.flags.writeable = False
    return out


def _choose_template(poly: np.ndarray, q: np.ndarray, forbidden: np.ndarray | None = None,
                     n_vertices: int = 0, forbidden_edges: np.ndarray | None = None) -> np.ndarray:
    """The triangulation of each polygon whose smallest angle is largest, from the qualities q.

    Triangles in ``forbidden`` (keys of :func:`_triple_keys`), and those
    with a diagonal of the polygon in ``forbidden_edges`` (keys of
    :func:`edge_keys`), count as worst.
    """
    n = poly.shape[1]
    templates = polygon_triangulations(n)
    combos = _combos(n)
    tmpl_idx = _template_combos(n)
    if forbidden is not None and len(forbidden):
        q = np.where(np.isin(_triple_keys(poly[:, combos], n_vertices), forbidden), FORBIDDEN_QUALITY, q)
    if forbidden_edges is not None and len(forbidden_edges):
        # The sides of each triangle that are diagonals of the polygon
        # (its own sides are in every triangulation).
        ends = combos[:, [[0, 1], [1, 2], [0, 2]]]                       # (C, 3, 2) local
        gap = ends[..., 1] - ends[..., 0]
        diagonal = (gap != 1) & (gap != n - 1)                           # (C, 3)
        keys = edge_keys(poly[:, ends[..., 0]], poly[:, ends[..., 1]], n_vertices)   # (P, C, 3)
        bad = (np.isin(keys, forbidden_edges) & diagonal[None]).any(axis=2)
        q = np.where(bad, FORBIDDEN_QUALITY, q)
    # The smallest quality of each template's triangles (P, T): exact, as
    # q[:, tmpl_idx].min(axis=2), without a reduction call per (P, T) row.
    score = q[:, tmpl_idx[:, 0]]
    for k in range(1, tmpl_idx.shape[1]):
        score = np.minimum(score, q[:, tmpl_idx[:, k]])
    best = np.argmax(score, axis=1)
    tri_local = templates[best]  # (P, n-2, 3)
    return np.take_along_axis(poly[:, None, :], tri_local.reshape(len(poly), -1)[:, None, :], axis=2) \
        .reshape(-1, 3)
