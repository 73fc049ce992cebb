"""Singular points: where F and all three partial derivatives vanish.

1. Candidate boxes: subdivide the domain with the surface's bounds on
   boxes (stacked arrays, whole-level operations; a polynomial's Bernstein
   forms) and keep a box only while F, Fx, Fy, Fz may all vanish on it.
2. Gauss-Newton on (F, Fx, Fy, Fz) from every candidate box centre, all at
   once in double precision.
3. Each distinct end point is classified and, if degenerate (A2 and
   beyond, D, E: fixed only to about eps**(1/(k+1)) by Newton, and not a
   singular point at all of a polynomial with rounded coefficients), moved
   to the centre of its singular point (:mod:`singmesh.skeleton.centre`).
4. A point is singular when F and grad F vanish there to the precision of
   the input (:func:`accept_residual`); the centres are deduplicated.
   Points on a curve of singular points (infinite Milnor number) are not
   returned as points: the flag says they were seen.
"""

from __future__ import annotations

import weakref

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from singmesh import tolerances as tol
from singmesh.errors import SurfaceError
from singmesh.surface import CHILD_OFFSETS, Surface

from .centre import centre, residual, residual_each
from .classify import NotSingularError, analyse_each
from .points import SingularPoint
from .swing import Swing


#: Per surface (while it lives): the last candidate boxes of each box and
#: axes searched, with their data, for a deeper search to go on from.
_KEPT: "weakref.WeakKeyDictionary[Surface, dict]" = weakref.WeakKeyDictionary()


def candidate_boxes(surface: Surface, box: np.ndarray, level: int, axes=(0, 1, 2),
                    near: tuple[np.ndarray, float] | None = None):
    """Boxes at ``level`` on which F and its partial derivatives along ``axes`` may all vanish.

    The surface's bounds on boxes decide (``Surface.enclose``, ``split``,
    ``may_vanish``).  Boxes are refined level by level as stacked arrays,
    at most ``CANDIDATE_CHUNK`` at a time (a curve of singular points or
    hundreds of nodes make many), so memory stays bounded and nothing is
    dropped.

    Parameters
    ----------
    near : ((k, 3) ndarray, float), optional
        Points and a radius: only boxes meeting the balls round them are
        searched (a deeper look at a few places).  Such a search neither
        uses up nor keeps the boxes a whole search goes on from.

    Returns
    -------
    lo, hi : (K, 3) ndarrays, the boxes' corners, sorted
    """
    # Enclosed even when a kept search goes on: the surface's tests may
    # depend on the root box (a polynomial's rounding dust).
    box = np.asarray(box, dtype=float)
    root = surface.enclose(box)
    todo = [(root, np.zeros((1, 3), np.int64), 0)]
    key = (box.tobytes(), tuple(axes))
    kept = _KEPT.get(surface, {})
    if key in kept and kept[key][0] <= level:
        # The boxes an earlier, shallower search of the same surface and box
        # ended with (the curve search's): the deeper one goes on from them.
        todo = [(kept[key][1], kept[key][2], kept[key][0])]
        if near is None:
            del kept[key]
    ends = []
    out = []
    offsets = CHILD_OFFSETS  # child c of a split box: Surface.split's order
    while todo:
        d, corner, lvl = todo.pop()
        if len(corner):
            keep = surface.may_vanish(d, tuple(axes))
            if near is not None:
                keep &= _meets_balls(box, corner, lvl, *near)
            if not keep.all():
                d, corner = d[keep], corner[keep]
        if len(corner) == 0:
            continue
        if lvl == level:
            out.append(corner)
            ends.append(d)
            continue
        for part in range(0, len(corner), tol.CANDIDATE_CHUNK):
            sl = slice(part, part + tol.CANDIDATE_CHUNK)
            children = surface.split(d[sl])  # (n, 8, ...)
            todo.append((children.reshape((-1,) + children.shape[2:]),
                         (2 * corner[sl, None, :] + offsets[None]).reshape(-1, 3), lvl + 1))
    if not out:
        return np.zeros((0, 3)), np.zeros((0, 3))
    if near is None and sum(d.nbytes for d in ends) <= tol.CANDIDATE_KEEP_BYTES:
        _KEPT.setdefault(surface, {})[key] = (level, np.concatenate(ends), np.concatenate(out))
    corner = np.concatenate(out)
    corner = corner[np.lexsort(corner.T[::-1])]
    return _corners(box, corner, level)


def _meets_balls(box: np.ndarray, corner: np.ndarray, level: int, centres: np.ndarray,
                 radius: float) -> np.ndarray:
    """Which boxes of ``level`` (integer corners) come within ``radius`` of a centre."""
    from scipy.spatial import cKDTree

    lo, hi = _corners(box, corner, level)
    # The distance from the box's centre less its half diagonal: never more
    # than the distance from the box.
    d, _ = cKDTree(centres).query((lo + hi) / 2)
    return d <= radius + 0.5 * float(np.linalg.norm(hi[0] - lo[0])) if len(lo) else np.zeros(0, bool)


def _corners(box, corner, level):
    h = (box[:, 1] - box[:, 0]) / (1 << level)
    lo = box[:, 0] + corner * h
    return (lo, lo + h)


