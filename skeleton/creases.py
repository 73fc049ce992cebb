"""Creases: curves where F = 0 has a kink, found and traced as singular curves are.

Each kink of F (:meth:`Surface.crease_systems`: a Max/Min's tie, an Abs's
zero, an R-function's f = g = 0) is the common zero set of two smooth
functions G1, G2.  On it the surface is two half-sheets meeting at an
angle: like a cuspidal edge, a curve with two triangles per edge, meshed
by the tubes of :mod:`singmesh.facets.tubes` from a
:class:`~singmesh.skeleton.singular_curves.CurveSet` of type ``"crease"``.

1. Samples: minimum-norm Newton on (G1, G2) from the centres of the boxes
   where both may vanish (interval bounds), kept where the kink is active.
2. Tracing: predictor along grad G1 x grad G2, corrector Newton, steps of
   ``CREASE_TRACE_STEP`` fine cells, both ways from an uncovered sample,
   until the box (the end placed on it by Newton with the face's plane as
   a third equation), back at the start (a closed crease), or where the
   kink stops being active (the end placed by bisection); then every
   step divided by Newton, all at once.
   A trace also ends where another active kink's crease meets it
   (Gauss-Newton on the equations of both: an octahedron's vertex).
3. Corners: ends of traces closer than ``CREASE_CORNER`` steps are one
   point (where three creases of a cube meet), placed by Gauss-Newton on
   the equations of all the creases there, and shared by them.
4. Ends on the box of two creases a few cells apart (a corner just
   outside the box) are joined in the graph by the surface's trace on
   that face, so that the tubes' strips reach the piece between them.
"""

from __future__ import annotations

from dataclasses import replace

import networkx as nx
import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra
from scipy.spatial import cKDTree

from singmesh import tolerances as tol
from singmesh.elementary import kink_values
from singmesh.surface import CreaseSystem, Surface, boxes_where

from .singular_curves import CurveSet, SingularCurve, SpecialPoint, _point_polyline_distance, back_at_start

#: The type of a crease's pieces in :class:`CurveSet`.
CREASE = "crease"
_EPS = float(np.finfo(float).eps)


def _tangent(system: CreaseSystem, x: np.ndarray) -> np.ndarray:
    """Unit tangents (k, 3) of the crease at points x: grad G1 x grad G2."""
    _, g = system.values(np.asarray(x, float).reshape(-1, 3))
    t = np.cross(g[:, 0], g[:, 1])
    return t / np.maximum(np.linalg.norm(t, axis=1, keepdims=True), 1e-300)


# ---------------------------------------------------------------- samples
def crease_samples(surface: Surface, system: CreaseSystem, box: np.ndarray, level: int) -> np.ndarray:
    """Points of the active crease near the boxes at ``level`` where G1, G2 and F may vanish."""
    _, corner = boxes_where(surface, box, level, lambda d: system.may_vanish(d) & ~surface.excludes_zero(d))
    if len(corner) == 0:
        return np.zeros((0, 3))
    size = (box[:, 1] - box[:, 0]) / (1 << level)
    start = box[:, 0] + (corner + 0.5) * size
    x, ok = system.newton(start, 2.0 * float(size.max()))
    ok &= np.all((x >= box[:, 0]) & (x <= box[:, 1]), axis=1)
    x = x[ok]
    return x[system.active(x)] if len(x) else x


# ---------------------------------------------------------------- tracing
def _clip(system: CreaseSystem, box: np.ndarray, x: np.ndarray, y: np.ndarray, h: float):
    """The point of the crease on the box's boundary between x (inside) and y (outside), or None."""
    d = y - x
    with np.errstate(all="ignore"):
        s = np.minimum(np.where(d < 0, (box[:, 0] - x) / d, np.inf), np.where(d > 0, (box[:, 1] - x) / d, np.inf))
    axis = int(np.argmin(s))
    value = box[axis, 0] if d[axis] < 0 else box[axis, 1]
    q = x + min(float(s[axis]), 1.0) * d
    extra = np.zeros((1, 4))
    extra[0, axis] = 1.0
    extra[0, 3] = value
    z, ok = system.newton(q[None], 2.0 * h, extra)
    if not ok[0]:
        return None
    z = z[0]
    z[axis] = value
    return np.clip(z, box[:, 0], box[:, 1])


def _crossing(systems: list, si: int, x: np.ndarray, y: np.ndarray, h: float, near=None):
    """Where another crease meets crease ``si`` between its points x and y, or None.

    Another kink whose two functions both come within two steps of y (to
    first order) is tried: Gauss-Newton on the equations of both from y;
    its point counts when it lies on the step from x to y or within a
    step beyond, and the other kink is active there (an octahedron's vertex, where the Abs creases
    x = 0 and y = 0 cross, or a cube's corner).
    """
    d = float(np.linalg.norm(y - x))
    both = kink_values(systems, y[None])  # every kink's values at y in one pass (None: one by one)
    for sj, other in enumerate(systems):
        if sj == si or (near is not None and not near(sj, y)):
            continue
        v, g = (both[0][:, sj], both[1][:, sj]) if both is not None else other.values(y[None])
        if not np.all(np.abs(v[0]) <= 2.0 * h * np.linalg.norm(g[0], axis=1)):
            continue
        z = _corner(systems, [si, sj], y, h)
        # On the step, or within a step beyond it (the next step would
        # pass the corner, where Newton on this crease alone may fail).
        if z is None or np.linalg.norm(z - x) > d + h or np.dot(z - x, y - x) <= 0:
            continue
        if other.active(z[None])[0] and not _runs_along(systems, si, sj, z, y - x, h):
            return z
    return None


def _runs_along(systems: list, si: int, sj: int, z: np.ndarray, ahead: np.ndarray, h: float) -> bool:
    """Whether crease ``si`` goes on through z (in the direction ``ahead``) past kink ``sj``: no corner.

    Crease si goes on when it is still active half a step on.  Then sj
    makes no corner at z if it runs along si (its equations vanish half a
    step from z along si, on either side: two kinks along one curve, as
    the coincident edges of two boxes with coplanar faces joined by Min,
    whose common zeros Gauss-Newton finds anywhere on the line) or if its
    own crease is active at z alone, not half a step from z along it on
    either side (an edge of one box lying in a face of the other, whose
    end is on si).  Their gradients do not tell: on a tie of coplanar
    faces they are the pieces rounding picks.
    """
    # (Along the trace's step: at z the tangents are the pieces rounding
    # picks too.  A point Newton takes back to z tells nothing.)
    t = ahead / np.linalg.norm(ahead)
    q, ok = systems[si].newton(z + 0.5 * h * np.array([t, -t]), h)
    ok &= np.linalg.norm(q - z, axis=1) >= 0.25 * h
    if not ok[0] or not systems[si].active(q[:1])[0]:
        return False
    v, g = systems[sj].values(q[ok])
    size = np.linalg.norm(g, axis=2) * np.maximum(np.abs(q[ok]).max(axis=1), 1.0)[:, None]
    if np.any(np.all(np.abs(v) <= tol.CREASE_RESIDUAL * np.maximum(size, 1e-300), axis=1)):
        return True
    tj = _tangent(systems[sj], z)[0]
    r, ok = systems[sj].newton(z + 0.5 * h * np.array([tj, -tj]), h)
    ok &= np.linalg.norm(r - z, axis=1) >= 0.25 * h
    return not (ok & systems[sj].active(r)).any()


