"""Skeleton directions at a singular point: the Delta tests.

The skeleton for a direction v is V(F, grad F . v).  At a node with Hessian
M (F ~ x^T M x / 2) it has two real branches through the node iff

    Delta_v = -(v^T M v) |M| > 0

(seed 002 derives it for the axes, x +- y, x +- y +- z).  Fixed directions
can all fail (the seed gives two quadratic forms for which all thirteen
do); an eigenvector of M whose eigenvalue has the sign opposite to |M|
always passes when M is indefinite and non-degenerate, since then
v^T M v = lambda and Delta = -lambda |M| > 0.

For degenerate points (rank M < 3: A_k with k >= 2, D_k, E_6..E_8) the
quadratic test says nothing about the higher-order terms that shape the
branches, so the rule is: try the eigenvectors of M (those of non-zero
eigenvalues, then the kernel), then the thirteen fixed directions, and
keep a direction for a branch when its skeleton curve, traced from the
branch's link cycle, really reaches the point (see
:mod:`singmesh.skeleton.curves`).  That check is what guarantees a
skeleton curve per branch wherever one of these directions has one.
"""

from __future__ import annotations

import numpy as np

#: The thirteen fixed directions of SingSurf: axes, x+-y, x+-z, y+-z, x+-y+-z.
FIXED_DIRECTIONS = np.array([
    [1, 0, 0], [0, 1, 0], [0, 0, 1],
    [1, 1, 0], [1, -1, 0], [1, 0, 1], [1, 0, -1], [0, 1, 1], [0, 1, -1],
    [1, 1, 1], [1, 1, -1], [1, -1, 1], [1, -1, -1],
], dtype=float) / np.linalg.norm([
    [1, 0, 0], [0, 1, 0], [0, 0, 1],
    [1, 1, 0], [1, -1, 0], [1, 0, 1], [1, 0, -1], [0, 1, 1], [0, 1, -1],
    [1, 1, 1], [1, 1, -1], [1, -1, 1], [1, -1, -1],
], axis=1)[:, None]


def delta(hessian: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Delta_v = -(v^T M v) |M| for one or many directions v (..., 3)."""
    m = np.asarray(hessian, dtype=float)
    v = np.asarray(v, dtype=float)
    return -np.einsum("...i,ij,...j->...", v, m, v) * np.linalg.det(m)


def skeleton_directions(hessian: np.ndarray, rank_tol: float = 1e-8) -> np.ndarray:
    """Directions v to try for skeleton curves V(F, grad F . v), best first.

    Non-degenerate M: the eigenvectors passing the Delta test, then the
    fixed directions passing it.  Degenerate M: eigenvectors (non-zero
    eigenvalues first, then the kernel), then all fixed directions; the
    caller keeps those whose curve reaches the point.

    Returns
    -------
    (k, 3) ndarray of unit vectors
    """
    m = 0.5 * (np.asarray(hessian, float) + np.asarray(hessian, float).T)
    w, vecs = np.linalg.eigh(m)
    scale = max(np.abs(w).max(), 1e-300)
    degenerate = np.abs(w) <= rank_tol * scale
    if not degenerate.any():
        if (w > 0).all() or (w < 0).all():
            return np.zeros((0, 3))  # definite: an isolated point, no skeleton
        eig = vecs.T[delta(m, vecs.T) > 0]
        fixed = FIXED_DIRECTIONS[delta(m, FIXED_DIRECTIONS) > 0]
        return _canonical(np.concatenate([eig, fixed]))
    order = np.argsort(degenerate, kind="stable")  # non-zero eigenvalues first
    return _canonical(np.concatenate([vecs.T[order], FIXED_DIRECTIONS]))


def _canonical(v: np.ndarray) -> np.ndarray:
    """Unit vectors with a deterministic sign (first non-zero entry > 0)."""
    v = v / np.linalg.norm(v, axis=1, keepdims=True)
    first = np.argmax(np.abs(v) > 1e-12, axis=1)
    sign = np.sign(v[np.arange(len(v)), first])
    return v * sign[:, None]