def gauss_newton(surface: Surface, x: np.ndarray, iterations: int = 40,
                 max_step: float | None = None, across: np.ndarray | None = None,
                 rcond: float = 1e-12) -> np.ndarray:
    """Least-squares Newton on (F, grad F) = 0 from many starts at once.

    With ``max_step``, steps longer than that are shortened to it; with
    ``across`` (a unit vector, or one per start), steps have no component
    along it; ``rcond``: singular values of the Jacobian below this
    fraction of the largest are cut.  A start stops once its step is at rounding level (it would
    only jitter in the last bits): hundreds of nodes converge in a few
    steps, and only the slow ones (degenerate points) go on.
    """
    x = np.array(x, dtype=float)
    if across is not None:
        across = np.broadcast_to(np.asarray(across, dtype=float), x.shape)
    live = np.arange(len(x))
    swing = Swing(iterations)
    for _ in range(iterations):
        if len(live) == 0:
            break
        last = swing.cycle(live, x[live])
        if last is not None:
            x[live] = last  # the live starts alternate between two values to the end
            break
        y = x[live]
        f, g, h = surface.jet(y)
        r = np.concatenate([f[:, None], g], axis=1)  # (K, 4)
        j = np.concatenate([g[:, None, :], h], axis=1)  # (K, 4, 3)
        # A start that left F's domain or overflowed (exp of a large
        # argument) has no step: it becomes NaN and stops.
        finite = np.isfinite(j).all(axis=(1, 2)) & np.isfinite(r).all(axis=1)
        if across is not None:
            # Least squares in the plane across: the Jacobian's columns
            # projected onto it.  (A step of the whole space with its part
            # along ``across`` dropped does not converge where the curve's
            # tangent is not ``across``: near it the step along the tangent
            # is large, and its remainder across is not small.)
            a = across[live]
            j = j - np.einsum("kij,kj,kl->kil", j, a, a)
        if finite.all():
            step = np.einsum("kij,kj->ki", np.linalg.pinv(j, rcond=rcond), r)
        else:
            step = np.full(r.shape[:1] + (3,), np.nan)
            step[finite] = np.einsum("kij,kj->ki", np.linalg.pinv(j[finite], rcond=rcond), r[finite])
        if across is not None:
            a = across[live]
            step = step - np.einsum("ki,ki->k", step, a)[:, None] * a
        if max_step is not None:
            length = np.linalg.norm(step, axis=1, keepdims=True)
            step = step * np.minimum(1.0, max_step / np.maximum(length, 1e-300))
        new = y - step
        # A coordinate of a root at 0 (a point on a symmetry plane) falls by
        # about eps per step (the rounding of the others' residuals): Barth's
        # nodes at (-1, 0, 0) went 1e-24, 1e-55, ... and reached 0 by
        # underflow 20 steps later.  Below NEWTON_ZERO of the point's
        # largest coordinate it is that 0 now.
        tiny = np.abs(new) <= tol.NEWTON_ZERO * np.abs(new).max(axis=1, keepdims=True)
        new[tiny] = 0.0
        x[live] = new
        # Converged: each coordinate's step is below a few of its ulps.  A
        # coordinate going to 0 goes on until it is 0; NaN steps stay live
        # and stay NaN, as before.
        moving = ~np.all(np.abs(step) <= tol.NEWTON_STILL * np.abs(y), axis=1)
        live = live[moving & finite]
    return x


def accept_residual(surface: Surface) -> float:
    """The relative residual (:func:`residual`) below which a point is singular.

    ``SINGULAR_RESIDUAL`` for exact input; for rounded coefficients what
    their rounding allows (``INPUT_ROUNDING * degree * rounding``): a point
    singular to the precision of the input is singular.
    """
    return max(tol.SINGULAR_RESIDUAL, tol.INPUT_ROUNDING * surface.degree * surface.rounding)


def singular_points(surface: Surface, box, level: int = 8, avoid: np.ndarray | None = None,
                    avoid_radius: float = 0.0, on_radius: float = 0.0) -> tuple[list[SingularPoint], bool]:
    """Isolated singular points of F = 0 in ``box``.

    Parameters
    ----------
    surface : Surface
    box : (3, 2) array_like
    level : int
        Depth of the candidate search (``2**level`` boxes per axis).
    avoid : (k, 3) ndarray, optional
        Points of curves of singular points already traced, no further
        apart than ``on_radius``: candidate boxes within ``avoid_radius`` of
        them are not tested for curves again, and Newton ends within
        ``on_radius`` of them are points of those curves.  Ends off them (a
        point of F beside a curve) are isolated points as anywhere else.
    avoid_radius, on_radius : float

    Returns
    -------
    points : list of SingularPoint, sorted by coordinates, classified
    not_isolated : bool
        True when some candidate boxes form a long chain (a curve of
        singular points), or the classifier finds an infinite Milnor number
        at a point; those are not in ``points``.
    """
    box = np.asarray(box, dtype=float)
    first_level = level
    found, curve = _points_in(surface, box, *candidate_boxes(surface, box, level), avoid, avoid_radius, on_radius)
    size = float(np.max(box[:, 1] - box[:, 0]))
    for _ in range(tol.SINGULAR_CROWD_LEVELS):
        # Points a cell or two apart (Labs' septic's neighbouring orbits
        # near z = -0.56) share candidate boxes, and Newton from the box of
        # one may end at its neighbour: the one between is lost.  Where
        # points crowd, the search goes a level deeper.
        at = np.array([sp.point for sp in found]).reshape(-1, 3)
        cell = size / (1 << level)
        crowded = _crowded(at, tol.SINGULAR_CROWD * cell)
        if not crowded.any():
            break
        level += 1
        lo, hi = candidate_boxes(surface, box, level, near=(at[crowded], tol.SINGULAR_CROWD * cell))
        more, c = _points_in(surface, box, lo, hi, avoid, avoid_radius, on_radius)
        curve |= c
        if more:
            # Points both searches found are the first's.
            new = np.array([sp.point for sp in more])
            d, _ = _nearest(at, new)
            found = sorted(found + [sp for sp, far in zip(more, (d > tol.SINGULAR_MERGE * size).tolist()) if far],
                           key=lambda sp: tuple(sp.point))
    return _one_per_flat_point(found, tol.NON_SIMPLE_MERGE * size / (1 << first_level)), curve


def _one_per_flat_point(found: list[SingularPoint], radius: float) -> list[SingularPoint]:
    """``found`` with the non-simple points closer than ``radius`` (chained) kept as one: the
    least residual (then the least coordinates) of each cluster.  Simple points stay as they are
    (Labs' septic's nodes a box or two apart are distinct)."""
    flat = np.array([i for i, sp in enumerate(found)
                     if sp.classification is not None and getattr(sp.classification, "milnor", 0) is None], int)
    if len(flat) < 2:
        return found
    at = np.array([found[i].point for i in flat], dtype=float)
    _, label = linked(at, radius)
    res = np.array([found[i].residual for i in flat], dtype=float)
    order = np.lexsort((at[:, 2], at[:, 1], at[:, 0], res, label))
    first = np.r_[True, label[order][1:] != label[order][:-1]]
    drop = set(flat[order[~first]].tolist())
    return [sp for i, sp in enumerate(found) if i not in drop]


