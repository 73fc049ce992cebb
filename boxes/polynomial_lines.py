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
from singmesh.monomials import column_products, power_rows


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
    row, root = real_roots(_rescale(poly, centre, half), 1.0, repeats=_mirrored(coeffs, axis))
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
    n, nu, nv = t.shape
    fixed = np.asarray(fixed, dtype=float).reshape(-1, 2)
    # The products u^j v^k of each line as one (nu nv, L) table against the
    # tensor in one matrix product (each line's bits independent of the
    # others'): a tenth of the time of einsum's three-way product.
    pu, pv = power_rows(fixed[:, 0], nu), power_rows(fixed[:, 1], nv)
    q = (pu[:, None, :] * pv[None, :, :]).reshape(nu * nv, -1)
    return np.ascontiguousarray(column_products(np.ascontiguousarray(t).reshape(n, nu * nv), q).T)


def _rescale(poly: np.ndarray, centre: np.ndarray, half: np.ndarray) -> np.ndarray:
    """Coefficients in tau where s = centre + half * tau (rows independent)."""
    n = poly.shape[1] - 1
    i = np.arange(n + 1)[:, None]
    j = np.arange(n + 1)[None, :]
    # coefficient of tau^j: sum_i c_i C(i, j) centre^(i-j) half^j; the
    # n + 1 powers of each centre once (not one per (i, j)), the same values.
    powers = centre[:, None] ** np.arange(n + 1)
    m = np.where(i >= j, comb(i, j) * powers[:, np.maximum(i - j, 0)], 0.0)
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


def _mirrored(coeffs: np.ndarray, axis: int) -> bool:
    """Whether F (monomial tensor) is even or odd under a change of sign of one or both of
    the coordinates across ``axis``: then the lines at (u, v) and their mirror images
    carry the same polynomial up to sign (:func:`real_roots` looks for copies)."""
    ua, va = (axis + 1) % 3, (axis + 2) % 3
    t = np.moveaxis(coeffs, (axis, ua, va), (0, 1, 2))
    su = (-1.0) ** np.arange(t.shape[1])[None, :, None]
    sv = (-1.0) ** np.arange(t.shape[2])[None, None, :]
    for sign in (su, sv, su * sv):
        flipped = t * sign
        if np.array_equal(flipped, t) or np.array_equal(flipped, -t):
            return True
    return False


def real_roots(tau_poly: np.ndarray, bound: float, repeats: bool = True):
    """Real roots in [-bound, bound] of stacked polynomials in tau.

    Roots are found as companion-matrix eigenvalues (all of them, so none
    is missed between sign samples), kept when nearly real, and polished by
    Newton's method.  Equal rows (bit for bit: the lines of a surface
    symmetric in a coordinate plane, in pairs to eights) are solved once:
    every step is a function of the row alone (LAPACK solves each matrix
    alone, Newton's steps are elementwise), so each copy gets the bits its
    own solve would give, in the order of the rows.

    ``repeats``: look for equal rows (False: none are expected, as on the
    lines of a surface without mirror symmetry across them, and the search,
    a sort of the rows' hashes, is skipped).

    Returns
    -------
    row : (R,) int64, root : (R,) float64
        By effective degree, then row, each row's roots in the order of its
        eigenvalues.
    """
    distinct = _distinct_rows(tau_poly) if repeats else None
    if distinct is None:
        return _real_roots(tau_poly, bound, repeats)
    first, inverse = distinct
    row_d, root_d = _real_roots(tau_poly[first], bound, repeats)
    # Each distinct row's roots are consecutive: where they start.
    count = np.bincount(row_d, minlength=len(first))
    start = np.zeros(len(first), np.int64)
    if len(row_d):
        run = np.concatenate([[True], row_d[1:] != row_d[:-1]])
        start[row_d[run]] = np.flatnonzero(run)
    # The rows with roots, by degree then row (_real_roots's order).
    each = count[inverse]
    order = np.argsort(_degrees(tau_poly[first])[inverse], kind="stable")
    order = order[each[order] > 0]
    n = each[order]
    row = np.repeat(order, n)
    at = np.repeat(start[inverse[order]] - (np.cumsum(n) - n), n) + np.arange(int(n.sum()))
    return row, root_d[at]


