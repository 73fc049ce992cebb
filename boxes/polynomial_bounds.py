"""The box methods of a polynomial surface: Bernstein forms on stacked boxes.

:class:`singmesh.surface.PolynomialSurface` delegates its bounds on boxes
(the ``data`` of the surface interface) here.  Its ``data`` is the stack of
Bernstein tensors ``(N, n0+1, n1+1, n2+1)`` of F on the boxes
(:mod:`singmesh.boxes.bernstein`); the convex-hull property makes every
test below a certainty about F on the whole closed box, up to the slacks
that allow for rounding.

A box is *simple* when the surface in it is a union of discs, each bounded
by one cycle of face links.  The test used: some partial derivative F_a is
of one sign on the box (so each line parallel to axis a meets the surface
at most once and the surface is a graph over the faces normal to a), and on
both faces normal to a the face curve has no closed loop (a tangential
derivative of one sign there, or no curve at all).  A hole in the graph's
domain would be bounded by a closed loop of the top or bottom face curve,
because the two face curves cannot cross when F is monotone along a;
excluding such loops leaves discs.
"""

from __future__ import annotations

import numpy as np

from singmesh import tolerances as tol

from .bernstein import derivative, sign_definite


def empty_boxes(tensors: np.ndarray) -> np.ndarray:
    """Boxes where F certainly has no zero: all coefficients > slack, or all < -slack.

    The slack (``PRUNE_SLACK`` of the largest coefficient) keeps boxes where
    F may vanish up to rounding, e.g. exactly at a corner: pruning such a
    box would leave a hole in the faces that carry the events found there.
    """
    # F of both signs at the corners: not empty, without the pass over all
    # coefficients (half of a subdivision's children meet the surface, and
    # nearly all of those cross it between two corners).
    out = np.zeros(len(tensors), bool)
    rest = np.flatnonzero(~mixed_corners(tensors))
    if len(rest) == 0:
        return out
    flat = tensors[rest].reshape(len(rest), -1)
    lo, hi = flat.min(axis=1), flat.max(axis=1)
    # max |c| is max(hi, -lo) to the bit: no pass over |flat|.
    slack = tol.PRUNE_SLACK * np.maximum(hi, -lo)
    out[rest] = (lo > slack) | (hi < -slack)
    return out


def mixed_corners(tensors: np.ndarray) -> np.ndarray:
    """Boxes whose Bernstein coefficients at the box's corners (F's values
    there) take both strict signs.

    Then the least coefficient is below 0 and the largest above 0: F
    vanishes on the box, and a test of the coefficients against a slack of
    at least 0 passes or fails as on all of them, read from 8 coefficients
    per box instead of all.

    Returns
    -------
    (N,) bool
    """
    # The corners laid out as rows of all boxes (8, N): the signs are then
    # whole-row comparisons, not a reduction call per box of 8 values.  They
    # are gathered as columns of the boxes' flat coefficients (a take of 8
    # indices per row, then one transposed copy): copying the strided view
    # of the corners took seven times as long.
    shape = tensors.shape[1:]
    ends = [sorted({0, n - 1}) for n in shape]
    index = [g.ravel() for g in np.meshgrid(*ends, indexing="ij")]
    if tensors.flags.c_contiguous and len(tensors):
        picked = tensors.reshape(len(tensors), -1)[:, np.ravel_multi_index(index, shape)]
    else:
        picked = tensors[(slice(None),) + tuple(index)]
    rows = np.ascontiguousarray(picked.T)
    return (rows < 0).any(axis=0) & (rows > 0).any(axis=0)


def face_without_loops(face: np.ndarray) -> np.ndarray:
    """Whether the curve F + eps = 0 on stacked faces (N, a, b) has no closed loop.

    True when a tangential derivative is of one sign (the curve is a graph)
    or when there is no curve at all.
    """
    # The faces along the last axis (see _definite_last): 3.5x faster on
    # Barth's 5 x 5 faces, the same answers (minima and maxima are exact).
    face = np.ascontiguousarray(np.moveaxis(face, 0, -1))
    flat = face.reshape(face.shape[0] * face.shape[1], face.shape[2])
    return (
        _definite_last(np.diff(face, axis=0))
        | _definite_last(np.diff(face, axis=1))
        | (flat.min(axis=0) >= 0)
        | (flat.max(axis=0) < 0)
    )