def linked(points: np.ndarray, radius: float) -> tuple[int, np.ndarray]:
    """Single-linkage clusters of ``points`` at ``radius``: (count, label of each point).

    The components of the graph of pairs closer than ``radius`` (a k-d
    tree's pairs, not a dense matrix of all distances: 63 GB for the
    130,000 ends of a sheet's boxes).
    """
    from scipy.spatial import cKDTree

    pairs = cKDTree(points).query_pairs(radius, output_type="ndarray")
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(points), len(points)))
    return connected_components(graph, directed=False)


def _crowded(points: np.ndarray, distance: float) -> np.ndarray:
    """Which points have another closer than ``distance``."""
    if len(points) < 2:
        return np.zeros(len(points), bool)
    d, _ = _nearest(points, points, k=2)
    return d[:, 1] < distance


def _nearest(points: np.ndarray, queries: np.ndarray, k: int = 1):
    """Distances to the nearest ``k`` of ``points`` (and their indices)."""
    from scipy.spatial import cKDTree

    return cKDTree(points).query(queries, k=k)


def _points_in(surface: Surface, box: np.ndarray, lo: np.ndarray, hi: np.ndarray,
               avoid: np.ndarray | None, avoid_radius: float,
               on_radius: float) -> tuple[list[SingularPoint], bool]:
    """The singular points :func:`singular_points` finds from the candidate boxes ``lo``, ``hi``."""
    near = np.zeros(len(lo), bool)
    tree = None
    if avoid is not None and len(avoid) and len(lo):
        from scipy.spatial import cKDTree

        tree = cKDTree(avoid)
        d, _ = tree.query((lo + hi) / 2)
        near = d <= avoid_radius + float(np.linalg.norm(hi[0] - lo[0]))
    # A curve of singular points makes a long chain of candidate boxes
    # with singular points all along it.  Starts in a chain are not points.
    # The boxes round a traced curve are its chain: they are not tested
    # (the curve is known), but Newton runs from them below, since a point
    # of F beside the curve (an A2 of one factor a cell from the other)
    # has its boxes there too.
    on_curve = np.zeros(len(lo), bool)
    # A sheet of singular points (F touching 0 along a surface without
    # changing sign: sqrt(y^2 + z^2) - z on its half-plane) makes a clump
    # as wide as it is long: Newton from each of its boxes cost seconds and
    # finds no point.  Its boxes are not points either.
    far = np.nonzero(~near)[0]
    on_curve[far] = _sheets(surface, lo[far], hi[far], box)
    rest = far[~on_curve[far]]
    on_curve[rest] = _curve_chains(surface, lo[rest], hi[rest], box)
    curve = bool(on_curve.any())
    lo, hi, near = lo[~on_curve], hi[~on_curve], near[~on_curve]
    if len(lo) == 0:
        return [], curve
    cell = float(np.max(hi[0] - lo[0]))
    near_lo, near_hi = lo[near], hi[near]
    lo, hi = lo[~near], hi[~near]

    x = gauss_newton(surface, (lo + hi) / 2)
    size = box[:, 1] - box[:, 0]
    margin = 1e-9 * size

    def accepted(x, lo, hi):
        # A degenerate point on a face of the box is fixed only to
        # ~eps^(1/k) by Gauss-Newton, as likely outside as in: a start a
        # cell out is centred first, then checked.
        inside = np.all((x >= box[:, 0] - (hi - lo)) & (x <= box[:, 1] + (hi - lo)), axis=1)
        # Accept loosely first: degenerate points are only fixed to ~eps^(1/k)
        # in double precision, and centring decides.
        near_cell = np.all(np.abs(x - (lo + hi) / 2) <= 2.0 * (hi - lo), axis=1)
        ok = inside & near_cell & np.isfinite(x).all(axis=1)
        ok[ok] = residual(surface, x[ok]) < tol.SINGULAR_LOOSE
        return ok

    ok = accepted(x, lo, hi)
    if not ok.all():
        # Gauss-Newton wanders off a very flat point (x^3 + y^7 + z^2:
        # grad F ~ y^6 along y, and the least-squares step gives that tiny
        # column F's remainder): all 8 starts round it ended 0.2 away, and
        # the point was lost.  Without the flat directions it stays, near
        # enough for centring.
        again = np.nonzero(~ok)[0]
        y = gauss_newton(surface, (lo[again] + hi[again]) / 2, rcond=tol.SINGULAR_FLAT_RCOND)
        good = accepted(y, lo[again], hi[again])
        x[again[good]] = y[good]
        ok[again[good]] = True
    x = x[ok]
    if len(near_lo):
        # Newton from the boxes round a traced curve ends on it (its pinch
        # and triple points are the curve's special points, not isolated
        # ones), in a few steps where it is near; the ends off it are
        # points beside the curve.
        y = (near_lo + near_hi) / 2
        for steps in tol.CURVE_NEAR_STEPS:
            y = gauss_newton(surface, y, iterations=steps)
            off = tree.query(y)[0] > on_radius
            y, near_lo, near_hi = y[off], near_lo[off], near_hi[off]
        x = np.concatenate([x, y[accepted(y, near_lo, near_hi)]])
    # Starts along a curve the clump test missed (a clump of candidates
    # spread over a sheet, where Newton across does not settle) end densely
    # along it: a chain of end points CURVE_SPAN boxes long.
    x, more = _dense_chains(surface, x, cell)
    curve |= more
    if len(x) == 0:
        return [], curve
    # One start per distinct end point (to the merge distance), best first.
    res = residual(surface, x)
    x = _dedupe(x, tol.SINGULAR_MERGE * size.max(), key=res)
    x = x[np.lexsort((x[:, 2], x[:, 1], x[:, 0], residual(surface, x)))]
    limit = accept_residual(surface)
    found: list[SingularPoint] = []
    regions: list[tuple[np.ndarray, float]] = []   # centres and the radius their starts fall in
    # Ends beside a traced curve that are not simple are that curve's (a
    # special point its trace stopped short of: Crixxi's tangential
    # meetings of cuspidal edges); the simple ones are points beside it.
    # The curve test steps 4 and 8 boxes off: beside a curve it would land
    # on it, so there the jet decides.
    beside = (tree.query(x)[0] <= avoid_radius) if tree is not None else np.zeros(len(x), bool)
    # The curve test of every start, in one batch (a few are not needed).
    along = np.zeros(len(x), bool)
    along[~beside] = _on_curve_many(surface, x[~beside], cell, steps=(4, 8))
    # The first classification of every other start, in one batch (those
    # in the region of a point found before are not needed).
    first = iter(analyse_each(surface, x[~along]))
    # ... and their residuals (a node's centre is its start: most points).
    at_start = iter(residual_each(surface, x[~along]).tolist())
    with np.errstate(all="ignore"):
        for p, on, by in zip(x, along.tolist(), beside.tolist()):
            known = None if on else next(first)
            r_start = None if on else next(at_start)
            if regions and (_lengths(p - np.array([c for c, _ in regions]))
                            <= np.array([r for _, r in regions])).any():
                continue  # another start in the region of a point already centred
            # The region of an end on a curve: its starts.  Beside a traced
            # curve only the end itself (a node a cell off is not the curve's).
            region = on_radius if by else 3.0 * cell
            if on or (by and isinstance(known, tuple) and known[0].milnor is None):
                # On a curve of singular points: not a point, and no need
                # to classify it (the costliest kind to classify).
                curve |= not by
                regions.append((p, region))
                continue
            try:
                q, kind, _ = centre(surface, p, reach=2.0 * cell, limit=limit, first=known)
            except NotSingularError:
                continue  # singular only to the loose test
            if by and kind.milnor is None:
                regions.append((q, region))
                continue
            if kind.milnor is None and (_on_curve(surface, q, cell, steps=(2, 4, 8)) or _continues(surface, q, cell)):
                # Non-simple: on a curve of singular points (its neighbours
                # are singular too), or an isolated point of higher type
                # (x^2 - y^6 - z^4 is singular to CURVE_RESIDUAL two boxes
                # along y at level 8, not four; x^3 + y^7 + z^2 not eight).
                # Straight steps miss an arc that turns within 8 boxes (an
                # arc of a sextic double curve too short to be traced, a
                # few cells from a traced one, where Newton from the boxes
                # round that one ends: fuzz s1-494); tracing follows it.
                curve = True
                regions.append((q, 3.0 * cell))
                continue
            if (kind.milnor or 0) >= tol.CURVE_CHECK_MILNOR and _continues(surface, q, cell):
                # Read as a high A_k (F flat to rounding along a short,
                # tightly turning arc of a double curve: the rotated
                # parabola's A12 to A15), but the locus goes on along the
                # Hessian's kernel both ways: a curve, not a point.
                curve |= not by
                regions.append((q, region))
                continue
            if not np.all((q >= box[:, 0] - margin) & (q <= box[:, 1] + margin)):
                continue
            # On a face of the box to rounding: on it (a vertex of the mesh).
            q = np.minimum(np.maximum(q, box[:, 0]), box[:, 1])
            r = r_start if q.tobytes() == p.tobytes() else float(residual(surface, q))
            if r > limit:
                continue
            # Starts of a degenerate point spread over its region (up to
            # ~eps^(1/(k+1))): those closer than a few times this one's
            # distance centre to the same point.
            # (Non-simple ones, Milnor number not found, too.)
            reach = 4.0 * float(np.linalg.norm(q - p)) if kind.milnor is None or kind.milnor > 1 else 0.0
            regions.append((q, max(reach, tol.SINGULAR_MERGE * size.max())))
            found.append(SingularPoint(point=q, residual=r, hessian_rank=3 - kind.corank,
                                       signature=kind.hessian_signature, classification=kind))
    pts = _dedupe(np.array([s.point for s in found]).reshape(-1, 3), tol.SINGULAR_MERGE * size.max())
    found_at = np.array([s.point for s in found]).reshape(-1, 3)
    keep = [found[int(np.argmin(_lengths(found_at - q)))] for q in pts]
    keep.sort(key=lambda s: tuple(s.point))
    return keep, curve