def _trace_one_way(system: CreaseSystem, box: np.ndarray, x0: np.ndarray, t0: np.ndarray, h: float,
                   max_steps: int, systems: list | None = None, si: int = 0, near=None,
                   earlier: cKDTree | None = None):
    """Vertices from x0 along t0 (x0 excluded) and how the trace ended.

    ``"box"``: the last vertex is on the box's boundary; ``"closed"``: back
    at x0; ``"end"``: the kink stops being active between the last vertex
    and the point returned as third item; ``"meet"``: the last vertex is
    where another crease (of ``systems``) meets it, or where the trace runs
    onto ``earlier`` (points of this crease, or of the kinks before it, traced before: a trace that
    went on through a corner of its own crease, where the rim of
    Max(|u| + |v|, |w|) turns); ``"lost"``: Newton lost it.
    """
    pts = [x0]
    t = t0
    multi = systems is not None and len(systems) > 1
    n, ahead = 0, tol.CREASE_AHEAD_MIN
    while n < max_steps:
        x = pts[-1]
        # Several steps at once (predicted along the tangent, Newton on all
        # of them in one call), checked in order below as single steps
        # are; where the first of them fails, the single step with its
        # shorter tries.
        ys, ts = _steps_ahead(system, x, t, h, min(ahead, max_steps - n)) if ahead > 1 else (None, None)
        if ys is None or not len(ys):
            ahead = 1
            ys, ts, how = _one_step(system, box, pts, t, h, systems, si, near)
            if how is not None:
                return pts[1:], how, None
        inside = np.all((ys >= box[:, 0]) & (ys <= box[:, 1]), axis=1)
        cand = _crossing_candidates(systems, si, ys, h, near) if multi else np.zeros(len(ys), bool)
        act = system.active(ys)
        hit = earlier.query(ys) if earlier is not None else None
        for j, y in enumerate(ys):
            x = pts[-1]
            if not inside[j]:
                c = _clip(system, box, x, y, h)
                if c is not None:
                    if np.linalg.norm(c - x) < tol.CURVE_MERGE * h and len(pts) > 1:
                        pts[-1] = c
                    else:
                        pts.append(c)
                    return pts[1:], "box", None
                return pts[1:], "lost", None
            if cand[j]:
                z = _crossing(systems, si, x, y, h, near)
                if z is not None:
                    if np.linalg.norm(z - x) > np.linalg.norm(y - x) and np.linalg.norm(z - y) >= tol.CURVE_MERGE * h:
                        pts.append(y)  # the meeting point lies beyond y
                    elif np.linalg.norm(z - pts[-1]) < tol.CURVE_MERGE * h and len(pts) > 1:
                        pts.pop()
                    pts.append(z)
                    return pts[1:], "meet", None
            if not act[j]:
                return pts[1:], "end", y
            if hit is not None and hit[0][j] <= tol.CREASE_ONTO * h:
                pts.append(earlier.data[hit[1][j]].copy())
                return pts[1:], "meet", None
            if back_at_start(y, pts, h):
                return pts[1:], "closed", None
            pts.append(y)
            n += 1
        t = ts[-1]
        ahead = min(2 * max(ahead, 1), tol.CREASE_AHEAD_MAX)
    return pts[1:], "lost", None


def _steps_ahead(system: CreaseSystem, x: np.ndarray, t: np.ndarray, h: float, k: int):
    """Up to k steps of a trace from x along t in one Newton call: the points and their tangents.

    Newton from x + j h t (j = 1 ... k) with the reach of a single step;
    kept while each point is what a single step from the one before would
    accept (within h of that step's prediction, and ahead along its
    tangent): on a straight crease all of them, on a curved one the first
    few.  Returns ((m, 3), (m, 3)) with m <= k, tangents oriented along the trace.
    """
    pred = x + h * np.arange(1, k + 1)[:, None] * t
    z, ok = system.newton(pred, h)
    tz = _tangent(system, z)
    prev, tp = x, t
    m = 0
    for j in range(k):
        d = z[j] - prev
        if not ok[j] or np.dot(d, tp) <= 0.3 * h or np.linalg.norm(d - h * tp) > h:
            break
        tz[j] = tz[j] if np.dot(tz[j], d) >= 0 else -tz[j]
        prev, tp = z[j], tz[j]
        m += 1
    return z[:m], tz[:m]


def _one_step(system: CreaseSystem, box: np.ndarray, pts: list, t: np.ndarray, h: float, systems, si, near):
    """One step of a trace (a whole, half or quarter step): ((1, 3), (1, 3), None), or how the trace ended.

    Where no step lands (Newton fails past a point where another crease
    meets this one), the meeting point is appended to ``pts`` ("meet"), or
    the trace is lost.
    """
    x = pts[-1]
    for scale in (1.0, 0.5, 0.25):
        z, ok = system.newton((x + scale * h * t)[None], scale * h)
        if ok[0] and np.dot(z[0] - x, t) > 0.3 * scale * h:
            y = z[0]
            t_new = _tangent(system, y)[0]
            return y[None], (t_new if np.dot(t_new, y - x) >= 0 else -t_new)[None], None
    z = _crossing(systems, si, x, x + h * t, h, near) if systems is not None and len(systems) > 1 else None
    if z is not None:
        if np.linalg.norm(z - x) < tol.CURVE_MERGE * h and len(pts) > 1:
            pts[-1] = z  # x was Newton's landing next to (or on) the corner
        else:
            pts.append(z)
        return None, None, "meet"
    return None, None, "lost"


def _crossing_candidates(systems: list, si: int, ys: np.ndarray, h: float, near) -> np.ndarray:
    """(k,) bool: another kink's two functions both come within two steps of ys[j] (to first order).

    The test :func:`_crossing` makes first, for all the points at once:
    only where it holds is the crossing looked for.
    """
    out = np.zeros(len(ys), bool)
    others = [sj for sj in range(len(systems)) if sj != si]
    mask = np.stack([near(sj, ys) if near is not None else np.ones(len(ys), bool) for sj in others], 1)
    if not mask.any():
        return out
    both = kink_values([systems[sj] for sj in others], ys)
    for c, sj in enumerate(others):
        rows = np.nonzero(mask[:, c])[0]
        if not len(rows):
            continue
        v, g = (both[0][rows, c], both[1][rows, c]) if both is not None else systems[sj].values(ys[rows])
        with np.errstate(invalid="ignore"):
            out[rows] |= np.all(np.abs(v) <= 2.0 * h * np.linalg.norm(g, axis=2), axis=1)
    return out


