"""Curvatures of the surface F = 0 at points of it, from F's exact derivatives.

Goldman's formulas for implicit surfaces (R. Goldman, "Curvature formulas
for implicit curves and surfaces", CAGD 22, 2005), with g = grad F and
H the Hessian of F at a point of F = 0:

* Gaussian curvature ``K = -det([[H, g], [g^T, 0]]) / |g|^4``
  (= g adj(H) g^T / |g|^4);
* mean curvature ``M = (g H g^T - |g|^2 tr H) / (2 |g|^3)``;
* principal curvatures ``k1, k2 = M +- sqrt(max(M^2 - K, 0))``, k1 >= k2.

Sign convention: the unit normal is ``n = grad F / |grad F|`` (the mesh's
normals) and a curvature is positive where the surface bends *towards*
n (its centre of curvature on n's side), ``M = -div(n) / 2``.  The sphere ``x^2 + y^2 + z^2 - r^2`` (n outward)
has ``M = k1 = k2 = -1/r`` and ``K = 1/r^2``; written as ``r^2 - x^2 - y^2
- z^2`` (n inward) it has ``M = +1/r``.  K does not depend on the sign of F.

Where grad F vanishes (singular points and curves) the curvature is not
defined: all values are NaN there, and where F is not defined or not
differentiable to second order (NaN or infinite derivatives).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .tolerances import CURVATURE_GRADIENT_ZERO


@dataclass
class Curvatures:
    """Curvatures at n points (NaN where grad F vanishes).

    Attributes
    ----------
    gaussian : (n,) float64
        K = k1 k2.
    mean : (n,) float64
        (k1 + k2) / 2, positive where the surface bends towards grad F.
    principal : (n, 2) float64
        k1 >= k2.
    directions : (n, 2, 3) float64
        Unit tangent directions of k1 and k2 (any orthonormal pair at an
        umbilic, where k1 = k2).
    """

    gaussian: np.ndarray
    mean: np.ndarray
    principal: np.ndarray
    directions: np.ndarray


def curvatures(surface, points) -> Curvatures:
    """Gaussian, mean and principal curvatures of ``surface`` at ``points`` on it.

    Parameters
    ----------
    surface : singmesh.surface.Surface
        F, through ``jet`` (value, gradient, Hessian) and ``gradient_magnitude``.
    points : (n, 3) array_like
        Points of F = 0 (the formulas hold on the zero set only).

    Returns
    -------
    Curvatures
    """
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    if len(p) == 0:
        return Curvatures(np.zeros(0), np.zeros(0), np.zeros((0, 2)), np.zeros((0, 2, 3)))
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        _, g, h = surface.jet(p)
        return from_derivatives(g, h, surface.gradient_magnitude(p))


def from_derivatives(g: np.ndarray, h: np.ndarray, g_magnitude: np.ndarray | None = None) -> Curvatures:
    """:func:`curvatures` from the gradients (n, 3) and Hessians (n, 3, 3).

    ``g_magnitude`` (n, 3), the size of the terms summed for each partial
    derivative: a gradient below its rounding error is zero (NaN results).
    """
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        gg = np.einsum("ni,ni->n", g, g)
        norm = np.sqrt(gg)
        zero = ~(norm > 0) | ~np.isfinite(norm) | ~np.isfinite(h).all(axis=(1, 2))
        if g_magnitude is not None:
            # grad F = 0 to rounding: a singular point, not a tiny gradient.
            zero |= norm <= CURVATURE_GRADIENT_ZERO * np.linalg.norm(g_magnitude, axis=1)
        safe = np.where(zero, 1.0, norm)
        # g adj(H) g^T: adj(H) of a symmetric 3 x 3 matrix by cofactors.
        adj = _adjugate(h)
        gaussian = np.einsum("ni,nij,nj->n", g, adj, g) / safe**4
        ghg = np.einsum("ni,nij,nj->n", g, h, g)
        mean = (ghg - gg * np.trace(h, axis1=1, axis2=2)) / (2 * safe**3)
        root = np.sqrt(np.maximum(mean**2 - gaussian, 0.0))
        principal = np.stack([mean + root, mean - root], axis=1)
        directions = _principal_directions(g / safe[:, None], h / safe[:, None, None])
    gaussian[zero] = np.nan
    mean[zero] = np.nan
    principal[zero] = np.nan
    directions[zero] = np.nan
    return Curvatures(gaussian, mean, principal, directions)


def _adjugate(h: np.ndarray) -> np.ndarray:
    """Adjugate (transposed cofactor matrix) of each 3 x 3 matrix: (n, 3, 3)."""
    i1, i2 = [1, 2, 0], [2, 0, 1]
    # cof[a, b] = h[a+1, b+1] h[a+2, b+2] - h[a+1, b+2] h[a+2, b+1] (indices mod 3).
    cof = (h[:, i1][:, :, i1] * h[:, i2][:, :, i2] - h[:, i1][:, :, i2] * h[:, i2][:, :, i1])
    return np.swapaxes(cof, 1, 2)


def _principal_directions(n: np.ndarray, h: np.ndarray) -> np.ndarray:
    """Eigenvectors of the shape operator -P H P / |g| in the tangent plane: (n, 2, 3).

    ``n`` unit normals, ``h`` Hessians divided by |g|.  The operator is
    written in an orthonormal tangent basis (t1, t2) and its 2 x 2 matrix
    diagonalised; the larger eigenvalue (k1) comes first.
    """
    # t1: n crossed with the axis it is least along (never parallel to n).
    axis = np.eye(3)[np.argmin(np.abs(np.nan_to_num(n)), axis=1)]
    t1 = np.cross(n, axis)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(n, t1)
    basis = np.stack([t1, t2], axis=1)  # (n, 2, 3)
    s = -np.einsum("nai,nij,nbj->nab", basis, h, basis)
    ok = np.isfinite(s).all(axis=(1, 2))
    vec = np.full((len(n), 2, 2), np.nan)
    if ok.any():
        _, v = np.linalg.eigh(s[ok])  # ascending: k2's vector, then k1's
        vec[ok] = v[:, :, ::-1]
    # Column c of vec: the basis coefficients of direction c.
    return np.einsum("nac,nai->nci", vec, basis)
