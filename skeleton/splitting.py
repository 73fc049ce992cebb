"""Truncated power series and the splitting lemma, in floating point.

The classifier of singular points (:mod:`singmesh.skeleton.classify`) works
on Taylor polynomials at a point known only to about 1e-12, so everything
here is numerical: a polynomial or power series in ``m`` variables is a
dense numpy array of shape ``(N + 1,) * m`` whose entry ``[i, j, ...]`` is
the coefficient of ``t1**i t2**j ...``; entries of total degree above the
truncation order ``N`` are kept at zero.  Exact sympy arithmetic would be
exact only for the wrong (rounded) point, and is far slower.

Main entry points
-----------------
compose
    ``F(p + M y)`` for a coefficient tensor ``F``: translation to a point
    and rotation to a new basis, by Horner's rule (no binomial tables, so
    nothing overflows for degree 18).
split
    The splitting lemma: eliminate the variables in which the quadratic
    part is non-degenerate by solving ``dG/dw = 0`` for them as power
    series in the kernel variables (implicit function theorem), and return
    the residual function of the kernel variables.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Sequence

import numpy as np

__all__ = [
    "degree_grid",
    "truncate",
    "mul",
    "derivative",
    "compose",
    "translate_many",
    "substitute",
    "split",
    "series_order",
]


@lru_cache(maxsize=64)
def _degree_grid(m: int, N: int) -> np.ndarray:
    grid = np.sum(np.indices((N + 1,) * m), axis=0) if m else np.zeros(())
    grid.setflags(write=False)
    return grid


def degree_grid(m: int, N: int) -> np.ndarray:
    """Total degree of each entry of an ``(N + 1,) * m`` coefficient array."""
    return _degree_grid(m, N)


@lru_cache(maxsize=64)
def _toeplitz_index(n: int) -> tuple[np.ndarray, np.ndarray]:
    diff = np.subtract.outer(np.arange(n), np.arange(n))
    return np.where(diff >= 0, diff, 0), diff < 0


def truncate(a: np.ndarray, N: int, m: int | None = None) -> np.ndarray:
    """Crop the first ``m`` axes (all by default) to ``N + 1`` and zero degree > N.

    Trailing axes beyond ``m`` are left alone (they index other, not yet
    substituted variables).
    """
    m = a.ndim if m is None else m
    index = tuple(slice(0, N + 1) for _ in range(m))
    out = np.array(a[index], dtype=float, copy=True)
    # Pad when the input is smaller than the truncation box.
    if any(s < N + 1 for s in out.shape[:m]):
        pad = [(0, N + 1 - s) for s in out.shape[:m]] + [(0, 0)] * (out.ndim - m)
        out = np.pad(out, pad)
    deg = degree_grid(m, N).reshape((N + 1,) * m + (1,) * (out.ndim - m))
    out[np.broadcast_to(deg > N, out.shape)] = 0.0
    return out


def mul(a: np.ndarray, b: np.ndarray, N: int, m: int | None = None) -> np.ndarray:
    """Truncated product of two series in the first ``m`` axes.

    ``b`` may have size-1 trailing axes so that it broadcasts over extra
    trailing axes of ``a`` (coefficients of variables not substituted yet).
    """
    m = a.ndim if m is None else m
    if m == 1 and a.shape[0] == N + 1 and b.shape[0] == N + 1 and b.size == N + 1:
        # One series variable: multiply by the lower-triangular Toeplitz
        # matrix of b (broadcasts over trailing axes of a).
        index, upper = _toeplitz_index(N + 1)
        Tb = b.reshape(N + 1)[index]
        Tb[upper] = 0.0
        # np.tensordot(Tb, a, axes=(1, 0)) without its bookkeeping: the
        # same matrix product on the same (N + 1, rest) view of a.
        return np.dot(Tb, a.reshape(N + 1, -1)).reshape(a.shape)
    if m == 2 and a.ndim == 2 and b.ndim == 2 and a.shape == b.shape == (N + 1, N + 1):
        # Two variables: Kronecker substitution, rows laid out with stride
        # 2N + 1 so that one 1-D convolution is the 2-D one (no overlap).
        stride = 2 * N + 1
        fa = np.zeros((N + 1, stride))
        fb = np.zeros((N + 1, stride))
        fa[:, : N + 1] = a
        fb[:, : N + 1] = b
        full = np.convolve(fa.ravel(), fb.ravel())[: (N + 1) * stride]
        return truncate(full.reshape(N + 1, stride), N, 2)
    if a.ndim == 1:
        full = np.convolve(a, b)
    else:
        # General case (not used by the classifier's 1- and 2-variable
        # series); scipy.signal is imported here because it is slow to load.
        # Direct, not FFT: FFT rounding is relative to the largest
        # coefficient and would swamp the small high-order ones.
        from scipy import signal

        full = signal.convolve(a, b, method="direct")
    return truncate(full, N, m)


def derivative(a: np.ndarray, axis: int) -> np.ndarray:
    """Coefficients of the partial derivative along ``axis`` (same shape)."""
    n = a.shape[axis]
    out = np.zeros_like(a)
    src = [slice(None)] * a.ndim
    dst = [slice(None)] * a.ndim
    src[axis] = slice(1, n)
    dst[axis] = slice(0, n - 1)
    shape = [1] * a.ndim
    shape[axis] = n - 1
    out[tuple(dst)] = a[tuple(src)] * np.arange(1, n, dtype=float).reshape(shape)
    return out


def _mul_affine(T: np.ndarray, const: float, lin: Sequence[float], m: int, N: int) -> np.ndarray:
    """``T * (const + sum_b lin[b] y_b)`` on the last ``m`` axes of ``T``.

    Terms pushed past index ``N`` are dropped: they have total degree > N
    and, the factor having no negative powers, only feed higher degrees.
    """
    out = const * T if const != 0.0 else np.zeros_like(T)
    lead = T.ndim - m
    for b, coef in enumerate(lin):
        if coef == 0.0:
            continue
        src = [slice(None)] * T.ndim
        dst = [slice(None)] * T.ndim
        src[lead + b] = slice(0, N)
        dst[lead + b] = slice(1, N + 1)
        out[tuple(dst)] += coef * T[tuple(src)]
    return out


def compose(coeffs: np.ndarray, const: Sequence[float], lin: np.ndarray, N: int) -> np.ndarray:
    """Coefficients of ``F(const + lin @ y)`` truncated at total degree ``N``.

    Parameters
    ----------
    coeffs : ndarray, n dimensions
        ``coeffs[i, j, ...]`` multiplies ``x1**i x2**j ...``.
    const : (n,) array_like
        Constant parts of the substituted affine forms (the point).
    lin : (n, m) array_like
        ``x_a = const[a] + sum_b lin[a, b] y_b``.
    N : int
        Truncation order of the result.

    Returns
    -------
    (N + 1,) * m ndarray
    """
    coeffs = np.asarray(coeffs, dtype=float)
    const = np.asarray(const, dtype=float)
    lin = np.atleast_2d(np.asarray(lin, dtype=float))
    n, m = lin.shape
    if coeffs.ndim != n:
        raise ValueError("coeffs has %d axes but %d forms were given" % (coeffs.ndim, n))
    unit = np.zeros((N + 1,) * m)
    unit[(0,) * m] = 1.0
    # Powers of the last form, then one matrix product does the innermost
    # Horner level for all leading indices at once.
    s_last = coeffs.shape[-1]
    powers = [unit]
    for _ in range(1, s_last):
        powers.append(_mul_affine(powers[-1], const[-1], lin[-1], m, N))
    P = np.stack(powers).reshape(s_last, -1)
    Q = (coeffs.reshape(-1, s_last) @ P).reshape(coeffs.shape[:-1] + (N + 1,) * m)
    # Horner over the remaining old variables, last to first.
    for a in range(n - 2, -1, -1):
        lead = (slice(None),) * a
        acc = Q[lead + (Q.shape[a] - 1,)]
        for i in range(Q.shape[a] - 2, -1, -1):
            acc = Q[lead + (i,)] + _mul_affine(acc, const[a], lin[a], m, N)
        Q = acc
    return truncate(Q, N, m)


def translate_many(coeffs: np.ndarray, points: np.ndarray, N: int) -> np.ndarray:
    """``compose(coeffs, p, np.eye(3), N)`` for every row p of ``points`` (K, 3), in one pass.

    The same products and sums as :func:`compose` makes for each point
    alone (the matrix product per point as a stacked one, the same BLAS
    call), so each result has the bits of its own call: (K, N+1, N+1, N+1).
    """
    coeffs = np.asarray(coeffs, dtype=float)
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    if coeffs.ndim != 3:
        raise ValueError("coeffs has %d axes but 3 forms were given" % coeffs.ndim)
    k = len(points)
    shape = (N + 1,) * 3

    def times(T, c, axis):
        # _mul_affine(T, c, unit vector along ``axis``, 3, N) per point:
        # c T (0 where c is 0, as compose's zeros_like), plus T shifted by
        # one along the axis (1.0 * T is T).
        cc = c.reshape((k,) + (1,) * (T.ndim - 1))
        out = np.where(cc != 0.0, cc * T, 0.0)
        src = [slice(None)] * T.ndim
        dst = [slice(None)] * T.ndim
        src[T.ndim - 3 + axis] = slice(0, N)
        dst[T.ndim - 3 + axis] = slice(1, N + 1)
        out[tuple(dst)] += 1.0 * T[tuple(src)]
        return out

    s_last = coeffs.shape[-1]
    unit = np.zeros((k,) + shape)
    unit[(slice(None),) + (0,) * 3] = 1.0
    powers = [unit]
    for _ in range(1, s_last):
        powers.append(times(powers[-1], points[:, 2], 2))
    P = np.ascontiguousarray(np.stack(powers, axis=1).reshape(k, s_last, -1))
    Q = np.matmul(coeffs.reshape(-1, s_last), P).reshape((k,) + coeffs.shape[:-1] + shape)
    for a in (1, 0):
        lead = (slice(None),) * (a + 1)
        acc = Q[lead + (Q.shape[a + 1] - 1,)]
        for i in range(Q.shape[a + 1] - 2, -1, -1):
            acc = Q[lead + (i,)] + times(acc, points[:, a], 0 if a == 0 else 1)
        Q = acc
    # truncate(Q, N, 3) per point: degree > N zeroed.
    out = np.array(Q, dtype=float, copy=True)
    out[:, degree_grid(3, N) > N] = 0.0
    return out


def substitute(T: np.ndarray, phis: Sequence[np.ndarray], N: int) -> np.ndarray:
    """``T(t, phi(t))``: substitute series for the trailing variables of ``T``.

    Parameters
    ----------
    T : (N + 1,) * (m + r) ndarray
        A polynomial in ``(t1..tm, w1..wr)``.
    phis : r arrays of shape (N + 1,) * m
        ``w_i = phis[i](t)``; they must have no constant term for the
        truncation to be exact (it is so for the splitting lemma).
    N : int

    Returns
    -------
    (N + 1,) * m ndarray
    """
    r = len(phis)
    m = T.ndim - r
    acc = T
    # Horner over w_r, then w_{r-1}, ...: each step multiplies by a series
    # in t that broadcasts over the w-axes not yet substituted.
    for i in range(r - 1, -1, -1):
        phi = phis[i].reshape(phis[i].shape + (1,) * i)
        s = acc.shape[-1]
        res = acc[..., s - 1]
        for k in range(s - 2, -1, -1):
            res = acc[..., k] + mul(res, phi, N, m)
        acc = res
    return truncate(acc, N, m)


def split(G: np.ndarray, m: int, mu: Sequence[float], N: int,
          critical: bool = True) -> tuple[np.ndarray, list[np.ndarray]]:
    """Splitting lemma: the residual function of the kernel variables.

    Parameters
    ----------
    G : (N + 1,) * 3 ndarray
        Taylor polynomial at the singular point in an eigenbasis of the
        Hessian, the ``m`` kernel variables first.  Its terms of degree
        <= 2 are ignored and replaced by ``sum_i mu[i] / 2 * w_i**2``: the
        point is taken to be exactly critical, and the eigenvalues deemed
        zero exactly zero (the caller decided so, within its tolerance).
    m : int
        Corank, 1 or 2.
    mu : sequence of 3 - m floats
        The non-zero Hessian eigenvalues, in the order of the w-axes.
    N : int
        Truncation order.
    critical : bool
        False: keep the terms of degree <= 2 as they are (the point is
        near, not at, the singular point).  ``g`` is then F along the polar
        set ``dG/dw = 0`` with all its low-order terms (the unfolding that
        :mod:`singmesh.skeleton.centre` removes), and ``phi`` may have a
        small constant term.

    Returns
    -------
    g : (N + 1,) * m ndarray
        ``g(t) = G(t, phi(t))`` where ``dG/dw (t, phi(t)) = 0``; then
        ``G ~ g(t) + sum mu_i / 2 * w_i**2`` (right equivalence).
    phi : list of (N + 1,) * m ndarrays
        The eliminated variables as series in ``t`` (no constant term).
    """
    r = 3 - m
    G = truncate(G, N)
    deg = degree_grid(3, N)
    if critical:
        G[deg <= 2] = 0.0
        for i in range(r):
            idx = [0, 0, 0]
            idx[m + i] = 2
            G[tuple(idx)] = mu[i] / 2.0
    grads = [derivative(G, m + i) for i in range(r)]
    phis = [np.zeros((N + 1,) * m) for _ in range(r)]
    # Fixed point phi <- phi - dG/dw(t, phi) / mu.  dG/dw = mu w + (terms of
    # degree >= 2), so each sweep fixes at least one more order of phi; N
    # sweeps make it exact to order N.
    for _ in range(N):
        values = [substitute(grads[i], phis, N) for i in range(r)]
        new = [phis[i] - values[i] / mu[i] for i in range(r)]
        change = max(float(np.max(np.abs(new[i] - phis[i]))) for i in range(r))
        phis = new
        if change == 0.0:
            break
    g = substitute(G, phis, N)
    if critical:
        # The residual has no terms below degree 3 (phi = O(t^2)); clear the
        # rounding dust so that later order tests see exact zeros there.
        g[degree_grid(m, N) <= 2] = 0.0
    return g, phis


def series_order(c: np.ndarray, threshold: float, start: int = 0) -> int | None:
    """First index ``j >= start`` with ``|c[j]| > threshold`` (1-D), or None."""
    for j in range(start, len(c)):
        if abs(c[j]) > threshold:
            return j
    return None