def _ends(system_of: list, systems: list, inside: np.ndarray, outside: np.ndarray, h: float) -> np.ndarray:
    """Where each kink stops being active between inside[i] (active) and outside[i]: bisection, all at once."""
    k = len(inside)
    a, b = inside.copy(), outside.copy()
    if k == 0:
        return a
    for _ in range(60):
        if np.all(np.linalg.norm(b - a, axis=1) <= 1e-13 * h):
            break
        mid = 0.5 * (a + b)
        act = np.zeros(k, bool)
        for s in sorted(set(system_of)):
            rows = np.nonzero(np.asarray(system_of) == s)[0]
            z, ok = systems[s].newton(mid[rows], h)
            mid[rows] = np.where(ok[:, None], z, mid[rows])
            act[rows] = systems[s].active(mid[rows]) & ok
        a = np.where(act[:, None], mid, a)
        b = np.where(act[:, None], b, mid)
    return a


def _stacked_values(systems: list, which: list, x: np.ndarray):
    """The equations of the creases ``which`` at one point x, stacked: (2k,) values and (2k, 3) gradients."""
    both = kink_values([systems[s] for s in which], x[None])
    if both is not None:
        return both[0][0].reshape(-1), both[1][0].reshape(-1, 3)
    vs, gs = zip(*(systems[s].values(x[None]) for s in which))
    return np.concatenate([a[0] for a in vs]), np.concatenate([a[0] for a in gs])


def _corner(systems: list, which: list, start: np.ndarray, h: float):
    """Gauss-Newton from ``start`` on the stacked equations of the creases ``which``: the point, or None."""
    x = np.array(start, float)
    with np.errstate(all="ignore"):
        for _ in range(tol.CREASE_NEWTON):
            v, g = _stacked_values(systems, which, x)
            if not (np.isfinite(g).all() and np.isfinite(v).all()):
                return None
            step = np.linalg.lstsq(g, v, rcond=1e-13)[0]
            x_new = x - step
            small = np.all(np.abs(step) <= 4 * _EPS * np.maximum(np.abs(x), 1.0))
            x = x_new
            if small:
                break
        v, g = _stacked_values(systems, which, x)
        size = np.linalg.norm(g, axis=1) * max(float(np.abs(x).max()), 1.0)
    good = np.all(np.abs(v) <= tol.CREASE_RESIDUAL * np.maximum(size, 1e-300))
    return x if good and np.linalg.norm(x - start) <= 2.0 * tol.CREASE_CORNER * h else None


def _pinned(systems: list, x: np.ndarray, h: float) -> np.ndarray:
    """Corners x (k, 3) moved onto the common zero of every kink equation that vanishes there.

    Gauss-Newton on the kinks of the traces that meet at a corner is
    singular where they run along one line (the coincident edges of two
    boxes with coplanar faces): it lands anywhere on a short stretch of
    that line, ~1e-7 off the true corner.  The other kinks through the
    corner (the edges that make it a corner) pin it; a corner where they
    do not (rank below 3), or that would move further than
    ``CREASE_SAME`` steps or off any of its equations, stays as it is.
    """
    x = np.asarray(x, float)
    with np.errstate(all="ignore"):
        def stacked(y):
            vg = [s.values(y) for s in systems]
            return np.concatenate([v for v, _ in vg], 1), np.concatenate([g for _, g in vg], 1)

        def on(v, g, y, within=None):
            """Rows vanishing at y: within this distance, or else to CREASE_RESIDUAL (relative).

            A tie of two pieces with one gradient there (a Min of boxes
            whose faces are coplanar) has no distance: its value is
            measured against the largest gradient at y instead."""
            size = np.linalg.norm(g, axis=2)
            if within is None:
                within = tol.CREASE_RESIDUAL * np.maximum(np.abs(y).max(axis=1), 1.0)[:, None]
                size = np.maximum(size, np.nan_to_num(size).max(axis=1, keepdims=True))
            return np.isfinite(v) & np.isfinite(g).all(axis=2) & (size > 0) & (np.abs(v) <= within * size)

        v, g = stacked(x)
        # The kinks within CREASE_SAME steps of the corner: the ones through it, placed ~1e-7 off.
        rows = on(v, g, x, tol.CREASE_SAME * h)
        off = np.any(rows & ~on(v, g, x), axis=1)
        y = x.copy()
        for _ in range(tol.CREASE_NEWTON):
            v, g = stacked(y)
            v, g = np.where(rows, v, 0.0), np.where(rows[:, :, None], g, 0.0)
            step = np.einsum("kij,kj->ki", np.linalg.pinv(g, rcond=1e-13), v)
            step = np.where(np.isfinite(step), step, 0.0)
            y = y - step
            if np.all(np.abs(step) <= 4 * _EPS * np.maximum(np.abs(y), 1.0)):
                break
        v, g = stacked(y)
        sv = np.linalg.svd(np.where(rows[:, :, None], g, 0.0), compute_uv=False)
        good = (sv[:, 2] > tol.CREASE_PIN_RANK * sv[:, 0]) & np.all(on(v, g, y) | ~rows, axis=1)
        good &= off & (np.linalg.norm(y - x, axis=1) <= tol.CREASE_SAME * h)
    return np.where(good[:, None], y, x)


def _densify(systems: list, lines: list, pieces: int) -> list:
    """Each step of each polyline divided into ``pieces`` by Newton from the chord, all at once per crease."""
    if pieces <= 1:
        return lines
    out = []
    for s, p, closed, ends in lines:
        q = np.vstack([p, p[:1]]) if closed else p
        a, b = q[:-1], q[1:]
        j = np.arange(pieces) / pieces
        grid = a[:, None, :] + j[None, :, None] * (b - a)[:, None, :]
        inner = grid[:, 1:].reshape(-1, 3)
        # A point Newton moves by more than half its spacing is left out:
        # next to a corner where the crease itself bends (an octahedron's
        # vertex) it would land on the corner.
        reach = np.repeat(0.5 * np.linalg.norm(b - a, axis=1) / pieces, pieces - 1)
        z, ok = systems[s].newton(inner, reach)
        grid[:, 1:] = z.reshape(len(a), pieces - 1, 3)
        good = np.ones((len(a), pieces), bool)
        good[:, 1:] = ok.reshape(len(a), pieces - 1)
        dense = grid.reshape(-1, 3)[good.ravel()]
        if not closed:
            dense = np.vstack([dense, p[-1:]])
        out.append((s, dense, closed, ends))
    return out


def _no_repeats(pts: np.ndarray, h: float) -> np.ndarray:
    """The polyline without vertices that repeat their neighbour (a sample on a corner, and the
    corner placed again by the trace from it); its ends are kept."""
    if len(pts) < 2:
        return pts
    same = np.linalg.norm(np.diff(pts, axis=0), axis=1) < 1e-6 * h
    drop = np.zeros(len(pts), bool)
    n = len(pts)
    for i in np.nonzero(same)[0].tolist():
        # Of vertices i and i + 1, the one that is not an end goes.
        if i + 1 < n - 1:
            drop[i + 1] = True
        elif i > 0:
            drop[i] = True
    return pts[~drop]


