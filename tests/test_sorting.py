"""singmesh.sorting (issue #11): stable sorts by one plain sort of packed keys give
numpy's stable sorts entry for entry, on the keys the mesher sorts (lattice keys,
edge keys, root positions with ties, -0.0, NaN) and on keys too wide to pack."""

from __future__ import annotations

import numpy as np
import pytest

from singmesh import sorting


def _floats(rng, n):
    x = rng.normal(size=n) * 10.0 ** rng.integers(-20, 20, n)
    x[: n // 3] = np.round(x[: n // 3], 1)          # many ties
    x[rng.integers(0, n, n // 50)] = 0.0
    x[rng.integers(0, n, n // 50)] = -0.0           # tied with 0.0 in numpy's sorts
    x[rng.integers(0, n, n // 50)] = np.nan         # all tied, after every number
    x[rng.integers(0, n, n // 50)] = np.inf
    x[rng.integers(0, n, n // 50)] = -np.inf
    return x


@pytest.mark.parametrize("seed", range(6))
def test_lexsort_is_numpys(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 30000))
    ints = rng.integers(-50, 50, n)
    wide = rng.integers(-(1 << 62), 1 << 62, n)     # ranks, not offsets
    wide[: n // 2] = wide[n // 2: 2 * (n // 2)]
    small = rng.integers(0, 3, n).astype(np.int8)
    flags = rng.random(n) < 0.5
    x, y = _floats(rng, n), _floats(rng, n)
    for keys in [(x,), (ints,), (wide,), (x, ints), (small, x, ints), (y, x, ints), (flags, wide),
                 (ints, small), (x, y, wide, ints)]:  # the last too wide to pack: np.lexsort
        want = np.lexsort(keys)
        got = sorting.lexsort(keys)
        assert got.dtype.kind == "i" and np.array_equal(got, want), [k.dtype for k in keys]
    assert np.array_equal(sorting.stable_argsort(x), np.argsort(x, kind="stable"))
    assert np.array_equal(sorting.stable_argsort(wide), np.argsort(wide, kind="stable"))


def test_first_occurrences_and_unique_inverse_are_numpys():
    rng = np.random.default_rng(3)
    for n, hi in [(1, 5), (7, 3), (5000, 100), (40000, 1 << 55), (40000, 1 << 20)]:
        a = rng.integers(0, hi, n)
        a[: n // 2] = a[n // 2: 2 * (n // 2)][::-1]
        assert np.array_equal(sorting.first_occurrences(a), np.sort(np.unique(a, return_index=True)[1]))
        u, inv = sorting.unique_inverse(a)
        u0, inv0 = np.unique(a, return_inverse=True)
        assert np.array_equal(u, u0) and np.array_equal(inv, inv0)
    assert len(sorting.first_occurrences(np.zeros(0, np.int64))) == 0
    assert len(sorting.lexsort((np.zeros(0),))) == 0


@pytest.mark.parametrize("side", ["left", "right"])
def test_search_sorted_is_numpys(side):
    """sorting.search_sorted (the needles sorted first) is np.searchsorted entry for entry:
    lattice keys as the leaf look-ups give them (repeats, misses, ends), floats with NaN."""
    rng = np.random.default_rng(5)
    for n, k in [(10, 5), (300, 5000), (13752, 82512), (47262, 8073)]:
        hay = np.sort(rng.integers(0, 1 << 40, n))
        hay[: n // 10] = hay[0]  # repeats in the haystack
        needles = np.concatenate([rng.integers(-5, 1 << 41, k // 2), rng.choice(hay, k - k // 2)])
        assert np.array_equal(sorting.search_sorted(hay, needles, side), np.searchsorted(hay, needles, side=side))
    x = np.sort(_floats(rng, 2000))
    q = _floats(rng, 3000)
    assert np.array_equal(sorting.search_sorted(x, q, side), np.searchsorted(x, q, side=side))


def test_in_sorted_is_numpys_isin():
    """sorting.in_sorted (a binary search per needle in a sorted haystack) is np.isin entry
    for entry: lattice keys with repeats, misses beyond both ends, negative keys (singular
    points'), an empty haystack or no needles, 2-d needles, floats with -0.0."""
    rng = np.random.default_rng(8)
    for n, k in [(1, 5), (50, 300), (2000, 60000), (40000, 500)]:
        hay = np.unique(rng.integers(0, 1 << 30, n))
        needles = np.concatenate([rng.integers(-50, 1 << 31, k // 2), rng.choice(hay, k - k // 2)])
        assert np.array_equal(sorting.in_sorted(needles, hay), np.isin(needles, hay))
        grid = needles[: 2 * (k // 4)].reshape(2, -1)
        assert np.array_equal(sorting.in_sorted(grid, hay), np.isin(grid, hay))
    assert not sorting.in_sorted(np.arange(5), np.zeros(0, np.int64)).any()
    assert sorting.in_sorted(np.zeros(0, np.int64), np.arange(5)).shape == (0,)
    x = np.unique(rng.normal(size=50))
    q = np.concatenate([x[::3], rng.normal(size=20), [0.0, -0.0]])
    x = np.sort(np.concatenate([x, [0.0]]))
    assert np.array_equal(sorting.in_sorted(q, x), np.isin(q, x))
