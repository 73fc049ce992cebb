"""Stable sorts of integer and float keys by one plain sort of packed integers.

``np.lexsort`` and ``np.argsort(kind="stable")`` are merge sorts, some ten
times slower than numpy's plain sort of int64 values (a vectorised quick
sort) on the 10^4-10^5 keys of a mesh.  Where every key fits in a few bits
(each replaced by its rank, or by its offset from its minimum) the keys and
the position of each entry pack into one int64 per entry: all packed values
differ, so the plain sort's order is the stable order, entry for entry the
one ``np.lexsort`` gives.  Keys too wide to pack go to ``np.lexsort``.
"""

from __future__ import annotations

import numpy as np

#: Bits of an int64 that packed keys may use (the sign bit stays 0).
_BITS = 63


def _order_key(a: np.ndarray) -> tuple[np.ndarray, int]:
    """Non-negative int64 values ordered and tied as ``a`` is in numpy's sorts, and their bound.

    Integers: their offsets from the minimum, where the range is small
    (no sort); else their dense ranks.  Floats: their dense ranks, -0.0
    tied with 0.0 and every NaN tied with every other, after all numbers
    (numpy's sort order).
    """
    if a.dtype.kind in "ib" or (a.dtype.kind == "u" and a.dtype.itemsize < 8):
        a = a.astype(np.int64, copy=False)
        lo, hi = int(a.min()), int(a.max())
        if hi - lo < (1 << 40):
            return a - lo, hi - lo + 1
    order = np.argsort(a)
    s = a[order]
    change = s[1:] != s[:-1]
    if a.dtype.kind == "f":
        change &= ~(np.isnan(s[1:]) & np.isnan(s[:-1]))  # NaN != NaN, but sorts tie them
    rank = np.empty(len(a), np.int64)
    rank[order] = np.concatenate([[0], np.cumsum(change)])
    return rank, int(rank[order[-1]]) + 1


def lexsort(keys) -> np.ndarray:
    """``np.lexsort(keys)`` (the last key primary, ties kept in order), entry for entry.

    Parameters
    ----------
    keys : sequence of (N,) arrays, integer, bool or float

    Returns
    -------
    (N,) int64 indices
    """
    keys = [np.asarray(k) for k in keys]
    n = len(keys[0]) if keys else 0
    if n < 2 or any(k.ndim != 1 or k.dtype.kind not in "iubf" for k in keys):
        return np.lexsort(keys) if keys else np.zeros(0, np.int64)
    index_bits = (n - 1).bit_length()
    packed = np.zeros(n, np.int64)
    used = index_bits
    for k in reversed(keys):  # the primary key first, in the highest bits
        value, bound = _order_key(k)
        bits = (bound - 1).bit_length()
        used += bits
        if used > _BITS:
            return np.lexsort(keys)
        if bits:
            packed <<= bits
            packed |= value
    packed <<= index_bits
    packed |= np.arange(n)
    packed.sort()
    return packed & ((1 << index_bits) - 1)


def stable_argsort(a: np.ndarray) -> np.ndarray:
    """``np.argsort(a, kind="stable")`` of a 1-d integer, bool or float array, entry for entry."""
    return lexsort([a])


def first_occurrences(a: np.ndarray) -> np.ndarray:
    """The index of the first entry of each distinct value of ``a``, in increasing order:
    ``np.sort(np.unique(a, return_index=True)[1])``."""
    a = np.asarray(a)
    if len(a) == 0:
        return np.zeros(0, np.int64)
    if a.dtype.kind not in "iub":
        return np.sort(np.unique(a, return_index=True)[1])
    # Any order of equal values (a plain sort): the first of each is the
    # least index among them.
    order = np.argsort(a)
    s = a[order]
    start = np.flatnonzero(np.concatenate([[True], s[1:] != s[:-1]]))
    return np.sort(np.minimum.reduceat(order, start))


def unique_inverse(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``np.unique(a, return_inverse=True)`` of a 1-d integer array."""
    a = np.asarray(a)
    if len(a) == 0 or a.dtype.kind not in "iu":
        return np.unique(a, return_inverse=True)
    order = stable_argsort(a)
    s = a[order]
    new = np.concatenate([[True], s[1:] != s[:-1]])
    inverse = np.empty(len(a), np.int64)
    inverse[order] = np.cumsum(new) - 1
    return s[new], inverse


#: Fewer needles than this go to ``np.searchsorted`` as they are.
_FEW_NEEDLES = 256


def search_sorted(a: np.ndarray, v: np.ndarray, side: str = "left") -> np.ndarray:
    """``np.searchsorted(a, v, side)`` for a 1-d ``v``, entry for entry, with the needles sorted first.

    A binary search per needle in random order misses the cache at every
    step; in increasing order the steps of one needle follow those of the
    one before (numpy also starts each search from the last result): on
    10^4-10^5 needles the sort costs a fraction of what it saves (Barth's
    leaf look-ups: ~8x).  Each needle's position does not depend on the
    others'.
    """
    v = np.asarray(v)
    if v.ndim != 1 or len(v) < _FEW_NEEDLES or len(a) < _FEW_NEEDLES:
        return np.searchsorted(a, v, side=side)
    order = np.argsort(v)
    out = np.empty(len(v), np.intp)
    out[order] = np.searchsorted(a, v[order], side=side)
    return out


def in_sorted(v: np.ndarray, a: np.ndarray) -> np.ndarray:
    """``np.isin(v, a)`` for a sorted 1-d ``a``: whether each entry of ``v`` occurs in ``a``.

    A binary search per entry (:func:`search_sorted`) instead of
    ``np.isin``'s sort of both arrays together: the haystack is sorted
    already, and only the needles' order is sorted out.
    """
    v = np.asarray(v)
    a = np.asarray(a)
    if len(a) == 0 or v.size == 0:
        return np.zeros(v.shape, bool)
    flat = v.ravel()
    pos = np.minimum(search_sorted(a, flat), len(a) - 1)
    return (a[pos] == flat).reshape(v.shape)