def trace_creases(surface: Surface, box: np.ndarray, step: float, level: int | None = None) -> list:
    """The creases as polylines: (system index, points, closed, (end kind, end kind)) each."""
    box = np.asarray(box, float)
    level = tol.CREASE_LEVEL if level is None else level
    systems = surface.crease_systems()
    h = tol.CREASE_TRACE_STEP * step
    diameter = float(np.linalg.norm(box[:, 1] - box[:, 0]))
    max_steps = int(8 * diameter / h) + 16
    lines = []
    found = [crease_samples(surface, system, box, level) for system in systems]
    # Another kink's crease can only meet this one near its own samples
    # (one per box of the search where it is active).
    radius = 2.0 * h + float(np.linalg.norm(box[:, 1] - box[:, 0])) / (1 << level)
    trees = [cKDTree(p) if len(p) else None for p in found]

    def near(sj, y):
        # (one point or several)
        if trees[sj] is None:
            return np.zeros(np.shape(y)[:-1], bool)
        return trees[sj].query(y, distance_upper_bound=radius)[0] <= radius

    others = []  # the lines of the kinks before this one
    for si, system in enumerate(systems):
        samples = found[si]
        if len(samples) == 0:
            continue
        samples = samples[np.lexsort(samples.T[::-1])]
        tree = cKDTree(samples)
        covered = np.zeros(len(samples), bool)
        if others:
            # Two kinks along one curve (the coincident edges of two boxes
            # with coplanar faces joined by Min) hold one crease, traced
            # once: samples on a line of an earlier kink are covered by it.
            gap = np.min([_point_polyline_distance(samples, p) for p in others if len(p) > 1]
                         or [np.full(len(samples), np.inf)], axis=0)
            covered |= gap <= tol.CREASE_SAME * h
        # Samples where grad G1 and grad G2 are parallel have no tangent: a
        # patch of common zeros, not a curve (a Min of two boxes whose faces
        # are coplanar is tied on the whole face they touch along), whose
        # traces were lost at once both ways, a few ms each, hundreds of them.
        _, g = system.values(samples)
        with np.errstate(all="ignore"):
            cross = np.linalg.norm(np.cross(g[:, 0], g[:, 1]), axis=1)
            flat = ~(cross > tol.CREASE_JUMP * np.linalg.norm(g[:, 0], axis=1) * np.linalg.norm(g[:, 1], axis=1))
        traced = []  # this crease's lines so far
        for i in range(len(samples)):
            if covered[i]:
                continue
            x0 = samples[i]
            if flat[i]:
                # (as a trace lost at once: the samples near it are covered)
                covered[tree.query_ball_point(x0, 1.5 * h)] = True
                continue
            t0 = _tangent(system, x0)[0]
            earlier = cKDTree(np.concatenate(traced + others)) if traced or others else None
            fwd, how_f, out_f = _trace_one_way(system, box, x0, t0, h, max_steps, systems, si, near, earlier)
            if how_f == "closed":
                back, how_b, out_b = [], "closed", None
            else:
                back, how_b, out_b = _trace_one_way(system, box, x0, -t0, h, max_steps, systems, si, near,
                                                    earlier)
                if how_b == "closed":
                    # Round the whole loop backwards (the way forwards was
                    # lost at a corner of the crease): the loop alone.
                    fwd, how_f, out_f = [], "closed", None
            pts = _no_repeats(np.array(back[::-1] + [x0] + fwd), h)
            for idx in tree.query_ball_point(pts, 1.5 * h):
                covered[idx] = True
            covered[i] = True
            if len(pts) < 2:
                continue
            traced.append(pts)
            lines.append([si, pts, how_f == "closed", [how_b, how_f], [out_b, out_f]])
        others += traced
    return systems, lines


def crease_curves(surface: Surface, box, step: float, level: int | None = None) -> CurveSet:
    """The creases of F = 0 in ``box`` as a :class:`CurveSet` of type ``"crease"``, vertices ``step`` apart.

    Returns an empty CurveSet for a surface without kinks (every polynomial).
    """
    box = np.asarray(box, dtype=float)
    if not surface.crease_systems():
        return CurveSet()
    systems, lines = trace_creases(surface, box, step, level)
    if not lines:
        return CurveSet()
    h = tol.CREASE_TRACE_STEP * step
    # Where a kink stops being active: its end, by bisection.
    jobs = [(k, e) for k, line in enumerate(lines) for e in (0, 1) if line[3][e] == "end"]
    if jobs:
        inside = np.array([lines[k][1][0 if e == 0 else -1] for k, e in jobs])
        outside = np.array([lines[k][4][e] for k, e in jobs])
        placed = _ends([lines[k][0] for k, _ in jobs], systems, inside, outside, h)
        for (k, e), x in zip(jobs, placed):
            p = lines[k][1]
            near = np.linalg.norm(x - (p[0] if e == 0 else p[-1])) < tol.CURVE_MERGE * h and len(p) > 2
            if e == 0:
                lines[k][1] = np.vstack([x[None], p[1:] if near else p])
            else:
                lines[k][1] = np.vstack([p[:-1] if near else p, x[None]])
    lines = _densify(systems, [(s, p, c, tuple(how)) for s, p, c, how, _ in lines], tol.CREASE_TRACE_STEP)
    lines = _attach_fading_ends(systems, lines, h)
    lines = _join_crossings(systems, lines, h)
    return _join_on_box(surface, _curve_set(systems, lines, box, step), box, step)


def crease_gap(curves: CurveSet, box: np.ndarray, fine_level: int) -> float:
    """The smallest distance (max norm, fine cells) between two points of the creases that are apart.

    Two vertices of the curve graph are apart when the way between them
    along the graph is more than ``CREASE_GAP_DETOUR`` times their distance
    (two creases, or two stretches of one; not two creases near the corner
    where they meet).  ``inf`` when no such pair is closer than
    ``CREASE_MIN_GAP`` cells.
    """
    n = len(curves.points)
    if n < 2:
        return float("inf")
    box = np.asarray(box, dtype=float)
    cell = (box[:, 1] - box[:, 0]) / (1 << fine_level)
    p = curves.points / cell
    pairs = cKDTree(p).query_pairs(tol.CREASE_MIN_GAP, p=np.inf, output_type="ndarray")
    if len(pairs) == 0:
        return float("inf")
    d = np.linalg.norm(p[pairs[:, 0]] - p[pairs[:, 1]], axis=1)
    e = curves.edges
    # A crease that ends inside the box (its kink fades out) is joined to
    # what lies within CREASE_MIN_GAP cells of its end: creases fading out
    # where they meet (z - |x| max(y, 0)) are not apart there.
    degree = np.bincount(e.ravel(), minlength=n)
    inner = ~_faces_hit(curves.points, box).any(axis=(1, 2))
    ends = np.nonzero((degree == 1) & inner)[0]
    if len(ends):
        near = cKDTree(p).query_ball_point(p[ends], tol.CREASE_MIN_GAP, p=np.inf)
        extra = np.array([(a, b) for a, nb in zip(ends.tolist(), near) for b in nb if b != a], np.int64).reshape(-1, 2)
        e = np.concatenate([e, extra])
    # (+1e-9: csgraph drops explicit zero weights, as two coincident vertices)
    w = np.linalg.norm(p[e[:, 0]] - p[e[:, 1]], axis=1) + 1e-9
    graph = coo_matrix((w, (e[:, 0], e[:, 1])), shape=(n, n)).tocsr()
    src, inv = np.unique(pairs[:, 0], return_inverse=True)
    limit = tol.CREASE_GAP_DETOUR * tol.CREASE_MIN_GAP * np.sqrt(3.0)
    way = dijkstra(graph, directed=False, indices=src, limit=limit)[inv.reshape(-1), pairs[:, 1]]
    apart = way > tol.CREASE_GAP_DETOUR * d
    # A small closed crease (a cone capped by a small disc) bends back on
    # itself with no corner: across it the way is only pi/2 times the
    # distance, which the corner rule above cannot tell from a corner.
    # Along a way that passes no corner, a smaller detour is enough.
    smooth = _without_corners(graph, p, e, n)
    bent = dijkstra(smooth, directed=False, indices=src, limit=limit)[inv.reshape(-1), pairs[:, 1]]
    apart |= np.isfinite(bent) & (bent > tol.CREASE_LOOP_DETOUR * d)
    if not apart.any():
        return float("inf")
    return float(np.abs(p[pairs[apart, 0]] - p[pairs[apart, 1]]).max(axis=1).min())