def monotone_axis(tensors: np.ndarray) -> np.ndarray:
    """First axis a for which the box passes the simplicity test, else -1."""
    result = np.full(len(tensors), -1, dtype=np.int64)
    todo = np.arange(len(tensors))
    for a in range(3):
        # Each axis only on the boxes no earlier axis passed.
        t = tensors if len(todo) == len(tensors) else tensors[todo]
        ok = sign_definite(derivative(t, a), (1, 2, 3))
        k = np.flatnonzero(ok)
        if len(k):
            # Both end faces normal to a of the boxes that passed, gathered
            # at once as (K, 2, u, v) (not each box's whole tensor, twice),
            # and tested in one call.
            index = [k[:, None], slice(None), slice(None), slice(None)]
            index[1 + a] = np.array([0, tensors.shape[1 + a] - 1])
            ends = t[tuple(index)]
            loopless = face_without_loops(ends.reshape((2 * len(k),) + ends.shape[2:])).reshape(len(k), 2)
            ok[k] = loopless[:, 0] & loopless[:, 1]
        result[todo[ok]] = a
        todo = todo[~ok]
        if len(todo) == 0:
            break
    return result


def face_modes(tensors: np.ndarray, n: int, side: np.ndarray, rows: np.ndarray | None = None) -> np.ndarray:
    """How the curve F = 0 lies on one face normal to axis ``n`` of each box.

    Parameters
    ----------
    tensors : (N, n0+1, n1+1, n2+1) ndarray
    n : int
        The face's normal axis; its tangential axes are u = (n+1)%3, v = (n+2)%3.
    side : (N,) int
        0 for each box's low face, 1 for its high face.
    rows : (K,) int64, optional
        Only the boxes ``tensors[rows]`` (``side`` and the result (K,) are theirs).

    Returns
    -------
    (N,) int64
        0: a graph over u (F_v of one sign); 1: over v (F_u of one sign);
        2: neither is known.
    """
    # Gather the face's slice only, not the boxes' whole tensors.
    index = [np.arange(len(tensors)) if rows is None else np.asarray(rows, np.int64),
             slice(None), slice(None), slice(None)]
    index[1 + n] = np.where(np.asarray(side) == 1, tensors.shape[1 + n] - 1, 0)
    face = tensors[tuple(index)]
    if n == 1:  # the remaining axes are (x, z) = (v, u)
        face = np.swapaxes(face, 1, 2)
    # The faces along the last axis, (u, v, K): the minima and maxima of
    # the differences are then taken across whole rows (elementwise), not
    # along the few coefficients of each face (a reduction call per face).
    face = np.ascontiguousarray(np.moveaxis(face, 0, -1))
    over_u = _definite_last(np.diff(face, axis=1))  # F_v of one sign
    mode = np.where(over_u, 0, 2).astype(np.int64)
    # F_u only where F_v is not of one sign.
    rest = np.nonzero(~over_u)[0]
    if len(rest):
        over_v = _definite_last(np.diff(face[..., rest], axis=0))  # F_u of one sign
        mode[rest[over_v]] = 1
    return mode


def _definite_last(coeffs: np.ndarray) -> np.ndarray:
    """:func:`sign_definite <singmesh.boxes.bernstein.sign_definite>` over all axes but the last."""
    if coeffs.size == 0:
        # F has degree 0 in that variable: the derivative is identically 0.
        return np.zeros(coeffs.shape[-1], dtype=bool)
    flat = coeffs.reshape(coeffs.size // coeffs.shape[-1], coeffs.shape[-1])
    lo, hi = flat.min(axis=0), flat.max(axis=0)
    return ((lo >= 0) & (hi > 0)) | ((hi <= 0) & (lo < 0))


def may_vanish(tensors: np.ndarray, axes, dust: float) -> np.ndarray:
    """Boxes on which F and its partial derivatives along ``axes`` may all vanish.

    The Bernstein forms of the derivatives are differences of F's (up to a
    positive factor): no conversion and no split.  The derivatives are
    tested first, then F, each on the boxes still kept only (the answer is
    each box's tests and-ed, in any order: the derivatives first, as each
    drops as many boxes as F does on a tensor a seventh smaller, cost less).
    A derivative along an axis F does not depend on is zero: no test.  Coefficients within
    ``CANDIDATE_SLACK`` of the box's largest, or within ``dust`` (the
    rounding left by splitting from the root box), count as zero: exact
    zeros at box corners come out of the conversion as +-1e-17.

    Returns
    -------
    (N,) bool
    """
    live = np.arange(len(tensors))
    t = tensors
    for a in [a for a in axes if t.shape[1 + a] > 1] + [None]:
        if len(live) == 0:
            break
        c = t if a is None else derivative(t, a)
        flat = c.reshape(len(c), -1)
        lo, hi = flat.min(axis=1), flat.max(axis=1)
        slack = np.maximum(tol.CANDIDATE_SLACK * np.maximum(hi, -lo), dust)
        keep = (lo <= slack) & (hi >= -slack)
        if not keep.all():
            t, live = t[keep], live[keep]
    out = np.zeros(len(tensors), bool)
    out[live] = True
    return out
