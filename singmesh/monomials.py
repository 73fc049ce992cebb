"""Monomial tensors of polynomials in x, y, z: derivatives and evaluation at points.

``C[i, j, k]`` is the coefficient of ``x**i y**j z**k``.  Used by
:class:`singmesh.surface.PolynomialSurface` (values, gradients, Hessians
and term sizes at points); the stages never see these tensors.
"""

from __future__ import annotations

import numpy as np


def differentiate(coeffs: np.ndarray, axis: int) -> np.ndarray:
    """Monomial coefficients of dF/d(axis) from those of F (same shape)."""
    n = coeffs.shape[axis]
    scale = np.arange(n, dtype=float)
    shape = [1, 1, 1]
    shape[axis] = n
    d = coeffs * scale.reshape(shape)
    d = np.roll(d, -1, axis=axis)
    index = [slice(None)] * 3
    index[axis] = n - 1
    d[tuple(index)] = 0.0
    return d


def powers(values: np.ndarray, n: int) -> np.ndarray:
    """``values[:, None] ** arange(n)`` by repeated products (exact for ints)."""
    out = np.empty(values.shape + (n,), dtype=float)
    out[..., 0] = 1.0
    if values.size <= _FEW_VALUES and n > 1:
        # Few points (the evaluations at one point): one running product
        # along the last axis, the same products in the same order in
        # three calls instead of n.
        out[..., 1:] = values[..., None]
        np.multiply.accumulate(out, axis=-1, out=out)
        return out
    # Many values: the powers as rows (each product a contiguous pass, not
    # a strided column: ten times faster), then laid out as columns.
    out[...] = np.moveaxis(power_rows(values, n), 0, -1)
    return out


def power_rows(values: np.ndarray, n: int) -> np.ndarray:
    """``values ** i`` for i < n as rows (n, ...) by repeated products: the bits of :func:`powers`."""
    rows = np.empty((n,) + values.shape, dtype=float)
    rows[0] = 1.0
    for i in range(1, n):
        np.multiply(rows[i - 1], values, out=rows[i])
    return rows


#: Up to this many values :func:`powers` takes a running product along the
#: powers (its inner loop is that short: slower than a product per power
#: on long columns, faster where the calls' overhead dominates).
_FEW_VALUES = 64


