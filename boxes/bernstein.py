"""Tensor-product Bernstein forms of a polynomial on boxes.

On a box ``[a0, b0] x [a1, b1] x [a2, b2]`` with local parameters
``t_i = (x_i - a_i) / (b_i - a_i)`` the polynomial is

    F = sum_{ijk} B[i, j, k] b_i^n0(t0) b_j^n1(t1) b_k^n2(t2)

with ``b_i^n(t) = C(n, i) t^i (1 - t)^(n - i)``.  The coefficients bound F
(convex-hull property): all of one sign means F has that sign on the box.
Arrays of many boxes are stacked along a leading axis, ``(n_boxes, n0+1,
n1+1, n2+1)``, and every operation here works on the whole stack.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from scipy.special import comb


@lru_cache(maxsize=None)
def power_to_bernstein(n: int) -> np.ndarray:
    """Matrix taking power coefficients in t on [0, 1] to Bernstein ones.

    ``b_k = sum_{j <= k} C(k, j) / C(n, j) q_j``.
    """
    k = np.arange(n + 1)[:, None]
    j = np.arange(n + 1)[None, :]
    m = np.where(j <= k, comb(k, j) / comb(n, j), 0.0)
    m.setflags(write=False)
    return m


def interval_matrix(n: int, a: float, b: float) -> np.ndarray:
    """Matrix taking power coefficients in x to Bernstein coefficients on [a, b]."""
    i = np.arange(n + 1)[None, :]
    j = np.arange(n + 1)[:, None]
    h = b - a
    # Substitute x = a + h t: coefficient of t^j is sum_i c_i C(i, j) a^(i-j) h^j.
    shift = np.where(i >= j, comb(i, j) * np.power(float(a), np.maximum(i - j, 0)), 0.0)
    shift = shift * np.power(float(h), j)
    return power_to_bernstein(n) @ shift


def bernstein_on_box(coeffs: np.ndarray, box) -> np.ndarray:
    """Bernstein tensor of the monomial tensor ``coeffs`` on ``box``.

    Parameters
    ----------
    coeffs : (n0+1, n1+1, n2+1) ndarray
        Monomial coefficients (``coeffs[i, j, k]`` of ``x^i y^j z^k``).
    box : sequence of three (lo, hi) pairs

    Returns
    -------
    (n0+1, n1+1, n2+1) ndarray
    """
    mats = [interval_matrix(coeffs.shape[a] - 1, *box[a]) for a in range(3)]
    return np.einsum("ai,bj,ck,ijk->abc", *mats, coeffs, optimize=True)


@lru_cache(maxsize=None)
def split_matrices(n: int) -> tuple[np.ndarray, np.ndarray]:
    """De Casteljau at t = 1/2: matrices giving the left and right halves.

    ``left = L @ b`` and ``right = R @ b`` are exact up to rounding (the
    entries are dyadic rationals).
    """
    i = np.arange(n + 1)[:, None]
    j = np.arange(n + 1)[None, :]
    left = np.where(j <= i, comb(i, j) / 2.0 ** i, 0.0)
    right = np.where(j >= i, comb(n - i, j - i) / 2.0 ** (n - i), 0.0)
    left.setflags(write=False)
    right.setflags(write=False)
    return left, right


def split(tensors: np.ndarray) -> np.ndarray:
    """Split every box of a stack into its 8 children.

    Parameters
    ----------
    tensors : (N, n0+1, n1+1, n2+1) ndarray

    Returns
    -------
    (N, 2, 2, 2, n0+1, n1+1, n2+1) ndarray
        ``out[m, cx, cy, cz]`` is the child with lower corner at
        ``parent_corner + (cx, cy, cz) * half_size``.
    """
    n = tensors.shape[0]
    n0, n1, n2 = tensors.shape[1:]
    both = [_both(d - 1) for d in (n0, n1)]
    last = split_matrices(n2 - 1)
    # One axis at a time as matrix products, in the order 0, 1, 2 (each
    # child's coefficient the same sums, rounded the same).  The middle
    # axis as one wide product: its axis moved to the front first (a copy
    # in runs of n2), not a batch of N * 2 * n0 small products (BLAS's
    # call per 5 x 5 matrix was a third of the split).  The last product
    # of each child half is written straight into its place.
    a = np.matmul(both[0], tensors.reshape(n, n0, n1 * n2))  # (N, [p a], [b c])
    a = np.ascontiguousarray(a.reshape(n * 2 * n0, n1, n2).transpose(1, 0, 2)).reshape(n1, -1)
    b = (both[1] @ a).reshape(2, n1, n, 2, n0, n2)  # (q, b, N, p, a, c)
    b = np.ascontiguousarray(b.transpose(2, 3, 0, 4, 1, 5)).reshape(-1, n2)  # (N, p, q, a, b, c)
    out = np.empty((n, 2, 2, 2, n0, n1, n2))
    for r in range(2):
        out[:, :, :, r] = (b @ last[r].T).reshape(n, 2, 2, n0, n1, n2)
    return out


@lru_cache(maxsize=None)
def _both(n: int) -> np.ndarray:
    """The left and right split matrices of degree ``n`` stacked: (2 (n+1), n+1)."""
    both = np.concatenate(split_matrices(n))
    both.setflags(write=False)
    return both


def derivative(tensors: np.ndarray, axis: int) -> np.ndarray:
    """Bernstein coefficients of dF/dt_axis (up to the positive factor n / h).

    Only signs are used by the callers, and the factor ``n / (b - a)`` is
    positive, so it is left out.
    """
    return np.diff(tensors, axis=1 + axis)


def sign_definite(coeffs: np.ndarray, axes) -> np.ndarray:
    """Whether the coefficients over ``axes`` are all >= 0 or all <= 0 and not all 0.

    The convex-hull property then makes the function monotone (weakly, and
    strictly off a set of measure zero) on the box or face.
    """
    if any(coeffs.shape[a] == 0 for a in axes):
        # F has degree 0 in that variable: the derivative is identically 0.
        return np.zeros(coeffs.shape[: min(axes)], dtype=bool)
    lo = coeffs.min(axis=axes)
    hi = coeffs.max(axis=axes)
    return ((lo >= 0) & (hi > 0)) | ((hi <= 0) & (lo < 0))


def evaluate_1d(coeffs: np.ndarray, t: np.ndarray) -> np.ndarray:
    """De Casteljau evaluation of stacked univariate Bernstein polynomials.

    Parameters
    ----------
    coeffs : (N, n+1) ndarray
    t : (N,) ndarray
    """
    b = np.array(coeffs, dtype=float, copy=True)
    t = np.asarray(t, dtype=float)[:, None]
    for r in range(b.shape[1] - 1, 0, -1):
        b = (1 - t) * b[:, :r] + t * b[:, 1 : r + 1]
    return b[:, 0]