def _without_corners(graph, points: np.ndarray, edges: np.ndarray, n: int):
    """The crease graph without the edges at its corners.

    A corner is a vertex where the creases do not go straight on: one that
    is not on exactly two edges, or where its two edges turn by more than
    ``CREASE_LOOP_TURN`` degrees.
    """
    e = edges[edges[:, 0] != edges[:, 1]]
    degree = np.bincount(e.ravel(), minlength=n)
    corner = degree != 2
    two = np.nonzero(~corner)[0]
    if len(two):
        # The two neighbours of each vertex of degree two, in edge order.
        ends = np.concatenate([e, e[:, ::-1]])
        ends = ends[np.argsort(ends[:, 0], kind="stable")]
        first = np.searchsorted(ends[:, 0], two)
        a = points[ends[first, 1]] - points[two]
        b = points[ends[first + 1, 1]] - points[two]
        cos = -(a * b).sum(1) / np.maximum(np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1), 1e-300)
        corner[two] = cos < np.cos(np.radians(tol.CREASE_LOOP_TURN))
    g = graph.tocoo()
    keep = ~(corner[g.row] | corner[g.col])
    return coo_matrix((g.data[keep], (g.row[keep], g.col[keep])), shape=(n, n)).tocsr()


def _attach_fading_ends(systems: list, lines: list, h: float) -> list:
    """Creases whose kink fades out on another crease, ending on it (a T junction).

    Where a crease ends inside the box because its kink fades out
    (``"end"``: its gradient jump goes to 0), and another crease passes
    within ``CREASE_CORNER`` steps of that end, the two meet there: in
    z - |x| max(y, 0) the kink of |x| fades at y = 0, on the crease of
    max(y, 0), whose own jump fades at x = 0 too, so neither kink is
    active there and no trace sees the other.  The meeting point (Gauss-
    Newton on both creases' equations) becomes the end, and the other
    crease is cut there, so that :func:`_curve_set` makes it one corner of
    the three ends.  A closed crease is not cut (left as it is).
    """
    lines = list(lines)
    for k in range(len(lines)):
        for e in (0, 1):
            s, p, closed, how = lines[k]
            if closed or how[e] not in ("end", "meet"):
                continue
            x = p[0] if e == 0 else p[-1]
            best = None
            for j, (sj, q, cj, _) in enumerate(lines):
                if j == k or len(q) < 2 or (cj and how[e] != "meet"):
                    continue
                d = np.linalg.norm(q - x, axis=1)
                i = int(np.argmin(d))
                if d[i] <= tol.CREASE_CORNER * h and (best is None or d[i] < best[0]):
                    best = (float(d[i]), j, i)
            if best is None:
                continue
            _, j, i = best
            sj, q, closed_j, how_j = lines[j]
            if how[e] == "meet" and not closed_j and i in (0, len(q) - 1):
                continue  # a corner of ends, which _curve_set joins
            # One crease run onto itself: where it crosses itself (a
            # double point), if it has one there.
            z = _double_point(systems[s], x, h) if s == sj else None
            if z is None:
                z = _corner(systems, sorted({s, sj}), x, h)
            if z is None and how[e] == "meet":
                z = x  # the trace's own meeting point
            if z is None:
                continue
            # This crease ends at z ...
            p = p.copy()
            if how[e] == "meet" and np.linalg.norm(x - z) >= tol.CURVE_MERGE * h:
                # It ran on past its crossing onto the other trace: the
                # vertices beyond z go.
                p = _up_to(p[::-1], z, h)[::-1] if e == 0 else _up_to(p, z, h)
            if e == 0:
                p = np.vstack([z[None], p[1:]]) if np.linalg.norm(p[0] - z) < tol.CURVE_MERGE * h and len(p) > 2 \
                    else np.vstack([z[None], p])
            else:
                p = np.vstack([p[:-1], z[None]]) if np.linalg.norm(p[-1] - z) < tol.CURVE_MERGE * h and len(p) > 2 \
                    else np.vstack([p, z[None]])
            lines[k] = (s, p, False, (("meet", how[1]) if e == 0 else (how[0], "meet")))
            # ... and the other is cut at z (at its vertex i, or next to it).
            if closed_j:
                # A closed crease (the square rim of Max(|x| + |y|, |z|))
                # is opened at z: one line from z round to z, whose two
                # ends become the corner with this end.
                n = len(q)
                if np.linalg.norm(q[i] - z) < 1e-6 * h:
                    rest = np.vstack([q[i + 1:], q[:i]])
                else:
                    ahead = np.dot(z - q[i], q[(i + 1) % n] - q[i]) > 0
                    cut = i + 1 if ahead else i
                    rest = np.vstack([q[cut:], q[:cut]])
                lines[j] = (sj, np.vstack([z[None], rest, z[None]]), False, ("meet", "meet"))
                continue
            if i == 0 or i == len(q) - 1:
                q = q.copy()
                q[i] = z
                hj = list(how_j)
                hj[0 if i == 0 else 1] = "meet"
                lines[j] = (sj, q, False, tuple(hj))
                continue
            if np.linalg.norm(q[i] - z) < 1e-6 * h:
                first, second = np.vstack([q[:i], z[None]]), np.vstack([z[None], q[i + 1:]])
            else:
                # z between vertices i - 1 and i, or i and i + 1.
                ahead = np.dot(z - q[i], q[i + 1] - q[i]) > 0
                cut = i + 1 if ahead else i
                first, second = np.vstack([q[:cut], z[None]]), np.vstack([z[None], q[cut:]])
            lines[j] = (sj, first, False, (how_j[0], "meet"))
            lines.append((sj, second, False, ("meet", how_j[1])))
    return lines