def _lengths(v: np.ndarray) -> np.ndarray:
    """np.linalg.norm of each row of ``v`` (K, 3), with its bits: the square
    root of the same BLAS dot product (a row times a column in matmul), not
    of a sum along the axis."""
    return np.sqrt(np.matmul(v[:, None, :], v[:, :, None])[:, 0, 0])


def _clumps(cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Connected clumps of boxes (integer cells touching at a face, edge or corner).

    Returns
    -------
    label : (K,) int64     clump of each cell
    span : (L,) int64      largest extent of each clump, in cells
    """
    n = len(cells)
    if n == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    c = cells - cells.min(axis=0) + 1
    m = int(c.max()) + 2
    keys = (c[:, 0] * m + c[:, 1]) * m + c[:, 2]
    order = np.argsort(keys)
    sorted_keys = keys[order]
    rows, cols = [], []
    for d in np.array(np.meshgrid([-1, 0, 1], [-1, 0, 1], [-1, 0, 1], indexing="ij")).reshape(3, -1).T:
        if not d.any():
            continue
        q = ((c[:, 0] + d[0]) * m + c[:, 1] + d[1]) * m + c[:, 2] + d[2]
        pos = np.minimum(np.searchsorted(sorted_keys, q), n - 1)
        hit = sorted_keys[pos] == q
        rows.append(np.nonzero(hit)[0])
        cols.append(order[pos[hit]])
    rows, cols = np.concatenate(rows), np.concatenate(cols)
    _, label = connected_components(coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, n)), directed=False)
    lo = np.full((label.max() + 1, 3), np.iinfo(np.int64).max)
    hi = np.full((label.max() + 1, 3), np.iinfo(np.int64).min)
    np.minimum.at(lo, label, cells)
    np.maximum.at(hi, label, cells)
    return label, (hi - lo).max(axis=1) + 1


def _principal(points: np.ndarray) -> np.ndarray:
    """The unit direction along which ``points`` spread most."""
    return np.linalg.svd(points - points.mean(axis=0), full_matrices=False)[2][0]


def _least(points: np.ndarray) -> np.ndarray:
    """The unit direction along which ``points`` spread least."""
    d = points - points.mean(axis=0)
    return np.linalg.eigh(d.T @ d)[1][:, 0]


def _sheets(surface: Surface, lo: np.ndarray, hi: np.ndarray, box: np.ndarray) -> np.ndarray:
    """Which candidate boxes lie on a sheet (a surface) of singular points.

    A clump of boxes (as :func:`_curve_chains`) at least ``CURVE_SPAN``
    boxes across in two directions and holding at least ``SHEET_FILL`` of
    the product of its two largest extents is a sheet when Newton from
    ``CURVE_SAMPLES`` of its boxes reaches singular points next to them
    that spread ``CURVE_SPAN / 2`` boxes across in two directions (a
    curve's points lie along one).  A curve's clump, a few boxes thick,
    fills a vanishing part of that product once it is that long.

    A square-free polynomial has no such sheet: where one is found F is
    nearly a square (``x^2 - 1e-20``, two planes 2e-10 apart), refused
    with a message saying so (:func:`near_double_message`) unless F has
    no zero there (``x^2 + 1e-20``).
    """
    return _sheets_and_zeroless(surface, lo, hi, box)[0]


def _sheets_and_zeroless(surface: Surface, lo: np.ndarray, hi: np.ndarray,
                         box: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_sheets`' boxes, and those of them on a near-double sheet with no zero (G^2 + e)."""
    out = np.zeros(len(lo), bool)
    zeroless = np.zeros(len(lo), bool)
    for mine, ends, normals in _sheet_clumps(surface, lo, hi, box):
        out[mine] = True
        if surface.is_polynomial and _rank_one(surface, ends):
            message = near_double_message(surface, ends, normals, box)
            if message is not None:
                raise SurfaceError(message)
            zeroless[mine] = True
    return out, zeroless


def _rank_one(surface: Surface, ends: np.ndarray) -> bool:
    """Whether F's Hessian has rank one (to ``NEAR_DOUBLE_RANK``) at most of ``ends``.

    Near G^2 - e it is 2 grad G grad G^T + 2 G Hess G, G ~ sqrt(e): rank one.
    Two curves of singular points crossing make a clump as wide as a sheet
    (the ellipses of two cylinders (x^2 + y^2 - 1)(x^2 + z^2 - 1) at
    (+-1, 0, 0)), their points with F = 0 to rounding, but two sheets cross
    there: rank two.
    """
    sv = np.linalg.svd(surface.hessian(ends), compute_uv=False)
    flat = sv[:, 1] <= tol.NEAR_DOUBLE_RANK * sv[:, 0]
    return bool(2 * flat.sum() > len(ends))


def _sheet_clumps(surface: Surface, lo: np.ndarray, hi: np.ndarray, box: np.ndarray):
    """The clumps of candidate boxes :func:`_sheets` finds to be sheets of singular points.

    Yields
    ------
    mine : (k,) int ndarray
        The clump's boxes (indices into ``lo``).
    ends, normals : (m, 3) ndarrays
        The singular points Newton reached from samples of the clump, and
        the clump's normal at each.
    """
    if len(lo) < tol.CURVE_SPAN ** 2 * tol.SHEET_FILL:
        return
    cells = np.rint((lo - box[:, 0]) / (hi - lo)).astype(np.int64)
    label, _ = _clumps(cells)
    n = np.bincount(label)
    first = np.full((len(n), 3), np.iinfo(np.int64).max)
    last = np.full((len(n), 3), np.iinfo(np.int64).min)
    np.minimum.at(first, label, cells)
    np.maximum.at(last, label, cells)
    ext = np.sort(last - first + 1, axis=1)
    wide = np.nonzero((ext[:, 1] >= tol.CURVE_SPAN) & (n >= tol.SHEET_FILL * ext[:, 2] * ext[:, 1]))[0]
    if len(wide) == 0:
        return
    h = float(np.max(hi[0] - lo[0]))
    limit = max(accept_residual(surface), tol.CURVE_RESIDUAL)
    for lab in wide.tolist():
        mine = np.nonzero(label == lab)[0]
        centres = (lo[mine] + hi[mine]) / 2
        picks = np.linspace(0, len(mine) - 1, tol.CURVE_SAMPLES).astype(int)
        starts = centres[picks]
        # Newton along the clump's normal where each start is (the least
        # principal direction of the boxes within three of it): in the
        # sheet F is flat, and a free step drifts along it (F ~ y^2 / 2z
        # falls as z grows).
        normal = np.array([_least(centres[np.abs(centres - c).max(axis=1) <= 3.0 * h])
                           for c in starts])
        x = starts.copy()
        for _ in range(60):
            f, g, hess = surface.jet(x)
            r = np.concatenate([f[:, None], g], axis=1)
            jn = np.einsum("kij,kj->ki", np.concatenate([g[:, None, :], hess], axis=1), normal)
            t = np.einsum("ki,ki->k", jn, r) / np.maximum(np.einsum("ki,ki->k", jn, jn), 1e-300)
            x = x - np.clip(t, -h, h)[:, None] * normal
        good = np.isfinite(x).all(axis=1) & (np.abs(x - starts).max(axis=1) <= 2 * h)
        good[good] = residual(surface, x[good]) <= limit
        ends = x[good]
        if len(ends) < 3:
            continue
        # The spread of the ends across their first principal direction.
        sv = np.linalg.svd(ends - ends.mean(axis=0), compute_uv=False)
        if sv[1] >= 0.5 * tol.CURVE_SPAN * h / np.sqrt(len(ends)):
            yield mine, ends, normal[good]


def near_double_message(surface: Surface, ends: np.ndarray, normals: np.ndarray, box: np.ndarray) -> str | None:
    """What to tell the user of a sheet of singular points of a polynomial F, or None.

    F = G^2 - e with e tiny against F's terms is singular to
    ``CURVE_RESIDUAL`` all along G = 0, and its two sheets G = +-sqrt(e)
    are 2 sqrt(2 |F| / F_nn) apart (F_nn the second derivative across the
    sheet): ``x^2 - 1e-20``'s 2e-10, at most ~2e-4 of F's scale, a few
    thousandths of a cell of any lattice the memory allows; no lattice
    edge between them sees the sign change.  Where |F| there is below the
    rounding of F's terms (``INPUT_ROUNDING``: the sphere's square plus
    1e-16, whose constant rounds to 1) two sheets and none are the same
    input.  Both are refused with what they are.  Where F has the sign of
    F_nn above rounding (G^2 + e) it has no zero there: None, nothing to
    refuse (the sheet's boxes are no points nor curves).

    Parameters
    ----------
    ends, normals : (m, 3) ndarrays
        Points of the sheet (:func:`_sheet_clumps`) and the sheet's normal at each.
    """
    f, _, hess = surface.jet(ends)
    bend = np.einsum("ki,kij,kj->k", normals, hess, normals)
    noise = tol.INPUT_ROUNDING * surface.degree * surface.rounding * surface.magnitude(ends)
    lost = np.abs(f) <= noise
    apart = (f * bend < 0) & ~lost
    if not (apart.any() or lost.any()):
        return None
    # The point said: the nearest sheets (or the largest rounding).
    gaps = 2.0 * np.sqrt(np.abs(2.0 * f / np.where(bend != 0, bend, np.inf)))
    i = int(np.flatnonzero(apart)[np.argmin(gaps[apart])]) if apart.any() else int(np.argmax(noise))
    size = float(np.max(box[:, 1] - box[:, 0]))
    at = ", ".join(f"{c:.3g}" for c in ends[i])
    if apart.any():
        what = (f"F = G^2 - e there with e = {abs(float(f[i])):.2g}: two sheets {gaps[i]:.2g} apart "
                f"({gaps[i] / size:.2g} of the box), closer than any lattice edge parts")
    else:
        what = (f"F = G^2 + e there with |e| <= {float(noise[i]):.2g}, the rounding of F's terms there: two "
                "sheets or none, rounding cannot tell")
    return (f"F is nearly a square near ({at}), a near-double component: {what}; mesh G alone "
            "(its surface once), or write e exactly and large enough to part the sheets by a fine cell")


def _curve_chains(surface: Surface, lo: np.ndarray, hi: np.ndarray, box: np.ndarray) -> np.ndarray:
    """Which candidate boxes lie on a curve of singular points.

    A curve makes a clump of at least ``CURVE_SPAN`` boxes (touching at a
    face, edge or corner) with singular points all along it.  A degenerate
    isolated point makes a long clump too (a corank-3 point, or one with
    rounded coefficients: its Bernstein ranges hold zero far out), but
    with one singular point in it.  So: Newton from ``CURVE_SAMPLES`` boxes
    spread along each long clump, across the clump (along it, Newton drifts
    on a curve to its most degenerate point); it is a curve when two of
    them reach singular points (to the precision of the input) next to
    their boxes and ``CURVE_SPAN / 2`` boxes apart.
    """
    if len(lo) == 0:
        return np.zeros(0, bool)
    cells = np.rint((lo - box[:, 0]) / (hi - lo)).astype(np.int64)
    label, extent = _clumps(cells)
    curve = np.zeros(len(extent), bool)
    h = float(np.max(hi[0] - lo[0]))
    # Newton across a curve of cusps or tacnodes converges slowly; a point
    # residual of CURVE_RESIDUAL is on it for this purpose.
    limit = max(accept_residual(surface), tol.CURVE_RESIDUAL)
    long = np.nonzero(extent >= tol.CURVE_SPAN)[0].tolist()
    starts, dirs, owner = [], [], []
    for lab in long:
        mine = np.nonzero(label == lab)[0]
        centres = (lo[mine] + hi[mine]) / 2
        axis = _principal(centres)
        t = (centres - centres.mean(axis=0)) @ axis
        picks = np.argsort(t, kind="stable")[np.linspace(0, len(mine) - 1, tol.CURVE_SAMPLES).astype(int)]
        for k in picks.tolist():
            # Across the clump where it is: the boxes within three of this one.
            local = centres[np.abs(centres - centres[k]).max(axis=1) <= 3.0 * h]
            starts.append(centres[k])
            dirs.append(_principal(local))
            owner.append(lab)
    if not long:
        return curve[label]
    # All clumps' starts in one Newton run (each across its own direction).
    starts, owner = np.array(starts), np.array(owner)
    x = gauss_newton(surface, starts, iterations=60, max_step=h, across=np.array(dirs))
    good = np.abs(x - starts).max(axis=1) <= 2 * h
    good[good] = residual(surface, x[good]) <= limit
    for lab in long:
        # Two singular points CURVE_SPAN / 2 boxes apart, each found next to
        # where it was looked for: an isolated point is one of them at most.
        ends = x[good & (owner == lab)]
        far = np.linalg.norm(ends[:, None] - ends[None], axis=2).max(initial=0.0)
        curve[lab] = far >= 0.5 * tol.CURVE_SPAN * h
    return curve[label]


def _on_curve(surface: Surface, p: np.ndarray, cell: float, steps=(2,)) -> bool:
    """Whether singular points lie ``steps`` boxes away from ``p`` along its Hessian's kernel.

    Newton across a kernel direction from so many boxes along it (either
    way): on a curve of singular points (tangent in the kernel) it lands
    next to where it started, at every step; near an isolated point
    nothing is singular that far (at two boxes even an A5, checked only
    once the classifier found a non-simple point; at four and eight any
    A_k up to A7).
    """
    return bool(_on_curve_many(surface, np.asarray(p, float)[None], cell, steps)[0])


def _on_curve_many(surface: Surface, points: np.ndarray, cell: float, steps=(2,)) -> np.ndarray:
    """:func:`_on_curve` for many points: all their Newton runs in one batch."""
    points = np.asarray(points, float).reshape(-1, 3)
    w, v = np.linalg.eigh(surface.hessian(points))
    scale = np.maximum(np.abs(w).max(axis=1, initial=0.0), 1e-300)
    kernel = np.abs(w) <= tol.CENTRE_RANK_RTOL * scale[:, None]   # (K, 3)
    pt, col = np.nonzero(kernel)
    if len(pt) == 0:
        return np.zeros(len(points), bool)
    d = v[pt, :, col]                                             # (J, 3) kernel directions
    shifts = np.array([sign * k for k in steps for sign in (1.0, -1.0)])  # (S,)
    start = points[pt][:, None, :] + shifts[None, :, None] * cell * d[:, None, :]   # (J, S, 3)
    across = np.repeat(d, len(shifts), axis=0)
    start = start.reshape(-1, 3)
    q = gauss_newton(surface, start, iterations=40, max_step=cell, across=across)
    with np.errstate(all="ignore"):
        good = np.abs(q - start).max(axis=1) <= 1.5 * cell
        good[good] = residual(surface, q[good]) <= tol.CURVE_RESIDUAL
    # A direction is along a curve when, at every step, either sign lands.
    hit = good.reshape(len(d), len(steps), 2).any(axis=2).all(axis=1)
    out = np.zeros(len(points), bool)
    out[pt[hit]] = True
    return out


def _continues(surface: Surface, p: np.ndarray, cell: float) -> bool:
    """Whether the singular locus through ``p`` goes on as a curve along its Hessian's kernel.

    The curve tracer (steps of half a box, shorter on tight turns, each
    vertex Newton-corrected to a curve vertex's residual) followed from
    ``p`` along a kernel direction, both ways: on a curve it leaves the
    cube of ``CURVE_CHECK_REACH`` boxes around ``p`` or takes all its
    ``CURVE_CHECK_STEPS`` both ways, or one way comes round to ``p``; from an isolated point of type A_k the residual
    grows as the k-th power of the distance and the trace is lost within
    a few boxes (an A12 of unit coefficients at 0.15, five boxes at level
    6 and under the cube's 0.08 at level 8 only from A20 on).  Unlike
    :func:`_on_curve` (straight steps), it follows an arc that turns
    within two boxes (a parabola z = 8 x^2 near its vertex), and beyond
    the box of the mesh (a short arc dipping into it).
    """
    from .singular_curves import _trace_one_way

    w, v = np.linalg.eigh(surface.hessian(np.asarray(p, float)[None])[0])
    scale = max(float(np.abs(w).max(initial=0.0)), 1e-300)
    reach = tol.CURVE_CHECK_REACH * cell
    cube = np.stack([p - reach, p + reach], axis=1)
    for col in np.flatnonzero(np.abs(w) <= tol.CENTRE_RANK_RTOL * scale):
        ways = []
        for sign in (1.0, -1.0):
            pts, how = _trace_one_way(surface, cube, p, sign * v[:, col], 0.5 * cell, tol.CURVE_CHECK_STEPS)
            # All its steps taken without losing the locus: a curve that
            # winds inside the cube (the branches of a sextic double curve
            # looping within 10 boxes: fuzz s1-494), not an isolated point,
            # whose trace is lost within a few boxes.
            ways.append("steps" if how == "lost" and len(pts) >= tol.CURVE_CHECK_STEPS else how)
        if "closed" in ways or all(how in ("box", "steps") for how in ways):
            return True
    return False


def _dense_chains(surface: Surface, x: np.ndarray, cell: float) -> tuple[np.ndarray, bool]:
    """Newton end points not in a dense chain, and whether there was one.

    Single-linkage clusters at two boxes spanning ``CURVE_SPAN`` boxes or
    more with at least one end point per two boxes of their span: end
    points along a curve.  Nodes, even hundreds, are boxes apart.  The
    ends round a very flat isolated point spread so too (x^2 - y^6 - z^4:
    |grad F| ~ d^5, below SINGULAR_LOOSE over 12 boxes at level 8), but
    from its most singular end, 4 and 8 boxes along the Hessian's kernel
    nothing is singular (:func:`_on_curve`): those stay starts.
    """
    if len(x) < 2:
        return x, False
    # Single linkage at two boxes.
    _, labels = linked(x, 2.0 * cell)
    drop = np.zeros(len(x), bool)
    res = None
    for lab in np.unique(labels):
        sel = labels == lab
        span = float(np.ptp(x[sel], axis=0).max())
        if span >= tol.CURVE_SPAN * cell and sel.sum() >= 0.5 * span / cell:
            if res is None:
                res = residual(surface, x)
            members = np.flatnonzero(sel)
            best = members[np.argmin(res[members])]
            if _on_curve(surface, x[best], cell, steps=(4, 8)):
                drop |= sel
    return x[~drop], bool(drop.any())


def _representatives(x: np.ndarray, labels: np.ndarray, key: np.ndarray | None) -> tuple | None:
    """Each cluster's representative and extent (clusters in the order of their labels), all
    clusters at once: the members of each in index order, the sums, differences and
    sorts the loop over clusters in :func:`_dedupe` makes, cluster by cluster.

    The centre is the members' mean (:func:`_cluster_means`, as
    ``mean(axis=0)`` of the cluster), the distances each row's norm, the
    nearest the first least (as ``argmin``): finite points only, None
    where a distance is not finite (the caller's loop then decides).
    """
    order = np.argsort(labels, kind="stable")
    lab = labels[order]
    xs = x[order]
    start = np.flatnonzero(np.concatenate([[True], lab[1:] != lab[:-1]]))
    count = np.diff(np.concatenate([start, [len(xs)]]))
    extent = (np.maximum.reduceat(xs, start, axis=0) - np.minimum.reduceat(xs, start, axis=0)).max(axis=1)
    if key is not None:
        best = np.lexsort((xs[:, 2], xs[:, 1], xs[:, 0], key[order], lab))
    else:
        centre = _cluster_means(xs, start, count)
        d = np.linalg.norm(xs - np.repeat(centre, count, axis=0), axis=1)
        if not np.isfinite(d).all():
            return None  # (argmin takes the first NaN; sorts put NaN last)
        best = np.lexsort((d, lab))
    # The first of each cluster in the sorted order (clusters in label order).
    return xs[best[start]], extent


def _cluster_means(xs: np.ndarray, start: np.ndarray, count: np.ndarray) -> np.ndarray:
    """``xs[start[c]:start[c] + count[c]].mean(axis=0)`` of each cluster c, to the bit.

    numpy sums along the first axis row after row (``np.add.reduceat``
    sums otherwise): the clusters' sums add their r-th members together,
    r = 1, 2, ..., for all clusters at once; a large cluster (few) takes
    its own ``mean``.
    """
    sums = xs[start].copy()
    small = count <= _FEW_MEMBERS
    for r in range(1, int(count[small].max(initial=1))):
        more = np.flatnonzero(small & (count > r))
        sums[more] += xs[start[more] + r]
    centre = sums / count[:, None]
    for c in np.flatnonzero(~small).tolist():
        centre[c] = xs[start[c]:start[c] + count[c]].mean(axis=0)
    return centre


#: Clusters of at most this many points have their means summed together
#: (a step per member rank); larger ones one by one.
_FEW_MEMBERS = 32


def _dedupe(x: np.ndarray, radius: float, key: np.ndarray | None = None, spans: bool = False):
    """One representative per cluster of points closer than ``radius``.

    The representative is the member with the smallest ``key`` (default:
    the one nearest the cluster's centre); the choice is deterministic.
    With ``spans``, also return each cluster's extent (largest side of its
    bounding box).
    """
    if len(x) <= 1:
        x = x.reshape(-1, 3)
        return (x, np.zeros(len(x))) if spans else x
    # Single linkage by a k-d tree's pairs: a dense distance matrix of the
    # 65,000 Newton ends along a flat valley of |grad F| takes 16 GiB.
    labels = linked(x, radius)[1]
    batch = _representatives(x, labels, key) if np.isfinite(x).all() else None
    if batch is not None:
        reps, extent = batch
        order = np.lexsort(reps.T[::-1])
        return (reps[order], extent[order]) if spans else reps[order]
    reps, extent = [], []
    for lab in np.unique(labels):
        sel = labels == lab
        members = x[sel]
        extent.append(np.ptp(members, axis=0).max())
        if key is not None:
            reps.append(members[np.lexsort((members[:, 2], members[:, 1], members[:, 0], key[sel]))[0]])
            continue
        c = members.mean(axis=0)
        reps.append(members[np.argmin(np.linalg.norm(members - c, axis=1))])
    reps = np.array(reps)
    order = np.lexsort(reps.T[::-1])
    return (reps[order], np.array(extent)[order]) if spans else reps[order]


def skeleton_nodes(surface: Surface, box, level: int = 6) -> tuple[np.ndarray, np.ndarray]:
    """Points where F and two partial derivatives vanish but grad F does not.

    There the x-, y- or z-skeleton curves V(F, F_a), V(F, F_b) meet: the
    surface normal is along the third axis.  Found like singular points:
    candidate boxes for (F, F_a, F_b), then Newton on that square
    system from every candidate at once.

    Returns
    -------
    points : (k, 3) ndarray, sorted
    axes : (k, 2) int64, the pair (a, b) of vanishing derivatives
    """
    box = np.asarray(box, dtype=float)
    size = box[:, 1] - box[:, 0]
    found, pairs = [], []
    for a, b in ((0, 1), (0, 2), (1, 2)):
        lo, hi = candidate_boxes(surface, box, level, axes=(a, b))
        if len(lo) > tol.SKELETON_NODE_MAX or len(lo) == 0:
            continue  # a whole curve of them (e.g. a surface of revolution): not points
        x = (lo + hi) / 2
        live = np.ones(len(x), bool)
        for _ in range(30):
            f, g, h = surface.jet(x[live])
            r = np.stack([f, g[:, a], g[:, b]], axis=1)
            j = np.stack([g, h[:, a], h[:, b]], axis=1)
            with np.errstate(over="ignore", invalid="ignore"):
                ok = np.abs(np.linalg.det(j)) > 1e-300
            step = np.zeros((live.sum(), 3))
            step[ok] = np.linalg.solve(j[ok], r[ok][..., None])[..., 0]
            x[live] = x[live] - step
            # Starts that run off the box are dropped, not followed to overflow.
            live &= np.all(np.abs(x - box.mean(axis=1)) <= size, axis=1)
            if not live.any():
                break
        x = x[live]
        f, g, _ = surface.jet(x)
        scale = np.maximum(surface.magnitude(x), 1e-300)
        gn = np.linalg.norm(g, axis=1)
        good = (np.isfinite(x).all(axis=1)
                & np.all((x >= box[:, 0] - 1e-9 * size) & (x <= box[:, 1] + 1e-9 * size), axis=1)
                & (np.abs(f) <= 1e-12 * scale) & (np.abs(g[:, a]) <= 1e-10 * gn) & (np.abs(g[:, b]) <= 1e-10 * gn)
                & (gn > tol.SINGULAR_LOOSE * surface.scale))
        # Newton from boxes along a curve of such points (Cayley's cubic has
        # lines of them) lands all along it: clusters that long are curves.
        step = float(np.max(hi[0] - lo[0]))
        reps, extent = _dedupe(x[good], 2.0 * step, spans=True)
        pts = _dedupe(reps[extent <= 8.0 * step], tol.SINGULAR_MERGE * size.max())
        found.append(pts)
        pairs.append(np.tile([a, b], (len(pts), 1)))
    if not found:
        return np.zeros((0, 3)), np.zeros((0, 2), np.int64)
    return np.concatenate(found), np.concatenate(pairs).astype(np.int64)
