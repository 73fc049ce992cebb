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
    # Pinched polygons (a vertex twice, not consecutively): rare, cut in Python.
    order = np.lexsort((ids, poly_of))
    dup = (np.diff(poly_of[order]) == 0) & (np.diff(ids[order]) == 0)
    pinched = set(poly_of[order][1:][dup].tolist())
    out_ids, out_sizes, out_src = [], [], []
    for p in range(n_poly):
        seq = ids[new_offsets[p]:new_offsets[p + 1]]
        pieces = _cut_pinched(list(seq)) if p in pinched else [seq]
        for piece in pieces:
            if len(piece) >= 3:
                out_ids.append(np.asarray(piece, np.int64))
                out_sizes.append(len(piece))
                out_src.append(p)
    if not out_ids:
        return np.zeros(1, np.int64), np.zeros(0, np.int64), np.zeros(0, np.int64)
    return (np.concatenate([[0], np.cumsum(out_sizes)]), np.concatenate(out_ids),
            np.asarray(out_src, np.int64))


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
    cycle_offsets: np.ndarray,
    cycle_events: np.ndarray,
    event_key: np.ndarray,
    event_point: np.ndarray,
    gradient: Callable[[np.ndarray], np.ndarray],
    project: Callable[[np.ndarray], np.ndarray] | None = None,
):
    """Vertices and triangles from the cycles of all boxes.

    Parameters
    ----------
    cycle_offsets, cycle_events : cycles as event indices (see ``Cycles``)
    event_key, event_point : identity and position of every event
    gradient : callable giving grad F at points (orientation reference)
    project : callable projecting points onto the surface (centre vertices)

    Returns
    -------
    vertices : (V, 3), faces : (T, 3) int64, face_cycle : (T,) int64
    """
    keys, ids = np.unique(event_key[cycle_events], return_inverse=True)
    first = np.zeros(len(keys), np.int64)
    first[ids[::-1]] = cycle_events[::-1]
    vertices = event_point[first]
    offsets, poly, src = clean_polygons(cycle_offsets, ids)
    normals = gradient(vertices)
    faces, extra, face_poly = triangulate_polygons((offsets, poly), vertices, normals, project)
    vertices = np.concatenate([vertices, extra])
    face_cycle = src[face_poly]
    # Drop vertices no triangle uses (collapsed infinitesimal features).
    used = np.zeros(len(vertices), bool)
    used[faces.ravel()] = True
    remap = np.cumsum(used) - 1
    return vertices[used], remap[faces], face_cycle
