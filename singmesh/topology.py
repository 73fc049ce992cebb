"""Topological and geometric facts computed from a triangle mesh alone."""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components


def edges_with_counts(faces: np.ndarray):
    """Unique undirected edges (E, 2) and how many triangles use each."""
    e = np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    return np.unique(e, axis=0, return_counts=True)


def component_count(n_vertices: int, faces: np.ndarray) -> int:
    """Connected components of the triangles (vertices joined by edges)."""
    if len(faces) == 0:
        return 0
    e = faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    g = coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n_vertices, n_vertices))
    _, label = connected_components(g, directed=False)
    return len(np.unique(label[np.unique(faces)]))


def triangle_angles(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Angles (T, 3) in degrees."""
    p = vertices[faces]
    out = np.empty((len(faces), 3))
    for i in range(3):
        a = p[:, (i + 1) % 3] - p[:, i]
        b = p[:, (i + 2) % 3] - p[:, i]
        c = np.einsum("ij,ij->i", a, b) / np.maximum(
            np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1), 1e-300)
        out[:, i] = np.degrees(np.arccos(np.clip(c, -1, 1)))
    return out


def on_box_boundary(points: np.ndarray, box: np.ndarray, rel: float = 1e-12) -> np.ndarray:
    """Whether points lie on a face of the box (to ``rel`` of its size)."""
    return _bounds_met(points, box, rel) >= 1


def on_box_edge(points: np.ndarray, box: np.ndarray, rel: float = 1e-12) -> np.ndarray:
    """Whether points lie on an edge of the box (two faces, to ``rel`` of its size)."""
    return _bounds_met(points, box, rel) >= 2


def _bounds_met(points: np.ndarray, box: np.ndarray, rel: float) -> np.ndarray:
    """Per point, how many of the box's faces it lies on (0 to 3)."""
    scale = rel * (box[:, 1] - box[:, 0])
    return ((np.abs(points - box[:, 0]) <= scale) | (np.abs(points - box[:, 1]) <= scale)).sum(axis=1)
