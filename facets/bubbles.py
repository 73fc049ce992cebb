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


def lattice_specks(vertices: np.ndarray, faces: np.ndarray, cell: float, fixed: np.ndarray,
                   gradient, hessian) -> np.ndarray:
    """Which triangles belong to lattice specks (see the module docstring).

    Parameters
    ----------
    vertices : (V, 3) ndarray
    faces : (T, 3) int64
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
    n = len(vertices)
    if len(faces) == 0:
        return np.zeros(0, bool)
    a = faces.ravel()
    b = np.roll(faces, -1, axis=1).ravel()
    # Two sides of each triangle join its three corners: the same pieces as
    # with all three sides, and the same labels (scipy numbers the pieces in
    # the order of their least vertex), from two thirds of the edges.
    two = np.concatenate([faces[:, 0], faces[:, 1]]), np.concatenate([faces[:, 1], faces[:, 2]])
    k, label = connected_components(coo_matrix((np.ones(len(two[0]), np.int8), two), shape=(n, n)), directed=False)
    face_label = label[faces[:, 0]]
    sizes = np.bincount(face_label, minlength=k)
    # A piece holding a singular vertex is the singularity's.
    spoiled = np.zeros(k, bool)
    np.logical_or.at(spoiled, label[fixed], True)
    # Never the whole mesh: the largest piece stays whatever it is.
    spoiled[np.argmax(sizes)] = True
    candidate = (sizes > 0) & (sizes <= tol.BUBBLE_FACES) & ~spoiled
    if not candidate.any():
        return np.zeros(len(faces), bool)
    # A piece with an open edge (on the box: one inside is not made) is
    # not closed (counted only when a small piece is left to judge).
    # Each undirected edge as one integer key (lower end * n + upper end):
    # a 1-d unique is some 12 times faster than unique rows (axis=0).
    key, count = np.unique(np.minimum(a, b) * n + np.maximum(a, b), return_counts=True)
    np.logical_or.at(spoiled, label[key[count == 1] // n], True)
    candidate &= ~spoiled
    if not candidate.any():
        return np.zeros(len(faces), bool)
    # Thickness of every piece at once: the smallest eigenvalue of its
    # vertices' covariance (2 sqrt(3 lambda): the extent of points spread
    # evenly across it).
    used = np.unique(faces)
    lab = label[used]
    m = np.bincount(lab, minlength=k).astype(float)
    centre = np.stack([np.bincount(lab, vertices[used, i], minlength=k) for i in range(3)], axis=1)
    centre /= np.maximum(m, 1.0)[:, None]
    d = vertices[used] - centre[lab]
    cov = np.zeros((k, 3, 3))
    np.add.at(cov, lab, d[:, :, None] * d[:, None, :])
    cov /= np.maximum(m, 1.0)[:, None, None]
    across = 2.0 * np.sqrt(3.0 * np.maximum(np.linalg.eigvalsh(cov[candidate])[:, 0], 0.0))
    pieces = np.nonzero(candidate)[0][across <= tol.BUBBLE_THICKNESS * cell]
    if not len(pieces):
        return np.zeros(len(faces), bool)
    # Newton on grad F = 0 from each piece's centre, all pieces at once.
    x = centre[pieces].copy()
    scale = np.linalg.norm(gradient(x), axis=1) + np.abs(hessian(x)).max(axis=(1, 2)) * cell
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
    # ... inside the piece's bounding box, widened by a cell.
    lo = np.full((k, 3), np.inf)
    hi = np.full((k, 3), -np.inf)
    np.minimum.at(lo, lab, vertices[used])
    np.maximum.at(hi, lab, vertices[used])
    inside = np.all((x >= lo[pieces] - cell) & (x <= hi[pieces] + cell), axis=1)
    speck = np.zeros(k, bool)
    speck[pieces[~(critical & inside)]] = True
    return speck[face_label]


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
