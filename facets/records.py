"""The curves of singular points as the mesh records them: their mesh vertices.

The curve graph's points are vertices of the mesh under the keys from
:func:`singmesh.facets.polygons.curve_key0` on; after assembly each key is
looked up among the vertices' keys.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from singmesh.sorting import search_sorted


def vertex_of(vkeys: np.ndarray, keys: np.ndarray) -> np.ndarray:
    """Mesh vertex of each key, -1 for keys no vertex has (``vkeys``: the key of each vertex)."""
    if len(vkeys) == 0:
        return np.full(len(keys), -1, np.int64)
    order = np.argsort(vkeys)
    pos = np.minimum(search_sorted(vkeys[order], keys), max(len(vkeys) - 1, 0))
    hit = (len(vkeys) > 0) & (vkeys[order][pos] == keys)
    return np.where(hit, order[pos], -1)


def curve_records(curves, vkeys: np.ndarray, key0: int) -> tuple[list, list]:
    """The curves' pieces and special points with their mesh vertices filled in.

    ``curves``: the traced curves (points keyed ``key0 + i``), ``vkeys``:
    the key of each mesh vertex.
    """
    if len(curves.points) == 0:
        return [], []
    vert = vertex_of(vkeys, key0 + np.arange(len(curves.points)))
    # Points no triangle has (an isolated line) follow the vertices, as in
    # Mesh.curve_lines().
    alone = vert < 0
    vert[alone] = len(vkeys) + np.arange(alone.sum())
    pieces = [replace(c, vertices=vert[c.vertices]) for c in curves.pieces]
    special = [replace(sp, vertex=int(vert[v])) for sp, v in zip(curves.special, curves.special_vertex.tolist())]
    return pieces, special


def curve_graph(curves, vkeys: np.ndarray, key0: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The curve graph: its points, edges (point pairs) and the mesh vertex of each point (-1: none)."""
    if len(curves.points) == 0:
        return np.zeros((0, 3)), np.zeros((0, 2), np.int64), np.zeros(0, np.int64)
    return curves.points, curves.edges, vertex_of(vkeys, key0 + np.arange(len(curves.points)))