def _up_to(p: np.ndarray, z: np.ndarray, h: float) -> np.ndarray:
    """The polyline p (its last vertices near z) without the vertices at or beyond z.

    Beyond: ahead of z in the direction from the last vertex a step or more
    before z; at least that vertex and the one before stay.
    """
    far = np.nonzero(np.linalg.norm(p - z, axis=1) >= h)[0]
    r = int(far[-1]) if len(far) else 0
    d = z - p[r]
    ahead = (p[r + 1:] - z) @ d > -tol.CURVE_MERGE * h * np.linalg.norm(d)
    keep = r + 1 + (int(np.argmax(ahead)) if ahead.any() else len(ahead))
    return p[:max(keep, 2)]


def _join_crossings(systems: list, lines: list, h: float) -> list:
    """Creases that cross with no vertex in common, cut at the crossing, which becomes a corner.

    Where the two operands of a kink are tangent on the surface (two
    cylinders of one radius joined by Min, the Steinmetz solid), their
    common zeros have a double point: two loops of one crease cross there,
    each traced on its own.  Unjoined, the four half-creases near it were
    taken for creases close together (the fine level raised to its limit)
    and meshed as two tubes through one point.  The crossing is placed by
    Gauss-Newton on G1 = G2 = 0 and grad G1 x grad G2 = 0 (a rank drop:
    :func:`_double_point`); two creases of different kinks crossing, on
    both kinks' equations (:func:`_corner`).
    """
    if not lines:
        return lines
    # Every segment of every trace at once: its line, its first vertex's
    # index, its ends a and b.
    n_seg = np.array([len(p) if closed else len(p) - 1 for _, p, closed, _ in lines])
    line = np.repeat(np.arange(len(lines)), n_seg)
    idx = np.arange(len(line)) - np.repeat(np.cumsum(n_seg) - n_seg, n_seg)
    a = np.concatenate([p[:n] for (_, p, _, _), n in zip(lines, n_seg)]).reshape(-1, 3)
    b = np.concatenate([np.roll(p, -1, axis=0)[:n] for (_, p, _, _), n in zip(lines, n_seg)]).reshape(-1, 3)
    pairs = cKDTree(0.5 * (a + b)).query_pairs(1.5 * h, output_type="ndarray") if len(a) > 1 \
        else np.zeros((0, 2), np.int64)
    u, v = pairs[:, 0], pairs[:, 1]
    # Not two segments near each other along one trace.
    size = np.array([len(p) for _, p, _, _ in lines])[line[u]]
    loop = np.array([closed for _, _, closed, _ in lines], bool)[line[u]]
    gap = np.abs(idx[u] - idx[v])
    gap = np.where(loop, np.minimum(gap, size - gap), gap)
    apart = (line[u] != line[v]) | (gap * np.linalg.norm(b[u] - a[u], axis=1) > tol.CREASE_CORNER * h + 1e-12)
    u, v = u[apart], v[apart]
    x, y, d = _closest(a[u], b[u], a[v], b[v])
    close = d <= tol.CREASE_CROSS * h
    found = []
    for uu, vv, mid in zip(u[close].tolist(), v[close].tolist(), 0.5 * (x[close] + y[close])):
        ku, kv = int(line[uu]), int(line[vv])
        # Ends of traces that meet are corners already (_curve_set).
        if any(not lines[k][2] and min(np.linalg.norm(mid - lines[k][1][0]), np.linalg.norm(mid - lines[k][1][-1]))
               <= tol.CURVE_MERGE * h for k in (ku, kv)):
            continue
        su, sv = lines[ku][0], lines[kv][0]
        z = _double_point(systems[su], mid, h) if su == sv else _corner(systems, sorted({su, sv}), mid, h)
        if z is not None and not any(np.linalg.norm(z - f) <= h for f in found):
            found.append(z)
    # Traces of one crease that stopped on each other ("meet") near its
    # double point, without crossing.
    for k, (sk, p, closed, how) in enumerate(lines):
        for e in (0, 1):
            if closed or how[e] != "meet":
                continue
            x = p[0] if e == 0 else p[-1]
            if not any(j != k and sj == sk and np.linalg.norm(q - x, axis=1).min() <= tol.CREASE_CORNER * h
                       for j, (sj, q, _, _) in enumerate(lines)):
                continue  # it met another kink's crease (a corner)
            z = _double_point(systems[sk], x, h)
            if z is not None and not any(np.linalg.norm(z - f) <= h for f in found):
                found.append(z)
    for z in found:
        lines = _through(systems, lines, z, h)
    return lines


def _through(systems: list, lines: list, z: np.ndarray, h: float) -> list:
    """The traces near the double point z cut back to a step from it and led into it.

    However the traces ran near the crossing (through it, stopped on each
    other a little past it, ended on a vertex of the other branch), every
    vertex within a step of z goes; each stretch left ends at z, joined to
    it by points of its own branch (Newton on the crease and a plane across
    the chord, a quarter step apart).
    """
    out = []
    for s, p, closed, how in lines:
        near = np.linalg.norm(p - z, axis=1) < h
        beside = not closed and any(how[e] in ("meet", "lost") and np.linalg.norm(p[-e] - z) < 2 * h for e in (0, 1))
        if not near.any() and not beside:
            out.append((s, p, closed, how))
            continue
        if near.all():
            continue
        if closed:
            # Start the loop at a vertex that stays, just after a cut.
            start = int(np.nonzero(~near & np.roll(near, 1))[0][0])
            p, near = np.roll(p, -start, axis=0), np.roll(near, -start)
            how = ("meet", "meet")
        # Runs of kept vertices; a run's end next to a cut goes to z.
        keep = np.nonzero(~near)[0]
        breaks = np.nonzero(np.diff(keep) > 1)[0]
        runs = np.split(keep, breaks + 1)
        for r in runs:
            q = p[r]
            if np.linalg.norm(q - z, axis=1).max() < 2 * h:
                continue  # a stub beside the crossing (a trace that turned there)
            # Cut ends, and the trace's own ends beside the crossing, go to z.
            lead0 = r[0] > 0 or closed or (how[0] in ("meet", "lost") and np.linalg.norm(q[0] - z) < 2 * h)
            lead1 = r[-1] < len(p) - 1 or closed or (how[1] in ("meet", "lost") and np.linalg.norm(q[-1] - z) < 2 * h)
            if lead0:
                q = np.vstack([_lead_in(systems[s], q[0], z, h)[::-1], q])
            if lead1:
                q = np.vstack([q, _lead_in(systems[s], q[-1], z, h)])
            out.append((s, q, False, ("meet" if lead0 else how[0], "meet" if lead1 else how[1])))
    return out


def _lead_in(system, v: np.ndarray, z: np.ndarray, h: float) -> np.ndarray:
    """Points from v (excluded) to z (included) on the crease, a quarter step apart."""
    n = max(1, int(np.ceil(np.linalg.norm(z - v) / (h / tol.CREASE_TRACE_STEP))))
    t = np.arange(1, n)[:, None] / n
    chord = v + t * (z - v)
    if len(chord):
        d = (z - v) / np.linalg.norm(z - v)
        planes = np.hstack([np.tile(d, (len(chord), 1)), (chord @ d)[:, None]])
        x, ok = system.newton(chord, 0.5 * np.linalg.norm(z - v) / n, extra=planes)
        chord = x[ok]
    return np.vstack([chord, z[None]])