def _degrees(tau_poly: np.ndarray) -> np.ndarray:
    """Effective degree of each row: leading coefficients under 1e-13 of the
    largest dropped (the roots they would add lie far outside [-1, 1])."""
    scale = np.abs(tau_poly).max(axis=1)
    significant = np.abs(tau_poly) > 1e-13 * scale[:, None]
    return np.where(significant.any(axis=1),
                    tau_poly.shape[1] - 1 - np.argmax(significant[:, ::-1], axis=1), 0)


def _real_roots(tau_poly: np.ndarray, bound: float, repeats: bool = True):
    """:func:`real_roots` of every row (``repeats``: look for matrices equal up to a factor)."""
    rows, roots = [], []
    scale = np.abs(tau_poly).max(axis=1)
    nonzero = scale > 0
    degree = _degrees(tau_poly)
    for d in np.unique(degree[nonzero]):
        if d < 1:
            continue
        sel = np.nonzero(nonzero & (degree == d))[0]
        if bound == 1.0 and d >= 3:
            # No eigenvalue of these could be kept (a quarter of a surface's
            # lines): LAPACK solves each matrix alone, so the others' are
            # the same without them.  (Quadratics cost less than the test.)
            sel = sel[~_far_from_zero(tau_poly[sel, : d + 1])]
            if len(sel) == 0:
                continue
        c = tau_poly[sel, : d + 1] / tau_poly[sel, d : d + 1]
        comp = np.zeros((len(sel), d, d))
        comp[:, np.arange(1, d), np.arange(d - 1)] = 1.0
        comp[:, :, -1] = -c[:, :d]
        eig = _eigvals_of_distinct(comp, c[:, :d]) if repeats else np.linalg.eigvals(comp)
        near = (np.abs(eig.imag) <= tol.ROOT_IMAG) & (np.abs(eig.real) <= bound)
        r, k = np.nonzero(near)
        rows.append(sel[r])
        roots.append(eig.real[r, k])
    if not rows:
        return np.zeros(0, np.int64), np.zeros(0)
    row = np.concatenate(rows)
    root = np.concatenate(roots)
    # A root that a step leaves unchanged (to the bit) stays so at every
    # later step (a step is a function of the root): only the others go on.
    # Likewise a root that a step takes back to where it was the step
    # before swings between those two values to the last step (a tenth of
    # a surface's roots, whose two neighbouring floats both leave |p| at
    # its rounding): it takes the one the last step would leave at once.
    active = np.arange(len(root))
    coeffs = tau_poly[row]
    before = root.copy()  # each active root before the last step
    for it in range(tol.NEWTON_ITERATIONS):
        c, r = coeffs[active], root[active]
        p, dp = _horner(c, r)
        ok = np.abs(dp) > 0
        step = np.where(ok, p / np.where(ok, dp, 1.0), 0.0)
        # Near a multiple root Newton may overshoot: accept only steps that
        # do not increase |p|.
        trial = r - step
        pt, _ = _horner(c, trial)
        better = np.abs(pt) <= np.abs(p)
        new = np.where(better, trial, r)
        moved = new.view(np.int64) != r.view(np.int64)
        swing = moved & (new.view(np.int64) == before[active].view(np.int64)) if it else np.zeros(len(r), bool)
        # The steps left alternate r and new: an even number of them ends on new.
        last = new if (tol.NEWTON_ITERATIONS - 1 - it) % 2 == 0 else r
        root[active] = np.where(swing, last, new)
        before[active] = r
        active = active[moved & ~swing]
        if len(active) == 0:
            break
    return row, root


def _distinct_rows(key: np.ndarray):
    """(first, inverse) of the distinct rows of ``key`` (N, k), bit for bit: ``key[first]``
    the distinct rows, ``key[first][inverse]`` is ``key``; None when all rows differ.

    Rows are told apart by a hash of their bits, sorted (on rows without
    copies that costs a sort of N integers); a row is a copy of the one
    before it in that order when both hashes and bits are equal.
    """
    n = len(key)
    if n < 2:
        return None
    bits = np.ascontiguousarray(key).view(np.int64).reshape(n, -1)
    if bits.shape[1] == 0:
        return None
    h = bits[:, 0] * _HASH[0]
    for j in range(1, bits.shape[1]):
        h ^= bits[:, j] * _HASH[j % len(_HASH)]  # (products wrap: a hash)
    if not (np.diff(np.sort(h)) == 0).any():
        return None
    order = np.argsort(h, kind="stable")
    s = bits[order]
    copy = (h[order][1:] == h[order][:-1]) & (s[1:] == s[:-1]).all(axis=1)
    new = np.concatenate([[True], ~copy])
    inverse = np.empty(n, np.int64)
    inverse[order] = np.cumsum(new) - 1
    return order[new], inverse


