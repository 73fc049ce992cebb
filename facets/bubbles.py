"""Closed specks of the lattice between two sheets closer than a cell.

Where two sheets of F = 0 pass within a cell of each other away from any
tube (a double curve or a degenerating cusp just outside the box, a
saddle contact), a lattice point can fall between them with all its
neighbours outside: the mesh of F + eps = 0 then closes a small
polyhedron round that point, a piece of its own.  The surface has no
such piece: a closed component of F = 0 bounds a region on which F has
an extremum, so a minimum or maximum of F lies inside it, while the thin
slab between two sheets has none: F is least across it and, along it,
greatest where the sheets are closest (a saddle), or has no critical
point at all.

A speck is dropped when it is closed inside the box, thin (no more than
``BUBBLE_THICKNESS`` cells across in its thinnest direction), small, has
no vertex on a singular point or curve, and Newton on grad F = 0 from its
centre finds no extremum of F in it: a real small component (a tiny
ellipsoid) keeps its extremum and stays.
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from singmesh import tolerances as tol


def lattice_specks(vertices: np.ndarray, faces: np.ndarray, box: np.ndarray, cell: float,
                   fixed: np.ndarray, gradient, hessian) -> np.ndarray:
    """Which triangles belong to lattice specks (see the module docstring).

    Parameters
    ----------
    vertices : (V, 3) ndarray
    faces : (T, 3) int64
    box : (3, 2) ndarray
        The domain: a piece with an open edge on it is not closed, and stays.
    cell : float
        The fine lattice's cell (largest side).
    fixed : (V,) bool
        Vertices on singular points and curves: a piece holding one stays.
    gradient, hessian : callables
        grad F (n, 3) and its Jacobian (n, 3, 3) at points (n, 3).

    Returns
    -------
    (T,) bool
    """
    drop = np.zeros(len(faces), bool)
    n = len(vertices)
    if len(faces) == 0:
        return drop
    a = faces.ravel()
    b = np.roll(faces, -1, axis=1).ravel()
    graph = coo_matrix((np.ones(len(a)), (a, b)), shape=(n, n))
    k, label = connected_components(graph, directed=False)
    face_label = label[faces[:, 0]]
    sizes = np.bincount(face_label, minlength=k)
    # Never the whole mesh: the largest piece stays whatever it is.
    candidates = [c for c in np.nonzero((sizes > 0) & (sizes <= tol.BUBBLE_FACES))[0].tolist()
                  if c != int(np.argmax(sizes))]
    if not candidates:
        return drop
    edges = np.sort(np.stack([a, b], axis=1), axis=1)
    uniq, count = np.unique(edges, axis=0, return_counts=True)
    open_vertex = np.zeros(n, bool)
    open_vertex[uniq[count == 1].ravel()] = True
    starts, pieces = [], []
    for c in candidates:
        tri = np.nonzero(face_label == c)[0]
        vs = np.unique(faces[tri])
        # Closed inside the box, no singular vertex, thin across.
        if open_vertex[vs].any() or fixed[vs].any():
            continue
        p = vertices[vs]
        centre = p.mean(axis=0)
        thinnest = np.linalg.svd(p - centre, compute_uv=False)[-1] if len(p) >= 3 else 0.0
        across = 2.0 * thinnest * np.sqrt(3.0 / len(p))   # rms spread -> extent, roughly
        if across > tol.BUBBLE_THICKNESS * cell:
            continue
        starts.append(centre)
        pieces.append((tri, p.min(axis=0) - cell, p.max(axis=0) + cell))
    if not pieces:
        return drop
    x = np.array(starts)
    g = gradient(x)
    scale = np.linalg.norm(g, axis=1) + np.abs(hessian(x)).max(axis=(1, 2)) * cell
    for _ in range(tol.BUBBLE_NEWTON):
        h = hessian(x)
        g = gradient(x)
        ok = np.abs(np.linalg.det(h)) > 0
        step = np.zeros_like(x)
        if ok.any():
            step[ok] = np.linalg.solve(h[ok], g[ok][..., None])[..., 0]
        x = x - step
    critical = np.linalg.norm(gradient(x), axis=1) <= tol.BUBBLE_CRITICAL * scale
    # An extremum (definite Hessian), not a saddle: where two sheets come
    # closest F has a saddle between them (least across, greatest along).
    lam = np.linalg.eigvalsh(hessian(x))
    critical &= (lam[:, 0] > 0) | (lam[:, -1] < 0)
    for (tri, lo, hi), xc, crit in zip(pieces, x, critical):
        inside = bool(np.all((xc >= lo) & (xc <= hi)))
        if not (crit and inside):
            drop[tri] = True
    return drop


def without_faces(vertices: np.ndarray, faces: np.ndarray, drop: np.ndarray, *per_vertex: np.ndarray):
    """The mesh without the ``drop`` triangles and the vertices only they used.

    Returns ``vertices, faces, *per_vertex`` (each per-vertex array kept
    on the same vertices).
    """
    faces = faces[~drop]
    used = np.zeros(len(vertices), bool)
    used[faces.ravel()] = True
    remap = np.cumsum(used) - 1
    return (vertices[used], remap[faces]) + tuple(a[used] for a in per_vertex)