def _closest(p0, p1, q0, q1):
    """The closest points of the segments p0-p1 and q0-q1 (each (k, 3)), and their distances (k,)."""
    d1, d2, r = p1 - p0, q1 - q0, p0 - q0
    a, e, f = (d1 * d1).sum(1), (d2 * d2).sum(1), (d2 * r).sum(1)
    c, b = (d1 * r).sum(1), (d1 * d2).sum(1)
    with np.errstate(all="ignore"):
        den = a * e - b * b
        s = np.where(den > 1e-300, np.clip((b * f - c * e) / den, 0.0, 1.0), 0.0)
        t = np.where(e > 1e-300, np.clip((b * s + f) / e, 0.0, 1.0), 0.0)
        s = np.where(a > 1e-300, np.clip((b * t - c) / a, 0.0, 1.0), 0.0)
    x, y = p0 + s[:, None] * d1, q0 + t[:, None] * d2
    return x, y, np.linalg.norm(x - y, axis=1)


def _double_point(system, start: np.ndarray, h: float):
    """Where the common zeros of G1, G2 cross themselves near ``start`` (grad G1 x grad G2 = 0), or None."""
    x = np.array(start, float)
    with np.errstate(all="ignore"):
        # Near a double point grad G1 x grad G2 is small beside the
        # gradients (one of them may itself go to 0 there: G1 = A - B of
        # a Min's operands); at a corner with another kink it is not.
        _, g = system.values(x[None])
        size = (np.linalg.norm(g[0, 0]) + np.linalg.norm(g[0, 1])) ** 2
        if not np.linalg.norm(np.cross(g[0, 0], g[0, 1])) <= tol.CREASE_DOUBLE_CROSS * size:
            return None
        for _ in range(tol.CREASE_NEWTON):
            # The residual at x and at x +- eps along each axis, in one call;
            # the Jacobian by central differences.
            eps = tol.CREASE_DIFF_STEP * max(1.0, float(np.abs(x).max()))
            at = _rank_residual(system, x + eps * np.vstack([np.zeros(3), np.eye(3), -np.eye(3)]))
            r, jac = at[0], ((at[1:4] - at[4:7]) / (2 * eps)).T
            if not (np.isfinite(r).all() and np.isfinite(jac).all()):
                return None
            step = np.linalg.lstsq(jac, r, rcond=1e-13)[0]
            x = x - step
            if np.all(np.abs(step) <= 4 * _EPS * np.maximum(np.abs(x), 1.0)):
                break
        v, g = system.values(x[None])
        rank = _rank_residual(system, x[None])[0, 2:]
    size = np.linalg.norm(g[0], axis=1) * max(float(np.abs(x).max()), 1.0)
    good = np.all(np.abs(v[0]) <= tol.CREASE_RESIDUAL * np.maximum(size, 1e-300))
    # grad G1 x grad G2 (scaled by |grad G1| + |grad G2|) vanishes there to
    # rounding; a corner of the crease (a kink of G1 or G2) is no double point.
    good &= bool(np.all(np.abs(rank) <= tol.CREASE_RESIDUAL * float(np.linalg.norm(g[0]))))
    return x if good and np.linalg.norm(x - start) <= h else None


def _rank_residual(system, x: np.ndarray) -> np.ndarray:
    """(k, 5): G1, G2 and grad G1 x grad G2 (scaled to a length) at the points x (k, 3); 0 at a double point."""
    v, g = system.values(x)
    scale = np.maximum(np.linalg.norm(g[:, 0], axis=1) + np.linalg.norm(g[:, 1], axis=1), 1e-300)
    return np.concatenate([v, np.cross(g[:, 0], g[:, 1]) / scale[:, None]], axis=1)


def _faces_hit(points: np.ndarray, box: np.ndarray) -> np.ndarray:
    """(k, 3, 2) bool: which faces of the box the points lie on (to 1e-9 of its size)."""
    size = float(np.max(box[:, 1] - box[:, 0]))
    return np.stack([np.abs(points - box[:, 0]) <= 1e-9 * size, np.abs(points - box[:, 1]) <= 1e-9 * size], -1)


def _join_on_box(surface: Surface, curves: CurveSet, box: np.ndarray, step: float) -> CurveSet:
    """Ends on the box of two creases a few cells apart, joined by the surface's trace on that face.

    Where a corner of creases lies just outside the box (a rotated cube
    poking out of it), its creases end on one face of the box closer than
    the tubes around them are wide: the piece of surface between them
    there has no rail of its own, and the strips reach it only along the
    curve graph.  The trace of that piece on the face (vertices ``step``
    apart, on F = 0 and on the face) joins the two ends as graph edges
    that belong to no crease.
    """
    ends = [(int(v), sp.point) for v, sp in zip(curves.special_vertex.tolist(), curves.special)
            if sp.kind == "end on the box"]
    if len(ends) < 2:
        return curves
    piece = np.full(len(curves.points), -1)
    for i, c in enumerate(curves.pieces):
        piece[np.asarray(c.vertices)] = i
    size = float(np.max(box[:, 1] - box[:, 0]))
    reach = tol.CREASE_BOX_JOIN * step
    new_pts, new_edges = [], []
    n = len(curves.points)
    for i in range(len(ends)):
        for j in range(i + 1, len(ends)):
            (a, pa), (b, pb) = ends[i], ends[j]
            d = float(np.linalg.norm(pb - pa))
            if piece[a] == piece[b] or d > reach:
                continue
            face = (np.abs(pa - box[:, 0]) <= 1e-9 * size) & (np.abs(pb - box[:, 0]) <= 1e-9 * size)
            side = 0
            if not face.any():
                face = (np.abs(pa - box[:, 1]) <= 1e-9 * size) & (np.abs(pb - box[:, 1]) <= 1e-9 * size)
                side = 1
            if not face.any():
                continue
            axis = int(np.argmax(face))
            k = max(1, int(np.ceil(d / step)))
            t = np.arange(1, k)[:, None] / k
            chord = pa + t * (pb - pa)
            with np.errstate(all="ignore"):
                x = surface.project(chord, free=np.arange(3) != axis, iterations=tol.CREASE_NEWTON)
                x[:, axis] = box[axis, side]
                f, g = surface.value_gradient(x)
                off = np.abs(f) / np.linalg.norm(g, axis=1)
            # The trace must run close to the chord (one piece of one face) and lie on F = 0.
            if not (np.all(np.isfinite(x)) and np.all(np.linalg.norm(x - chord, axis=1) <= 0.25 * step)
                    and np.all(off <= 1e-12 * size)):
                continue
            idx = [a] + list(range(n, n + len(x))) + [b]
            n += len(x)
            new_pts.append(x)
            new_edges += list(zip(idx[:-1], idx[1:]))
    if not new_edges:
        return curves
    points = np.vstack([curves.points] + new_pts)
    edges = np.vstack([curves.edges, np.array(new_edges, np.int64)])
    return CurveSet(points=points, edges=edges, pieces=curves.pieces, special=curves.special,
                    special_vertex=curves.special_vertex, wide=np.zeros(len(edges), bool))


