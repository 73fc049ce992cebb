"""Roots of a polynomial surface on axis-parallel lines (its ``line_roots``).

F restricted to a line is a univariate polynomial: its power coefficients
come straight from the monomial tensor, are rescaled to the segment, and
all its roots are found at once as companion-matrix eigenvalues, so none
is missed between sign samples; nearly-real ones are kept (nearly-double
roots too) and polished by Newton's method to full double precision.
"""

from __future__ import annotations

import numpy as np
from scipy.special import comb

from singmesh import tolerances as tol


def line_roots(coeffs: np.ndarray, axis: int, fixed: np.ndarray, s0: np.ndarray, s1: np.ndarray):
    """Zeros of the polynomial with monomial tensor ``coeffs`` on lattice segments.

    Parameters
    ----------
    coeffs : monomial tensor of F
    axis : the lines' direction
    fixed : (L, 2) coordinates of the two other axes (cyclic order)
    s0, s1 : (L,) the segments' ends along ``axis``

    Returns
    -------
    row : (R,) int64, s : (R,) float64
        The segment and the coordinate along ``axis`` of each root.
    """
    poly = line_polynomials(coeffs, axis, fixed)
    # Work in tau in [-1, 1] over the segment.
    centre, half = (s0 + s1) / 2, (s1 - s0) / 2
    row, root = real_roots(_rescale(poly, centre, half), 1.0)
    return row, centre[row] + half[row] * root


def line_polynomials(coeffs: np.ndarray, axis: int, fixed: np.ndarray) -> np.ndarray:
    """Power coefficients (in the global coordinate of ``axis``) of F on lines.

    Parameters
    ----------
    coeffs : monomial tensor of F
    axis : the line direction
    fixed : (L, 2) coordinates of the two other axes (cyclic order)

    Returns
    -------
    (L, n_axis + 1) ndarray, lowest power first
    """
    ua, va = (axis + 1) % 3, (axis + 2) % 3
    t = np.moveaxis(coeffs, (axis, ua, va), (0, 1, 2))
    pu = fixed[:, 0:1] ** np.arange(t.shape[1])
    pv = fixed[:, 1:2] ** np.arange(t.shape[2])
    return np.einsum("ijk,lj,lk->li", t, pu, pv, optimize=True)


def _rescale(poly: np.ndarray, centre: np.ndarray, half: np.ndarray) -> np.ndarray:
    """Coefficients in tau where s = centre + half * tau (rows independent)."""
    n = poly.shape[1] - 1
    i = np.arange(n + 1)[None, :, None]
    j = np.arange(n + 1)[None, None, :]
    # coefficient of tau^j: sum_i c_i C(i, j) centre^(i-j) half^j
    m = np.where(i >= j, comb(i, j) * centre[:, None, None] ** np.maximum(i - j, 0), 0.0)
    out = np.einsum("li,lij->lj", poly, m)
    return out * half[:, None] ** np.arange(n + 1)


def _horner(coeffs: np.ndarray, t: np.ndarray):
    """Values and derivatives of stacked polynomials (lowest power first)."""
    p = np.zeros_like(t)
    dp = np.zeros_like(t)
    for k in range(coeffs.shape[1] - 1, -1, -1):
        dp = dp * t + p
        p = p * t + coeffs[:, k]
    return p, dp


def real_roots(tau_poly: np.ndarray, bound: float):
    """Real roots in [-bound, bound] of stacked polynomials in tau.

    Roots are found as companion-matrix eigenvalues (all of them, so none
    is missed between sign samples), kept when nearly real, and polished by
    Newton's method.

    Returns
    -------
    row : (R,) int64, root : (R,) float64
    """
    rows, roots = [], []
    scale = np.abs(tau_poly).max(axis=1)
    nonzero = scale > 0
    # Effective degree: drop leading coefficients negligible on [-1, 1];
    # the roots they would add lie far outside the interval.
    significant = np.abs(tau_poly) > 1e-13 * scale[:, None]
    degree = np.where(significant.any(axis=1),
                      tau_poly.shape[1] - 1 - np.argmax(significant[:, ::-1], axis=1), 0)
    for d in np.unique(degree[nonzero]):
        if d < 1:
            continue
        sel = np.nonzero(nonzero & (degree == d))[0]
        c = tau_poly[sel, : d + 1] / tau_poly[sel, d : d + 1]
        comp = np.zeros((len(sel), d, d))
        comp[:, np.arange(1, d), np.arange(d - 1)] = 1.0
        comp[:, :, -1] = -c[:, :d]
        eig = np.linalg.eigvals(comp)
        near = (np.abs(eig.imag) <= tol.ROOT_IMAG) & (np.abs(eig.real) <= bound)
        r, k = np.nonzero(near)
        rows.append(sel[r])
        roots.append(eig.real[r, k])
    if not rows:
        return np.zeros(0, np.int64), np.zeros(0)
    row = np.concatenate(rows)
    root = np.concatenate(roots)
    coeffs = tau_poly[row]
    for _ in range(tol.NEWTON_ITERATIONS):
        p, dp = _horner(coeffs, root)
        ok = np.abs(dp) > 0
        step = np.where(ok, p / np.where(ok, dp, 1.0), 0.0)
        # Near a multiple root Newton may overshoot: accept only steps that
        # do not increase |p|.
        trial = root - step
        pt, _ = _horner(coeffs, trial)
        better = np.abs(pt) <= np.abs(p)
        root = np.where(better, trial, root)
    return row, root
