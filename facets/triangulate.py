"""Triangulate facet polygons into well-shaped triangles.

A facet is a small polygon of surface points (its vertices lie on the
surface, the polygon is nearly planar).  For up to
``MAX_TEMPLATE_POLYGON`` vertices every triangulation is tried at once on
all polygons of that size, and the one whose smallest angle is largest
wins (triangles facing against the surface normal count as worst).  Larger
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


def triangle_quality(p: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """Smallest angle (radians) of triangles (..., 3, 3); -1 if facing against ``normal``."""
    e0 = p[..., 1, :] - p[..., 0, :]
    e1 = p[..., 2, :] - p[..., 1, :]
    e2 = p[..., 0, :] - p[..., 2, :]

    def angle(a, b):
        na = np.linalg.norm(a, axis=-1)
        nb = np.linalg.norm(b, axis=-1)
        c = np.einsum("...i,...i->...", a, b) / np.maximum(na * nb, 1e-300)
        return np.arccos(np.clip(c, -1.0, 1.0))

    ang = np.minimum(np.minimum(angle(e0, -e2), angle(e1, -e0)), angle(e2, -e1))
    facing = np.einsum("...i,...i->...", np.cross(e0, -e2), normal)
    return np.where(facing > 0, ang, -1.0)


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
    n_vertices = len(points) + sum(len(p) for p in new_points)
    for _ in range(3):
        dup = _duplicated(np.concatenate(faces), n_vertices)
        if len(dup) == 0:
            break
        for slot, poly, quality in templated:
            faces[slot] = _choose_template(poly, quality, forbidden=dup, n_vertices=n_vertices)
    faces = np.concatenate(faces)
    owner = np.concatenate(owner)
    # What is left doubled (two identical 3-gons) is a pillow of zero
    # volume: both copies go.
    keys = _triple_keys(faces, n_vertices)
    _, inv, counts = np.unique(keys, return_inverse=True, return_counts=True)
    keep = counts[inv] == 1
    new_points = np.concatenate(new_points) if new_points else np.zeros((0, 3))
    return faces[keep], new_points, owner[keep]


def _triple_keys(tri: np.ndarray, n_vertices: int) -> np.ndarray:
    """One int64 per unordered vertex triple (exact while n_vertices < 2**21)."""
    t = np.sort(tri, axis=-1).astype(np.int64)
    if n_vertices >= 1 << 21:  # pragma: no cover - meshes of 2M vertices
        t = t % (1 << 21)
    return (t[..., 0] << 42) | (t[..., 1] << 21) | t[..., 2]


def _duplicated(faces: np.ndarray, n_vertices: int) -> np.ndarray:
    keys = _triple_keys(faces, n_vertices)
    uniq, counts = np.unique(keys, return_counts=True)
    return uniq[counts > 1]


def _template_quality(poly: np.ndarray, points: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """Quality (:func:`triangle_quality`) of every triangle of the polygons' vertices: (P, C(n, 3))."""
    combos = _combos(poly.shape[1])
    normal = normals[poly].sum(axis=1)
    return triangle_quality(points[poly[:, combos]], normal[:, None, :])


def _combos(n: int) -> np.ndarray:
    return np.array(list(combinations(range(n), 3)))


def _choose_template(poly: np.ndarray, q: np.ndarray, forbidden: np.ndarray | None = None,
                     n_vertices: int = 0) -> np.ndarray:
    """The triangulation of each polygon whose smallest angle is largest, from the qualities q.

    Triangles in ``forbidden`` (keys of :func:`_triple_keys`) count as worst.
    """
    n = poly.shape[1]
    templates = polygon_triangulations(n)
    combos = _combos(n)
    lookup = {tuple(c): i for i, c in enumerate(combos)}
    tmpl_idx = np.array([[lookup[tuple(sorted(t))] for t in tr] for tr in templates])
    if forbidden is not None and len(forbidden):
        q = np.where(np.isin(_triple_keys(poly[:, combos], n_vertices), forbidden), -2.0, q)
    score = q[:, tmpl_idx].min(axis=2)  # (P, T)
    best = np.argmax(score, axis=1)
    tri_local = templates[best]  # (P, n-2, 3)
    return np.take_along_axis(poly[:, None, :], tri_local.reshape(len(poly), -1)[:, None, :], axis=2) \
        .reshape(-1, 3)