def _curve_set(systems: list, lines: list, box: np.ndarray, step: float) -> CurveSet:
    """One graph of the crease polylines: ends that meet are one corner; the pieces and special points."""
    h = tol.CREASE_TRACE_STEP * step
    pts, edges, base = [], [], 0
    end_vertex = []  # (vertex, line, kind)
    for k, (s, p, closed, how) in enumerate(lines):
        n = len(p)
        idx = base + np.arange(n)
        e = np.stack([idx[:-1], idx[1:]], 1)
        if closed:
            e = np.vstack([e, [[idx[-1], idx[0]]]])
        else:
            end_vertex += [(int(idx[0]), k, how[0]), (int(idx[-1]), k, how[1])]
        pts.append(p)
        edges.append(e)
        base += n
    P = np.concatenate(pts)
    E = np.concatenate(edges).reshape(-1, 2)
    remap = np.arange(len(P))
    special: dict[int, str] = {}
    ends = [v for v, _, how in end_vertex if how in ("end", "meet", "lost")]
    if ends:
        g = nx.Graph()
        g.add_nodes_from(ends)
        close = cKDTree(P[ends]).query_pairs(tol.CREASE_CORNER * h, output_type="ndarray")
        g.add_edges_from([(ends[i], ends[j]) for i, j in close.tolist()])
        line_of = {v: k for v, k, _ in end_vertex}
        how_of = {v: how for v, _, how in end_vertex}
        for comp in sorted(nx.connected_components(g), key=min):
            comp = sorted(comp)
            which = sorted({lines[line_of[v]][0] for v in comp})
            x = _corner(systems, which, P[comp].mean(axis=0), h) if len(comp) > 1 else None
            if x is None and len(comp) > 1 and np.ptp(P[comp], axis=0).max() <= tol.CREASE_SAME * h:
                # Ends at one point already (traces that met there) of kinks
                # running along one line (coincident box edges): Gauss-Newton
                # on all their equations is singular, and the point is theirs.
                x = P[comp[0]].copy()
            if x is None:
                for v in comp:
                    special[v] = "end of the trace" if how_of[v] == "lost" else "end of a crease"
                continue
            P[comp[0]] = x
            remap[comp] = comp[0]
            special[comp[0]] = "corner of creases"
    corners = np.array(sorted(v for v, kind in special.items() if kind == "corner of creases"), np.int64)
    if len(corners):
        P[corners] = _pinned(systems, P[corners], h)
    for v, _, how in end_vertex:
        if how == "box":
            special[v] = "end on the box"
        elif how == "lost" and v not in special and remap[v] == v:
            special[v] = "end of the trace"
    # A trace started at a corner of creases whose two ends both meet that
    # corner again, within a step of it, is the corner itself (its points
    # coincide with it): not a crease.
    starts = np.concatenate([[0], np.cumsum([len(p) for _, p, _, _ in lines])])
    dropped = set()
    for k, (s, p, closed, how) in enumerate(lines):
        v0, v1 = remap[starts[k]], remap[starts[k + 1] - 1]
        if not closed and v0 == v1 and np.linalg.norm(p - P[v0], axis=1).max() <= h:
            dropped.add(k)
    if dropped:
        owner = np.repeat(np.arange(len(lines)), np.diff(starts))
        E = E[~np.isin(owner[E[:, 0]], list(dropped))]
    E = remap[E]
    # Vertices of the graph at one point to rounding are one: a corner
    # placed by Gauss-Newton next to a trace's own vertex on it (a trace
    # started at a sample there), 1e-14 cells apart, was an edge of no
    # length whose two ends crease_gap read as creases 0 cells apart.
    rep = _welded(P, E, set(special), tol.CREASE_WELD * h)
    remap, E = rep[remap], rep[E]
    special = {int(rep[v]): kind for v, kind in sorted(special.items(), key=lambda kv: rep[kv[0]] == kv[0])}
    E = E[E[:, 0] != E[:, 1]]
    E = np.unique(np.sort(E, axis=1), axis=0)
    used = np.zeros(len(P), bool)
    used[E.ravel()] = True
    new = np.cumsum(used) - 1
    P, E = P[used], new[E]
    special = {int(new[v]): kind for v, kind in special.items() if used[v]}
    sp_vertices = sorted(special)
    sp_index = {v: i for i, v in enumerate(sp_vertices)}
    pieces = []
    # Pieces: the lines, with their vertices renumbered.
    base = 0
    for k, (s, p, closed, how) in enumerate(lines):
        verts = new[remap[base + np.arange(len(p))]]
        verts = verts[np.r_[True, verts[1:] != verts[:-1]]]  # (welded neighbours)
        base += len(p)
        if k in dropped:
            continue
        ends = (-1, -1) if closed else (sp_index.get(int(verts[0]), -1), sp_index.get(int(verts[-1]), -1))
        pieces.append(SingularCurve(points=P[verts], type=CREASE, sheets=1, half_sheets=2, closed=closed,
                                    ends=ends, vertices=np.asarray(verts, np.int64)))
    specials = [SpecialPoint(point=P[v].copy(), kind=special[v]) for v in sp_vertices]
    return CurveSet(points=P, edges=E, pieces=pieces, special=specials,
                    special_vertex=np.asarray(sp_vertices, np.int64), wide=np.zeros(len(E), bool))


def _welded(P: np.ndarray, E: np.ndarray, keep: set, reach: float) -> np.ndarray:
    """For each vertex, the vertex it is one with: ends of edges shorter than ``reach``, joined.

    Of a group, a vertex in ``keep`` (a special point) stands for it, else the first.
    """
    rep = np.arange(len(P))
    short = E[np.linalg.norm(P[E[:, 0]] - P[E[:, 1]], axis=1) < reach]
    short = short[short[:, 0] != short[:, 1]]
    if not len(short):
        return rep
    g = nx.Graph()
    g.add_edges_from(short.tolist())
    for comp in nx.connected_components(g):
        comp = sorted(comp)
        head = next((v for v in comp if v in keep), comp[0])
        rep[comp] = head
    return rep


def merge_curve_sets(a: CurveSet, b: CurveSet) -> CurveSet:
    """One CurveSet of two (singular curves and creases), b's vertices after a's."""
    if len(b.points) == 0:
        return a
    if len(a.points) == 0:
        return b
    n = len(a.points)
    wa = a.wide if len(a.wide) == len(a.edges) else np.zeros(len(a.edges), bool)
    wb = b.wide if len(b.wide) == len(b.edges) else np.zeros(len(b.edges), bool)
    return CurveSet(points=np.vstack([a.points, b.points]), edges=np.vstack([a.edges, b.edges + n]),
                    pieces=list(a.pieces) + [replace(c, vertices=c.vertices + n,
                                                              ends=tuple(e + len(a.special) if e >= 0 else -1
                                                                         for e in c.ends)) for c in b.pieces],
                    special=list(a.special) + list(b.special),
                    special_vertex=np.concatenate([a.special_vertex, b.special_vertex + n]),
                    wide=np.concatenate([wa, wb]), wide_radius=max(a.wide_radius, b.wide_radius))