def evaluate_tensor(coeffs: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Evaluate the polynomial with monomial tensor ``coeffs`` at ``points``.

    Parameters
    ----------
    coeffs : (nx, ny, nz) ndarray
        ``coeffs[i, j, k]`` multiplies ``x**i y**j z**k``.
    points : (..., 3) ndarray

    Returns
    -------
    values : (...) ndarray
    """
    return evaluate_tensors([coeffs], points)[0]


def evaluate_tensors(tensors, points: np.ndarray, alone: bool = False) -> list[np.ndarray]:
    """:func:`evaluate_tensor` for several tensors of one shape at the same points.

    The powers of the coordinates are formed once for all of them; each
    value is computed exactly as :func:`evaluate_tensor` computes it alone.
    With ``alone``, each point's values have the bits of a call with that
    point alone (BLAS takes one row (gemv) in another order than several
    (gemm)): many per-point calls in one.
    """
    p = np.asarray(points, dtype=float)
    shape = p.shape[:-1]
    p = p.reshape(-1, 3)
    if alone:
        return [v.reshape(shape) for v in _contract(tensors, p, alone=True)]
    # Many points go in blocks: the (K, ny * nz) intermediate of a whole
    # large batch does not fit in cache and costs several times more.
    # Each row's value does not depend on the block (BLAS's gemm), but a
    # block of one row would be gemv: a last single row joins the block before.
    starts = list(range(0, len(p), _BLOCK)) or [0]
    if len(starts) > 1 and len(p) - starts[-1] == 1:
        starts.pop()
    ends = starts[1:] + [len(p)]
    contract = _contract_many if len(p) > _MANY else _contract
    blocks = [contract(tensors, p[a:b]) for a, b in zip(starts, ends)]
    if len(blocks) == 1:
        return [v.reshape(shape) for v in blocks[0]]
    return [np.concatenate(v).reshape(shape) for v in zip(*blocks)]


#: Points per block in :func:`evaluate_tensors`.
_BLOCK = 8192


def evaluate_tensors_many(tensors, points: np.ndarray) -> list[np.ndarray]:
    """The values :func:`evaluate_tensors` gives at ``points`` (K, 3) when called with
    more than ``_MANY`` points, for any K: each point's values do not depend on the
    others (:func:`_contract_many`), so a subset of a large call's points reads the
    bits that call gave them."""
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    blocks = [_contract_many(tensors, p[a:a + _BLOCK]) for a in range(0, len(p), _BLOCK)] or [
        _contract_many(tensors, p)]
    return [np.concatenate(v) for v in zip(*blocks)]

#: Above this many points :func:`evaluate_tensors` contracts y and z in one
#: matrix product of all the tensors (:func:`_contract_many`): a third of
#: the time of a product per tensor for F and grad F at 15,000 points.
#: Fewer (a point or a few: the per-point calls) keep :func:`_contract`,
#: whose one-row products the ``_each`` batches repeat to the bit.
_MANY = 64


def _contract_many(tensors, p: np.ndarray) -> list[np.ndarray]:
    """The polynomials with monomial tensors ``tensors`` (one shape) at the rows of p (K, 3), for many rows.

    The products y^j z^k of each point (a (ny nz, K) table) against each
    tensor in a matrix product (:func:`column_products`), then Horner's
    rule in x (whole rows): no stack of K tiny matrix products.  A point's
    values do not depend on the other points or on the other tensors.
    Other rounding than :func:`_contract`, as accurate.
    """
    nx, ny, nz = tensors[0].shape
    q = (power_rows(p[:, 1], ny)[:, None, :] * power_rows(p[:, 2], nz)[None, :, :]).reshape(ny * nz, -1)
    x = p[:, 0]
    out = []
    for coeffs in tensors:
        t = column_products(coeffs.reshape(nx, ny * nz), q)
        v = t[nx - 1].copy()
        for i in range(nx - 2, -1, -1):
            v *= x
            v += t[i]
        out.append(v)
    return out


def column_products(w: np.ndarray, q: np.ndarray) -> np.ndarray:
    """``w @ q`` (BLAS) with each column's bits independent of the other columns.

    BLAS rounds small or narrow products in another order than wide ones:
    the columns go in blocks of ``_COLUMNS``, the last padded with zeros,
    so that every product has one shape whatever the number of columns.
    """
    k = q.shape[1]
    blocks = k // _COLUMNS
    full = blocks * _COLUMNS
    out = np.empty((w.shape[0], k))
    if blocks:
        # All full blocks in one stacked product: numpy calls BLAS once per
        # block, with the shapes and strides of a product per block (the
        # same bits), without a Python step per block.
        np.matmul(w, q[:, :full].reshape(q.shape[0], blocks, _COLUMNS).transpose(1, 0, 2),
                  out=out[:, :full].reshape(w.shape[0], blocks, _COLUMNS).transpose(1, 0, 2))
    if full < k:
        last = np.zeros((q.shape[0], _COLUMNS))
        last[:, :k - full] = q[:, full:]
        out[:, full:] = (w @ last)[:, :k - full]
    return out


#: Columns per matrix product in :func:`column_products`.
_COLUMNS = 256


def _contract(tensors, p: np.ndarray, alone: bool = False) -> list[np.ndarray]:
    """The polynomials with monomial tensors ``tensors`` (one shape) at the rows of p (K, 3).

    ``alone``: the x contraction row by row (stacked one-row products, as
    for K = 1), not as one matrix product of all rows.
    """
    nx, ny, nz = tensors[0].shape
    px, py, pz = powers(p[:, 0], nx), powers(p[:, 1], ny)[:, None, :], powers(p[:, 2], nz)
    out = []
    for coeffs in tensors:
        # Contract one variable at a time (a matrix product, then two
        # row-wise sums): einsum with '...' does not optimise the four-way product.
        if alone:
            t = np.matmul(px[:, None, :], coeffs.reshape(nx, ny * nz))[:, 0]  # (K, ny*nz)
        else:
            t = px @ coeffs.reshape(nx, ny * nz)  # (K, ny*nz)
        # Batched matrix products (BLAS), not einsum's slow generic loop.
        t = np.matmul(py, t.reshape(-1, ny, nz))[:, 0]  # (K, nz)
        out.append(np.einsum("kl,kl->k", t, pz))
    return out
