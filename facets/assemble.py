"""Assemble the facets of all boxes into one indexed triangle mesh.

Vertices are merged by identity (the event keys of :mod:`singmesh.boxes.edges`:
a lattice point, or one root on one lattice line), never by rounding
coordinates.  Several events can share a key (both sides of a root at a
lattice point); consecutive repeats in a facet are dropped, and a facet
that repeats a vertex further apart is cut there into two.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from singmesh import tolerances as tol
from singmesh.sorting import unique_inverse

from .flips import area_and_longest, flip_slivers
from .triangulate import triangulate_polygons


def clean_polygons(offsets: np.ndarray, ids: np.ndarray):
    """Drop consecutive repeats (cyclically), split pinched polygons, drop < 3.

    Returns
    -------
    offsets, ids : the cleaned polygons in the same (offsets, flat) form
    source : (P,) int64  the input polygon each output polygon came from
    """
    n_poly = len(offsets) - 1
    poly_of = np.repeat(np.arange(n_poly), np.diff(offsets))
    nxt = np.arange(len(ids)) + 1
    last = offsets[1:] - 1
    nxt[last] = offsets[:-1]
    keep = ids != ids[nxt]
    # A polygon whose ids are all equal keeps nothing.
    ids, poly_of = ids[keep], poly_of[keep]
    counts = np.bincount(poly_of, minlength=n_poly)
    new_offsets = np.concatenate([[0], np.cumsum(counts)])
    # Pinched polygons (a vertex twice, not consecutively): rare, cut in
    # Python; all others pass through as arrays.
    # One int64 per (polygon, id), sorted: equal neighbours are repeats
    # (a plain sort, not a lexsort of two keys).
    width = np.int64(ids.max()) + 1 if len(ids) else np.int64(1)
    packed = np.sort(poly_of.astype(np.int64) * width + ids)
    pinched = np.zeros(n_poly, bool)
    pinched[packed[1:][np.diff(packed) == 0] // width] = True
    plain = ~pinched & (counts >= 3)
    keep_entry = plain[poly_of]
    sizes = [counts[plain]]
    flat = [ids[keep_entry]]
    src = [np.nonzero(plain)[0]]
    for p in np.nonzero(pinched)[0].tolist():
        for piece in _cut_pinched(list(ids[new_offsets[p]:new_offsets[p + 1]])):
            if len(piece) >= 3:
                sizes.append([len(piece)])
                flat.append(np.asarray(piece, np.int64))
                src.append([p])
    sizes = np.concatenate([np.asarray(x, np.int64) for x in sizes])
    if sizes.sum() == 0:
        return np.zeros(1, np.int64), np.zeros(0, np.int64), np.zeros(0, np.int64)
    return (np.concatenate([[0], np.cumsum(sizes)]), np.concatenate(flat),
            np.concatenate([np.asarray(x, np.int64) for x in src]))


def stitch_collinear(offsets: np.ndarray, ids: np.ndarray, src: np.ndarray, vertices: np.ndarray):
    """Remove polygons whose vertices lie on one line, mending their neighbours.

    Such a polygon is a sliver of F + eps of infinitesimal width along a
    line that lies in the surface (a lattice line in a plane or a ruled
    surface, on a box centred on it).  Its two sides are two chains between
    the same end points, one with the lattice points of finer neighbours
    on it, one without: the polygons across those links see different
    vertices on one segment.  The sliver goes, and every other polygon
    edge joining two of its vertices with others of them in between gets
    those in between (no T-junction, no zero-area triangle).

    Returns
    -------
    offsets, ids, src : as from :func:`clean_polygons`
    """
    n_poly = len(offsets) - 1
    if n_poly == 0:
        return offsets, ids, src
    poly_of = np.repeat(np.arange(n_poly), np.diff(offsets))
    # Per coordinate (x, y, z arrays), with the sums of np.sum and
    # np.linalg.norm over an axis of 3 in their order: the same bits
    # without a reduction call per row.
    pc = [np.ascontiguousarray(vertices[:, a])[ids] for a in range(3)]
    rel = [c - c[offsets[:-1]][poly_of] for c in pc]  # from each polygon's first vertex
    d2 = (rel[0] ** 2 + rel[1] ** 2) + rel[2] ** 2
    # The vertex farthest from the first one: the line's other end (of
    # equally far ones the last, NaN counting as farthest, as a sort would
    # put it).
    far = _last_max(d2, offsets, poly_of)
    ax = [r[far] for r in rel]  # per polygon
    length = np.sqrt((ax[0] ** 2 + ax[1] ** 2) + ax[2] ** 2)
    ax = [a[poly_of] for a in ax]
    c = (rel[1] * ax[2] - rel[2] * ax[1], rel[2] * ax[0] - rel[0] * ax[2], rel[0] * ax[1] - rel[1] * ax[0])
    off = np.sqrt((c[0] ** 2 + c[1] ** 2) + c[2] ** 2) / np.maximum(length[poly_of], 1e-300)
    worst = np.zeros(n_poly)
    np.maximum.at(worst, poly_of, off)
    flat = (worst <= tol.ZERO_AREA * length) & (np.diff(offsets) >= 3)
    if not flat.any():
        return offsets, ids, src
    p = vertices[ids]
    first = p[offsets[:-1]][poly_of]
    axis = np.stack(ax, axis=1)
    between: dict = {}
    for k in np.nonzero(flat)[0].tolist():
        chain_ids = ids[offsets[k]:offsets[k + 1]]
        t = (p[offsets[k]:offsets[k + 1]] - first[offsets[k]]) @ axis[offsets[k]]
        chain = [int(v) for v in chain_ids[np.argsort(t, kind="stable")]]
        for i in range(len(chain)):
            for j in range(i + 2, len(chain)):
                between[(chain[i], chain[j])] = chain[i + 1:j]
                between[(chain[j], chain[i])] = chain[i + 1:j][::-1]
    # Only polygons with an edge to mend go through Python.
    nxt = np.arange(len(ids)) + 1
    nxt[offsets[1:] - 1] = offsets[:-1]
    nv = np.int64(len(vertices))
    edge_keys = ids.astype(np.int64) * nv + ids[nxt]
    wanted = np.array([u * nv + v for u, v in between], np.int64)
    touched = np.zeros(n_poly, bool)
    touched[poly_of[np.isin(edge_keys, wanted)]] = True
    keep = ~flat & ~touched
    sizes = [np.diff(offsets)[keep]]
    flat_ids = [ids[keep[poly_of]]]
    srcs = [src[keep]]
    for k in np.nonzero(touched & ~flat)[0].tolist():
        cyc = [int(v) for v in ids[offsets[k]:offsets[k + 1]]]
        out = []
        for i, v in enumerate(cyc):
            out.append(v)
            out += between.get((v, cyc[(i + 1) % len(cyc)]), [])
        sizes.append([len(out)])
        flat_ids.append(np.asarray(out, np.int64))
        srcs.append([src[k]])
    sizes = np.concatenate([np.asarray(x, np.int64) for x in sizes])
    return (np.concatenate([[0], np.cumsum(sizes)]), np.concatenate(flat_ids),
            np.concatenate([np.asarray(x, np.int64) for x in srcs]))


def _last_max(values: np.ndarray, offsets: np.ndarray, poly_of: np.ndarray) -> np.ndarray:
    """Index of the largest of ``values`` in each block ``offsets[i]:offsets[i+1]`` (the last of equal ones).

    What ``np.lexsort((values, poly_of))``'s last entry per block is (NaN
    largest), without the sort; blocks are not empty.
    """
    if (np.diff(offsets) == 0).any():
        far = np.zeros(len(offsets) - 1, np.int64)
        order = np.lexsort((values, poly_of))
        far[poly_of[order]] = order
        return far
    top = np.maximum.reduceat(values, offsets[:-1])[poly_of]
    at_top = (values == top) | (np.isnan(top) & np.isnan(values))
    return np.maximum.reduceat(np.where(at_top, np.arange(len(values)), -1), offsets[:-1])




def _cut_pinched(seq: list) -> list[list]:
    """Cut a cyclic sequence at repeated entries into simple cycles."""
    out, stack, where = [], [], {}
    for v in seq:
        if v in where:
            i = where[v]
            loop = stack[i:]
            out.append(loop)
            for w in loop[1:]:
                where.pop(w, None)
            del stack[i + 1:]
        else:
            where[v] = len(stack)
            stack.append(v)
    out.append(stack)
    return [[a for j, a in enumerate(c) if j == 0 or a != c[j - 1]] for c in out]


def assemble(
    offsets: np.ndarray,
    keys: np.ndarray,
    points: np.ndarray,
    gradient: Callable[[np.ndarray], np.ndarray],
    project: Callable[[np.ndarray], np.ndarray] | None = None,
    apex: np.ndarray | None = None,
    fixed_keys: np.ndarray | None = None,
    return_gradient: bool = False,
):
    """Vertices and triangles from polygons given by vertex keys.

    Parameters
    ----------
    offsets, keys : polygon i is ``keys[offsets[i]:offsets[i+1]]``
    points : (S, 3) position of every entry of ``keys``
    gradient : callable giving grad F at points (orientation reference)
    project : callable projecting points onto the surface (centre vertices)
    apex : (P,) bool, optional
        Polygons whose first vertex is a singular point: large ones are
        fanned from it rather than from a new centre vertex.
    fixed_keys : (F,) int64, optional
        Keys of vertices on a curve of singular points: an edge between
        two of them is never flipped (it is the curve, or a crease).
    return_gradient : bool
        Also return grad F at the vertices (the orientation reference,
        evaluated once: the shaping stage needs it too).

    Returns
    -------
    vertices : (V, 3), faces : (T, 3) int64, key_of_vertex : (V,) int64
    gradient : (V, 3), only with ``return_gradient``
    """
    uniq, ids = unique_inverse(keys)  # np.unique's, by one plain sort of packed keys
    first = np.zeros(len(uniq), np.int64)
    first[ids[::-1]] = np.arange(len(keys))[::-1]
    vertices = points[first]
    offsets, poly, src = clean_polygons(offsets, ids)
    offsets, poly, src = stitch_collinear(offsets, poly, src, vertices)
    normals = gradient(vertices)
    fan = None if apex is None else apex[src]
    faces, extra, _ = triangulate_polygons((offsets, poly), vertices, normals, project, fan)
    vertices = np.concatenate([vertices, extra])
    # Centre vertices have no key of their own: mark them with one no
    # event or singular point can have.
    vkeys = np.concatenate([uniq, np.full(len(extra), np.iinfo(np.int64).min, np.int64)])
    # A facet whose vertices all collapsed onto a line (a sliver of F + eps
    # of infinitesimal width, e.g. along a lattice line lying in the
    # surface) has no area: its triangles go.  Elsewhere the template
    # search never picks a zero-area triangle when another exists.
    area2, longest = area_and_longest(vertices, faces)
    keep = ~(area2 <= tol.ZERO_AREA * longest)  # NaN kept, as before
    faces = faces[keep]
    fixed = None if fixed_keys is None else np.isin(vkeys, fixed_keys)
    faces = flip_slivers(vertices, faces, fixed, measures=(area2[keep], longest[keep]))
    # Drop vertices no triangle uses (collapsed infinitesimal features).
    used = np.zeros(len(vertices), bool)
    used[faces.ravel()] = True
    remap = np.cumsum(used) - 1
    if return_gradient:
        grad = np.concatenate([normals, gradient(extra)]) if len(extra) else normals
        return vertices[used], remap[faces], vkeys[used], grad[used]
    return vertices[used], remap[faces], vkeys[used]