def _eigvals_of_distinct(matrices: np.ndarray, key: np.ndarray) -> np.ndarray:
    """``np.linalg.eigvals(matrices)``, each distinct matrix solved once.

    ``key`` (N, k) tells the matrices apart: equal rows, bit for bit, are
    equal matrices (:func:`_distinct_rows`).  LAPACK solves each matrix
    alone, so the copies get the bits of the first (and the result is real
    exactly where it was).  :func:`real_roots` solves equal polynomials
    once already; this finds the polynomials equal up to a factor.
    """
    distinct = _distinct_rows(key)
    if distinct is None:
        return np.linalg.eigvals(matrices)
    first, inverse = distinct
    return np.linalg.eigvals(matrices[first])[inverse]


#: Odd 64-bit multipliers (splitmix64's and xxhash's constants) for the
#: hash of :func:`_eigvals_of_distinct`.
_HASH = np.array([0x9E3779B97F4A7C15, 0xC2B2AE3D27D4EB4F, 0x165667B19E3779F9, 0x85EBCA77C2B2AE63,
                  0x27D4EB2F165667C5, 0x94D049BB133111EB, 0xBF58476D1CE4E5B9, 0xFF51AFD7ED558CCD],
                 dtype=np.uint64).view(np.int64)


def _far_from_zero(poly: np.ndarray) -> np.ndarray:
    """Polynomials (rows, lowest power first, the last coefficient not 0) with no root that
    :func:`real_roots` could keep on [-1, 1]: |p| is larger on [-1, 1] than any such root allows.

    A kept root z = a + ib (|a| <= 1, |b| <= ``ROOT_IMAG``) computed as an
    eigenvalue of the companion matrix is an exact root of a polynomial
    whose coefficients differ from p's by the backward error of the
    eigenvalues (at most ~ n^3 eps (sum |c|)^2 / |c_d| in p's scale: here
    ``ROOT_FREE_BACKWARD`` of it, a 1e5-fold margin), so |p(a)| <= that + |b| max |p'|, and
    max |p'| <= sum k |c_k| (1 + |b|)^(k - 1).  The minimum of |p| on
    [-1, 1] is bounded below by its Bernstein coefficients (convex hull),
    less their rounding.
    """
    n = poly.shape[1] - 1
    a = np.abs(poly)
    total = a.sum(axis=1)
    allowed = (2.0 * tol.ROOT_IMAG * (a * np.arange(n + 1)).sum(axis=1)
               + tol.ROOT_FREE_BACKWARD * total * total / a[:, n] + tol.ROOT_FREE_ROUNDING * total * 2.0 ** n)
    # On ROOT_FREE_PIECES equal pieces of [-1, 1] (one hull over the whole
    # segment is too loose: the segment is a line's whole extent through the leaves).
    b = (poly @ _bernstein_of_tau(n)).reshape(len(poly), tol.ROOT_FREE_PIECES, n + 1)
    lo, hi = b.min(axis=(1, 2)), b.max(axis=(1, 2))
    return (lo > allowed) | (hi < -allowed)


_TO_BERNSTEIN: dict = {}


def _bernstein_of_tau(n: int) -> np.ndarray:
    """(n+1, PIECES (n+1)) M with ``poly @ M`` the Bernstein coefficients, on each of
    the ``ROOT_FREE_PIECES`` equal pieces of [-1, 1], of power coefficients in tau."""
    pieces = tol.ROOT_FREE_PIECES
    if (n, pieces) not in _TO_BERNSTEIN:
        k = np.arange(n + 1)
        # b_i = sum_{j <= i} C(i, j) / C(n, j) a_j from power coefficients a in u on [0, 1].
        to_b = np.where(k[:, None] <= k[None, :], comb(k[None, :], k[:, None]) / comb(n, k[:, None]), 0.0)
        blocks = []
        w = 2.0 / pieces
        for piece in range(pieces):
            t0 = -1.0 + piece * w
            # shift[kk, j]: coefficient of u^j in (t0 + w u)^kk
            shift = np.zeros((n + 1, n + 1))
            for kk in range(n + 1):
                j = np.arange(kk + 1)
                shift[kk, : kk + 1] = comb(kk, j) * t0 ** (kk - j) * w ** j
            blocks.append(shift @ to_b)
        _TO_BERNSTEIN[n, pieces] = np.concatenate(blocks, axis=1)
    return _TO_BERNSTEIN[n, pieces]
