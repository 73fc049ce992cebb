"""Curves of singular points: found, traced, typed, cut at their special points.

The one-dimensional part of {F = grad F = 0} in the box, as polylines
whose vertices lie on it to rounding (Gauss-Newton on (F, grad F), which
has the curve as a manifold of solutions: steps across it only).

1. Samples: Newton from the centres of the candidate boxes (where F and
   its three derivatives may all vanish), all at once.
2. Tracing: from an uncovered sample, predictor-corrector along the curve
   (predict along the last chord, correct across it) both ways, until the
   box's boundary or back at the start (a closed curve); samples near the
   trace are covered.  Steps of ``CURVE_TRACE_STEP`` vertices, then every
   step is divided by Newton on all its points at once.
3. Crossings: where two traces meet (a triple point of the Roman surface),
   the point where the Hessian's second singular value vanishes along one
   of them, shared by both.
4. Transversal type at every vertex: the plane curve singularity that F
   cuts on the plane normal to the curve (A1 double curve or isolated
   line, A2 cuspidal edge, A3 tacnode edge, D4 triple curve ...), read off
   the 2 x 2 Hessian in that plane and the number of arcs of F = 0 on a
   small circle in it.
5. Special points: crossings, changes of type along a curve (a pinch
   point where a double curve turns into an isolated line), ends on the
   box.  The curves are cut there into pieces of one type each.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import networkx as nx
import numpy as np
from scipy.spatial import cKDTree

from singmesh import tolerances as tol
from singmesh.surface import Surface

from .centre import residual
from .singular import _clumps, _sheets_and_zeroless, candidate_boxes, linked


@dataclass(frozen=True, eq=False)
class SpecialPoint:
    """A point of a singular curve where its type changes or curves meet.

    Attributes
    ----------
    point : (3,) ndarray
    kind : str
        ``"pinch point"``, ``"triple point"``, ``"crossing of curves"``,
        ``"change of type"`` or ``"end on the box"``.
    vertex : int or None
        Index of the point in ``Mesh.curve_lines()[0]``: the mesh vertex,
        or past the vertices for a point no triangle has (on an isolated
        line).  Set by :func:`singmesh.mesh`.
    """

    point: np.ndarray
    kind: str
    vertex: int | None = None

    def describe(self) -> str:
        x, y, z = self.point
        return f"({x:.10g}, {y:.10g}, {z:.10g})  {self.kind}"


@dataclass(frozen=True, eq=False)
class SingularCurve:
    """One piece of a curve of singular points, of one transversal type.

    Attributes
    ----------
    points : (n, 3) ndarray
        The polyline, vertices on the curve to rounding.
    type : str
        Transversal type, e.g. ``"A1 double curve"``, ``"A2 cuspidal edge"``.
    sheets : int
        Sheets of the surface through the curve (0 for an isolated real
        line, 1 for a cuspidal edge, 2 for a double or tacnode curve ...).
    half_sheets : int
        Arcs of F = 0 on a small circle around the curve: the triangles
        each of its mesh edges has.
    closed : bool
    ends : tuple of int
        Indices of the special points at its two ends (into
        :attr:`CurveSet.special`), -1 for none (a closed curve).
    vertices : (n,) int64 ndarray or None
        Indices of ``points`` in ``Mesh.curve_lines()[0]`` (mesh vertices,
        then the points no triangle has); set by :func:`singmesh.mesh`.
    """

    points: np.ndarray
    type: str
    sheets: int
    half_sheets: int
    closed: bool = False
    ends: tuple = (-1, -1)
    vertices: np.ndarray | None = None

    @property
    def length(self) -> float:
        p = np.vstack([self.points, self.points[:1]]) if self.closed else self.points
        return float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum())

    def describe(self) -> str:
        a, b = self.points[0], self.points[-1]
        shape = "closed" if self.closed else f"from ({a[0]:.6g}, {a[1]:.6g}, {a[2]:.6g}) to ({b[0]:.6g}, {b[1]:.6g}, {b[2]:.6g})"
        return (f"{self.type}: {len(self.points)} vertices, length {self.length:.6g}, {shape}, "
                f"{self.sheets} sheet{'s' if self.sheets != 1 else ''}")


@dataclass
class CurveSet:
    """All singular curves in the box as one graph, and their pieces.

    Attributes
    ----------
    points : (n, 3) ndarray   vertices of the curve graph
    edges : (m, 2) int64      its edges
    pieces : list of SingularCurve
    special : list of SpecialPoint
    special_vertex : (k,) int64  graph vertex of each special point
    """

    points: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    edges: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), np.int64))
    pieces: list = field(default_factory=list)
    special: list = field(default_factory=list)
    special_vertex: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    #: Per edge: its sheets stay within a cell or so of each other further
    #: out than the tube's usual reach (tangent branches: A_k, k >= 3) ...
    wide: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))
    #: ... and the tube's radius (cells) along those edges.
    wide_radius: float = 0.0
    #: How many times wider than the gap between its own far stretches the
    #: wide tube of a piece would be (1: every wide tube fits).  Such a
    #: piece (a small loop whose sheets cross at a small angle) gets the
    #: usual tube, and the lattice is made finer for it (``mesh``).
    cramped: float = 1.0

    def __len__(self) -> int:
        return len(self.pieces)


# ---------------------------------------------------------------- samples
def curve_samples(surface: Surface, box: np.ndarray, level: int) -> np.ndarray:
    """Points of the singular locus near the candidate boxes at ``level``, one per box."""
    lo, hi = candidate_boxes(surface, box, level)
    if len(lo) == 0:
        return np.zeros((0, 3))
    if surface.is_polynomial:
        # A sheet of singular points of a polynomial: F nearly a square
        # (x^2 - 1e-20), refused here with what it is, before its boxes are
        # traced as hundreds of curves (and the point search runs out of
        # memory on their ends).  One without zeros (G^2 + e) is no curve.
        _, flat = _sheets_and_zeroless(surface, lo, hi, box)
        lo, hi = lo[~flat], hi[~flat]
        if len(lo) == 0:
            return np.zeros((0, 3))
    # A curve makes a long clump of candidate boxes; isolated points make
    # small ones (a few boxes across): no Newton there.
    label, span = _clumps(np.rint((lo - box[:, 0]) / (hi - lo)).astype(np.int64))
    long = span[label] >= tol.CURVE_MIN_CLUMP
    lo, hi = lo[long], hi[long]
    if len(lo) == 0:
        return np.zeros((0, 3))
    h = float(np.max(hi[0] - lo[0]))
    start = (lo + hi) / 2
    x, ok = _correct(surface, start, None, 2 * h)
    ok &= np.abs(x - start).max(axis=1) <= 2 * h
    ok &= np.all((x >= box[:, 0] - 1e-9 * h) & (x <= box[:, 1] + 1e-9 * h), axis=1)
    return x[ok]


def _limit(surface: Surface) -> float:
    from .singular import accept_residual

    return max(accept_residual(surface), tol.CURVE_RESIDUAL)


def _vertex_limit(surface: Surface) -> float:
    """The residual a vertex of a traced curve must reach (stricter than a sample's :func:`_limit`)."""
    from .singular import accept_residual

    return max(accept_residual(surface), tol.CURVE_VERTEX_RESIDUAL)


# ---------------------------------------------------------------- tracing
def _correct(surface: Surface, q: np.ndarray, across: np.ndarray, h, each: bool = False,
             limit: float | None = None, polish: bool = False):
    """Newton from points q (k, 3) onto the curve, steps orthogonal to ``across`` (k, 3).

    A point is accepted (``ok``) with a relative residual below ``limit``
    (default :func:`_limit`).

    Across a cuspidal or tacnode edge the root is multiple and Newton only
    halves (or takes 2/3 of) the distance per step; each step is therefore
    also tried two and three times as long, and the best kept (the
    multiplicity's step), which restores fast convergence.

    ``h`` is one length or one per point.  With ``each`` every point stops
    on its own (as if corrected alone: many independent searches run at
    once give what they give one by one); otherwise all step until all
    have converged.

    With ``polish`` (a vertex of the curve) the steps in the normal plane
    keep singular values down to ``CURVE_SVD_PLANE_RTOL`` of the largest
    (across an A3 edge the one that matters falls as the square of the
    distance: ``CURVE_SVD_RTOL`` stopped it 5e-7 off the curve) and
    each point ends at its iterate of least residual (noise may blow up a
    step there).  Without, the cut of ``CURVE_SVD_RTOL`` keeps the steps
    tame where other curves pass near (the search for a crossing of two
    cuspidal edges, a meeting point of lost traces).
    """
    x = np.array(q, dtype=float)
    k = len(x)
    hk = np.broadcast_to(np.asarray(h, dtype=float), (k,))
    previous = np.full(k, np.inf)
    least = x.copy()  # each point's iterate with the least residual
    stalled = np.zeros(k, np.int64)
    if across is not None:
        plane = _normal_plane(np.asarray(across, dtype=float))
    live = np.arange(k)
    # A point that a step leaves where it was is a fixed point of the
    # step (each point's step depends on that point alone): it stays,
    # and only its stall count (and whether it was still moving) goes on.
    fixed = np.zeros(k, bool)
    fixed_moving = np.zeros(k, bool)
    # Without a direction held fixed, longer steps could slide along the
    # curve: plain steps then.
    factors = np.array([1.0, 2.0, 3.0]) if across is not None else np.ones(1)
    # Values at each point exactly as the plain call gives them (BLAS
    # takes one point (gemv) in another order than several (gemm)).
    alone = each or k == 1
    with np.errstate(all="ignore"):
        for _ in range(tol.CURVE_NEWTON):
            xs = x[live]
            f, g, hh = _rows_eval(surface.jet, xs, alone)
            r = np.concatenate([f[:, None], g], axis=1)
            j = np.concatenate([g[:, None, :], hh], axis=1)
            if across is None:
                step = _least_squares(j, r, drop_smallest=True)
            else:
                # Least squares in the plane normal to ``across`` itself,
                # not a 3-d step projected onto it: the 3-d step divides
                # rounding noise by the Jacobian's small singular value
                # along the curve, and when ``across`` is a chord a little
                # off the tangent, the projection keeps part of that
                # (Newton then stalls at ~1e-7 on 15-digit input).
                pl = plane[live]
                rtol = tol.CURVE_SVD_PLANE_RTOL if polish else tol.CURVE_SVD_RTOL
                step = np.einsum("kia,ka->ki", pl, _least_squares(j @ pl, r, rtol=rtol))
            length = np.linalg.norm(step, axis=1, keepdims=True)
            moving = length[:, 0] > tol.CURVE_STOP * hk[live]
            if each:
                # Converged (or stuck) points stop here, the others step.
                live, xs, step, length = live[moving], xs[moving], step[moving], length[moving]
                if not len(live):
                    break
            elif not (np.any(moving) or np.any(fixed_moving)):
                break  # converged (or stuck) everywhere
            step *= np.minimum(1.0, 0.5 * hk[live][:, None] / np.maximum(length, 1e-300))
            trials = xs[None] - factors[:, None, None] * step[None]
            fz, gz = _rows_eval(surface.value_gradient, trials.reshape(-1, 3), alone and len(factors) == 1)
            fz, gz = fz.reshape(trials.shape[:2]), gz.reshape(trials.shape)
            norm = np.abs(fz) + np.abs(gz).sum(axis=-1)
            norm = np.where(np.isfinite(norm), norm, np.inf)
            best = np.argmin(norm, axis=0)
            rows = np.arange(len(live))
            new = trials[best, rows]
            x[live] = new
            # At rounding level the residual stops falling: done there.
            now = norm[best, rows]
            stalled[live] = np.where(now >= 0.9 * previous[live], stalled[live] + 1, 0)
            better = now < previous[live]
            least[live[better]] = new[better]
            previous[live] = np.minimum(previous[live], now)
            if each:
                live = live[stalled[live] < 3]
                if not len(live):
                    break
            else:
                stalled[fixed] += 1
                if np.all(stalled >= 3):
                    break
                same = np.all((new == xs) | (np.isnan(new) & np.isnan(xs)), axis=1)
                fixed[live[same]] = True
                fixed_moving[live[same]] = moving[same]
                live = live[~same]
                if not len(live):
                    break  # nothing moves any more
        if polish:
            x = least
        ok = np.isfinite(x).all(axis=1) & (np.linalg.norm(x - q, axis=1) <= hk)
        limit = _limit(surface) if limit is None else limit
        if each:
            res = _rows_eval(lambda y: residual(surface, y), x[ok], True)
        else:
            res = residual(surface, x[ok])
        ok[ok] = res <= limit
        # Above rounding level, a residual Newton cannot reduce is a
        # minimum of F and grad F beside the curve, not a point of it.
        # Rounding level is measured against F's terms at the point (next
        # to a degenerate point all of them are tiny, and a residual below
        # the polynomial's coefficients times 1e-12 may still be all of F:
        # fuzz s1-72, 0.001 off the curve).
        from .singular import accept_residual

        # For a vertex (``polish``) held across a direction only: without
        # one (the meeting point of lost traces, where two cuspidal edges
        # cross and the locus itself is singular) no Newton step explains
        # the residual either.
        check = np.flatnonzero(ok) if polish and across is not None else np.zeros(0, np.int64)
        if len(check):
            check = check[_local_residual(surface, x[check], alone) > accept_residual(surface)]
        if len(check):
            ok[check] = _explained(surface, x[check], plane[check], alone) >= tol.CURVE_EXPLAINED
    return x, ok


def _local_residual(surface: Surface, x: np.ndarray, alone: bool) -> np.ndarray:
    """max(|F| / |F's terms|, |F_i| / |F_i's terms|) at x (k, 3): 0 at an exact zero, ~eps at rounding level.

    The terms' size is at least what rounding x itself moves F and F_i by
    (eps |x| in each coordinate, times |grad F| and the Hessian's rows):
    on a curve in a coordinate plane (Spitz's x^2 = y^3, z = 0) Newton
    leaves z at 1e-57 rather than 0, every term of F_z has a factor z, and
    F_z / its terms is 1 there however close to the curve the point is
    (trace steps refused all along it, the curve cut short).
    """
    f, g = _rows_eval(surface.value_gradient, x, alone)
    mag, gmag = _rows_eval(lambda y: tuple(np.asarray(m, float) for m in surface.magnitudes_each(y)), x, True)
    shift = np.finfo(float).eps * np.abs(x).max(axis=1)
    mag = np.maximum(mag, np.abs(g).sum(axis=1) * shift)
    gmag = np.maximum(gmag, np.abs(surface.hessian(x)).sum(axis=2) * shift[:, None])
    with np.errstate(all="ignore"):
        rf = np.where(f == 0, 0.0, np.abs(f) / np.maximum(mag, 1e-300))
        rg = np.where(g == 0, 0.0, np.abs(g) / np.maximum(gmag, 1e-300)).max(axis=1)
    return np.maximum(rf, rg)


def _explained(surface: Surface, x: np.ndarray, plane: np.ndarray, alone: bool) -> np.ndarray:
    """How much of the residual (F, grad F) at x (k, 3) a Newton step removes: |J s| / |r|.

    Near a point of the curve (of any transversal type) the residual is
    about J times the offset and the fraction is near 1; at a minimum of
    the residual beside the curve (a valley where F and grad F are small
    but not zero: next to a degenerate point of the locus, fuzz s1-73 and
    s1-377) J^T r = 0 and the fraction is at noise level.
    """
    f, g, hh = _rows_eval(surface.jet, x, alone)
    r = np.concatenate([f[:, None], g], axis=1)
    j = np.concatenate([g[:, None, :], hh], axis=1)
    # In the normal plane (``plane``, (k, 3, 2)), no relative cut: across
    # an A_k edge the singular value that explains the residual is itself
    # that small.
    j = j @ plane
    s = _least_squares(j, r, rtol=0.0)
    js = np.einsum("kij,kj->ki", j, s)
    return np.linalg.norm(js, axis=1) / np.maximum(np.linalg.norm(r, axis=1), 1e-300)


def _correct_vertex(surface: Surface, q: np.ndarray, across: np.ndarray, h: float):
    """:func:`_correct` to a curve vertex's residual (:func:`_vertex_limit`).

    Where the first round of Newton stops short of it (linear convergence
    across a cuspidal edge) a second round goes on from there; a point
    in a valley of small F and grad F off the curve stays where it is and
    is refused.
    """
    limit = _vertex_limit(surface)
    x, ok = _correct(surface, q, across, h, limit=limit, polish=True)
    again = ~ok & np.isfinite(x).all(axis=1) & (np.linalg.norm(x - q, axis=1) <= h)
    if again.any():
        y, good = _correct(surface, x[again], across[again], h, limit=limit, polish=True)
        good &= np.linalg.norm(y - q[again], axis=1) <= h
        x[again] = np.where(good[:, None], y, x[again])
        ok[again] = good
    return x, ok


def _rows_eval(fn, x: np.ndarray, alone: bool):
    """fn at the rows of x (n, 3): each row alone if ``alone``, else as rows of a batch of several.

    BLAS multiplies one row by a matrix (gemv) in another order than
    several (gemm), which changes the last bits of a polynomial's value:
    work done for many points at once reproduces the point-by-point
    calls (``alone``), or a batch that has shrunk to one point the batch.
    """
    if alone and len(x) > 1:
        parts = [fn(x[i:i + 1]) for i in range(len(x))]
        if isinstance(parts[0], tuple):
            return tuple(np.concatenate(p) for p in zip(*parts))
        return np.concatenate(parts)
    if not alone and len(x) == 1:
        out = fn(np.concatenate([x, x]))
        return tuple(o[:1] for o in out) if isinstance(out, tuple) else out[:1]
    return fn(x)


def _least_squares(j: np.ndarray, r: np.ndarray, drop_smallest: bool = False,
                   rtol: float = tol.CURVE_SVD_RTOL) -> np.ndarray:
    """Minimum-norm least-squares steps j^+ r, singular values below ``CURVE_SVD_RTOL`` of the largest dropped.

    Near a curve of singular points the Jacobian of (F, grad F) has a
    singular value of rounding size along the curve (exactly zero for
    exact input); inverting it would throw the point far along the curve.
    With ``drop_smallest`` the smallest is always dropped: the step goes
    across the curve, whose tangent that singular vector estimates.  In
    the plane normal to the curve (or with the smallest dropped) no
    absolute floor: small singular values there are a transversal type
    beyond A_k (y^6 + z^3, whose second derivatives vanish to fourth order
    on the curve), and a floor of 1e-11 stopped Newton 7e-4 off the curve.
    """
    # Where F or a derivative is undefined or infinite (the end of sqrt's
    # or asin's domain) no step: the point is not accepted.
    bad = ~(np.isfinite(j).all(axis=(1, 2)) & np.isfinite(r).all(axis=1))
    if bad.any():
        j = np.where(bad[:, None, None], 0.0, j)
        r = np.where(bad[:, None], 0.0, r)
    u, sv, vt = np.linalg.svd(j, full_matrices=False)
    cut = rtol * sv[:, :1]
    keep = sv > cut
    if drop_smallest:
        keep[:, -1] = False
    inv = np.where(keep, 1.0 / np.where(keep, sv, 1.0), 0.0)
    return np.einsum("kji,kj,kj->ki", vt, inv, np.einsum("kij,ki->kj", u, r))


def _normal_plane(t: np.ndarray) -> np.ndarray:
    """Orthonormal bases (k, 3, 2) of the planes normal to the directions t (k, 3)."""
    t = t / np.maximum(np.linalg.norm(t, axis=1, keepdims=True), 1e-300)
    helper = np.where(np.abs(t[:, :1]) < 0.9, np.array([1.0, 0, 0]), np.array([0, 1.0, 0]))
    n1 = _cross(t, helper)
    n1 /= np.linalg.norm(n1, axis=1, keepdims=True)
    return np.stack([n1, _cross(t, n1)], axis=2)


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise cross products of (k, 3) arrays: ``np.cross``'s arithmetic without its overhead."""
    a0, a1, a2 = a[:, 0], a[:, 1], a[:, 2]
    b0, b1, b2 = b[:, 0], b[:, 1], b[:, 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=1)


def _unit(v: np.ndarray) -> np.ndarray:
    return v / max(float(np.linalg.norm(v)), 1e-300)


def _inside(box: np.ndarray, p: np.ndarray) -> bool:
    return bool(np.all((p >= box[:, 0]) & (p <= box[:, 1])))


def _clip(surface: Surface, box: np.ndarray, x: np.ndarray, y: np.ndarray, h: float):
    """The point of the curve on the box's boundary between x (inside) and y (outside)."""
    d = y - x
    with np.errstate(all="ignore"):
        s_lo = np.where(d < 0, (box[:, 0] - x) / d, np.inf)
        s_hi = np.where(d > 0, (box[:, 1] - x) / d, np.inf)
    s = np.minimum(s_lo, s_hi)
    axis = int(np.argmin(s))
    q = x + min(float(s[axis]), 1.0) * d
    value = box[axis, 0] if d[axis] < 0 else box[axis, 1]
    # Newton held in the face's plane stalls on a tangent-sheet curve that
    # meets the face obliquely: Newton across the curve, then along it
    # onto the face (the curve is straight to rounding over that slide).
    # The slide along the chord's direction t, not the curve's tangent,
    # leaves the point off the curve by the slide times their angle (about
    # the curvature times h): each round shrinks the slide by that factor
    # only, so the rounds go on until the slide is at rounding level (three
    # left curve ends 1e-7 to 3e-5 of the box off the surface), as long as
    # each slide is shorter than the one before (a chord nearly along the
    # face, the curve bulging out of the box between its ends: the rounds
    # do not contract and wander off along the face).
    t = _unit(d)
    z = q
    previous = np.inf
    for k in range(tol.CURVE_CLIP_ROUNDS):
        corrected = _correct(surface, z[None], t[None], h)[0][0]
        if abs(t[axis]) <= 1e-3:
            z = corrected
            break
        slide = t * (value - corrected[axis]) / t[axis]
        length = float(np.linalg.norm(slide))
        if k >= 3 and not length < previous:
            break
        z, previous = corrected + slide, length
        if not length > tol.CURVE_STOP * h:
            break
    z[axis] = value
    z = np.clip(z, box[:, 0], box[:, 1])
    # The slides wandered off (a chord a few degrees from the face, the
    # curve bulging out of the box just beyond x: fuzz s1-394's end went
    # back along the face, 3.8e-5 of the box off the surface): the curve's
    # points on the planes across the chord, bisected between x (inside)
    # and y (outside).  Only for an end that is not even a sample of the
    # locus (``_limit``): Crixxi's cuspidal edges leave through edges of
    # the box, where Newton across them converges slowly and the rounds
    # stop between a sample's residual and a vertex's; bisected, those
    # ends came off the second face, and open edges.
    if residual(surface, z[None])[0] > _limit(surface):
        w = _bisect_exit(surface, box, x, y, h)
        if w is not None and residual(surface, w[None])[0] < residual(surface, z[None])[0]:
            z = w
    return _onto_box_edge(surface, box, z, axis, h)


def _onto_box_edge(surface: Surface, box: np.ndarray, z: np.ndarray, axis: int, h: float) -> np.ndarray:
    """The end z (on the face ``axis``) moved onto the box edge the curve leaves through, if it does.

    A curve through an edge (or corner) of the box is located across
    itself only to about the square root of rounding where its Hessian
    has rank one (a cuspidal or tacnode edge: Crixxi's cuspidal edges
    leave its test box through its edges), and its end lands on one face
    a few 1e-8 off the other: the strips' boundary edges from it to the
    rail on the other face then cut the box's corner (open edges inside
    the box), how far off depending on the machine's rounding.  For an
    end within ``CURVE_EDGE_SNAP`` steps of other faces, the curve's
    point on the box edge (Gauss-Newton on F = grad F = 0 along the edge,
    the other coordinates on their faces) replaces it when its residual
    is no larger: the curve goes through the box edge to the input's
    precision.  A curve passing beside the edge keeps its end.
    """
    lo, hi = box[:, 0], box[:, 1]
    face = np.where(np.abs(z - lo) <= np.abs(z - hi), lo, hi)
    near = np.abs(z - face) <= tol.CURVE_EDGE_SNAP * h
    near[axis] = False
    if not near.any():
        return z
    w = np.where(near, face, z)
    free = [a for a in range(3) if a != axis and not near[a]]
    with np.errstate(all="ignore"):
        for _ in range(tol.CURVE_EDGE_NEWTON if free else 0):
            f, g, hh = surface.jet(w[None])
            r = np.concatenate([f, g[0]])
            col = np.concatenate([g[0, free], hh[0, :, free[0]]])
            den = float(col @ col)
            if not den > 0.0:
                break
            step = float(col @ r) / den
            if not np.isfinite(step) or abs(step) > tol.CURVE_EDGE_SNAP * h:
                return z
            w[free[0]] -= step
            if abs(step) <= tol.CURVE_STOP * h:
                break
    if not (_inside(box, w) and residual(surface, w[None])[0] <= residual(surface, z[None])[0]):
        return z
    return w


def _bisect_exit(surface: Surface, box: np.ndarray, x: np.ndarray, y: np.ndarray, h: float):
    """The curve's point on the box's boundary between x (inside) and y (outside), by bisection, or None.

    The curve's point on the plane across the chord at x + s (y - x)
    (Newton in that plane) is inside the box at s = 0 and outside at
    s = 1; ``CURVE_CLIP_BISECT`` halvings of s bracket the exit, and the
    last point inside is put on the face the first outside has crossed.
    """
    d = y - x
    t = _unit(d)
    lo, hi = 0.0, 1.0
    inside, outside = x, None
    for _ in range(tol.CURVE_CLIP_BISECT):
        s = 0.5 * (lo + hi)
        p = _correct(surface, (x + s * d)[None], t[None], h, polish=True)[0][0]
        if not np.isfinite(p).all():
            return None
        if _inside(box, p):
            lo, inside = s, p
        else:
            hi, outside = s, p
    if outside is None:
        return None
    below = outside < box[:, 0]
    axis = int(np.argmax(np.maximum(box[:, 0] - outside, outside - box[:, 1])))
    w = inside.copy()
    w[axis] = box[axis, 0] if below[axis] else box[axis, 1]
    return np.clip(w, box[:, 0], box[:, 1])


def _exit_beyond(box: np.ndarray, x: np.ndarray, y: np.ndarray) -> float:
    """How far beyond y (inside the box) the ray from x through y leaves the box."""
    d = y - x
    with np.errstate(all="ignore"):
        s = np.minimum(np.where(d < 0, (box[:, 0] - x) / d, np.inf), np.where(d > 0, (box[:, 1] - x) / d, np.inf))
    return float((np.min(s) - 1.0) * np.linalg.norm(d))


def back_at_start(y: np.ndarray, pts: list, h: float) -> bool:
    """Whether a trace ``pts`` (its start first) with next vertex ``y`` has come round to its start.

    At the start, or at the first vertex after it: a start Newton left off
    the curve (near a crossing) is never come back to within 0.75 h, and
    the trace went round again and again (two cylinders at fine 256).
    Only after ``CURVE_CLOSE_STEPS`` steps' length: a trace taking short
    steps round a tight turn (the bottom of a U a cell across, fuzz
    s1-278) passes within 0.75 h of its first vertices on the other arm.
    """
    if len(pts) <= 3 or min(np.linalg.norm(y - pts[0]), np.linalg.norm(y - pts[1])) >= 0.75 * h:
        return False
    q = np.vstack([np.asarray(pts), y[None]])
    return float(np.linalg.norm(np.diff(q, axis=0), axis=1).sum()) >= tol.CURVE_CLOSE_STEPS * h


def _transversal(surface: Surface, x: np.ndarray) -> bool:
    """Whether two sheets cross transversally at x: the Hessian's two largest singular values comparable.

    There the locus is a smooth curve, and a trace that loses it at a
    full step is on a tight turn (followed with shorter steps).  Where the
    sheets are near tangent (two branches of the locus close together, a
    crossing of curves: fuzz s1-638) or along a cuspidal edge (rank one)
    it is not.
    """
    sv = np.linalg.svd(surface.hessian(x[None])[0], compute_uv=False)
    return bool(sv[1] >= tol.CURVE_TURN_RANK * sv[0])


def _along(surface: Surface, y: np.ndarray, t: np.ndarray) -> bool:
    """Whether the curve through y (on the locus) runs along t, where that can be read.

    Where two sheets cross transversally at y the curve's tangent is the
    Hessian's kernel.  A step that lands where it runs across t has left
    its curve for another one passing near the predicted point: fuzz
    s1-270's loop, whose two branches meet tangentially at a cubic cone's
    apex, stepped past it onto the double curve crossing there (a vertex
    on that curve, the loop joined to it by edges along it: open edges).
    Elsewhere (a cuspidal edge, the Hessian of rank one) there is no
    kernel direction to compare, and the step stands.
    """
    _, sv, vt = np.linalg.svd(surface.hessian(y[None])[0])
    if not sv[1] >= tol.CURVE_TURN_RANK * sv[0]:
        return True
    return bool(abs(np.dot(vt[2], t)) >= tol.CURVE_TRACE_ALONG)


def _continues(surface: Surface, x: np.ndarray, y: np.ndarray) -> bool:
    """Whether the curve runs from x to y: the chord's midpoint is within ``CURVE_STEP_SAGITTA`` of it.

    Two branches of a double curve passing a cell or two apart (two sheets
    nearly tangent: fuzz s3-474, at 27 degrees to each other) are both
    along the step, and a step from one landed on the other: the trace
    went on along it, the curve was traced twice and its other branch
    never.  Newton from the midpoint across the chord lands on the curve
    between x and y by its sagitta (0.1 of the chord for a turn of 45
    degrees); between two branches it goes half the gap to one of them.
    """
    chord = y - x
    length = float(np.linalg.norm(chord))
    m = 0.5 * (x + y)
    z, ok = _correct(surface, m[None], chord[None], length)
    return bool(ok[0] and np.linalg.norm(z[0] - m) <= tol.CURVE_STEP_SAGITTA * length)


def _kernel_step(surface: Surface, x: np.ndarray, t: np.ndarray, h: float) -> np.ndarray | None:
    """A trace step from x predicted along the curve's own tangent there, or None.

    Where the step along the last chord ``t`` loses the curve, the curve
    has turned within a step: two sheets crossing at a few degrees (fuzz
    s3-474, s3-2, s3-534: the Hessian's second singular value 0.2-2% of
    its first) bend their double curve round in a cell or two, and the
    chord then points off it (a loop's tip never passed, its other arm
    never traced).  Where the Hessian has rank two (two sheets, not a
    cuspidal edge) its kernel is the tangent at x itself; the steps of
    ``CURVE_KERNEL_SCALES`` along it (the side of ``t``) are tried, each
    landing where the curve runs along it, as every step must.
    """
    _, sv, vt = np.linalg.svd(surface.hessian(x[None])[0])
    if not sv[1] >= tol.CURVE_KERNEL_RANK * sv[0]:
        return None
    k = vt[2] if np.dot(vt[2], t) >= 0 else -vt[2]
    for scale in tol.CURVE_KERNEL_SCALES:
        q = x + scale * h * k
        z, ok = _correct_vertex(surface, q[None], k[None], scale * h)
        if ok[0] and np.dot(z[0] - x, k) > 0.3 * scale * h and _along(surface, z[0], k) \
                and _continues(surface, x, z[0]):
            return z[0]
    return None


def _start_direction(surface: Surface, x0: np.ndarray, t0: np.ndarray) -> np.ndarray:
    """The direction a trace from x0 sets out along: the samples' chord ``t0``, or the tangent where that is off it.

    Near the tip of a loop of the double curve (two sheets crossing at a
    few degrees) the samples lie on both arms and their principal
    direction is the arms', not the curve's at x0: the first step along
    it landed on the other arm (fuzz s3-2), which was then traced twice
    and the tip never.  Where the Hessian's kernel is one direction
    (``CURVE_KERNEL_RANK``) and ``t0`` is more than ``CURVE_START_ALONG``
    off it, the kernel (the tangent at x0) is taken, on ``t0``'s side.
    """
    _, sv, vt = np.linalg.svd(surface.hessian(x0[None])[0])
    if not sv[1] >= tol.CURVE_KERNEL_RANK * sv[0] or abs(np.dot(vt[2], t0)) >= tol.CURVE_START_ALONG:
        return t0
    return vt[2] if np.dot(vt[2], t0) >= 0 else -vt[2]


def _trace_one_way(surface: Surface, box: np.ndarray, x0: np.ndarray, t0: np.ndarray, h: float, max_steps: int,
                   earlier: cKDTree | None = None, earlier_points: np.ndarray | None = None,
                   earlier_tangents: np.ndarray | None = None):
    """Vertices from x0 along t0 (x0 excluded) and how the trace ended.

    It ends on the box's boundary ("box"), back at x0 ("closed"), where
    Newton loses the curve ("lost"), or on reaching an earlier trace
    ("joined", its vertex appended: a crossing, or a curve traced from
    both ends).
    """
    pts = [x0]
    t = t0
    for n in range(max_steps):
        x = pts[-1]
        y = None
        for scale in tol.CURVE_TRACE_SCALES:
            if scale < 0.25 and not _transversal(surface, x):
                break
            q = x + scale * h * t
            z, ok = _correct_vertex(surface, q[None], t[None], scale * h)
            if ok[0] and np.dot(z[0] - x, t) > 0.3 * scale * h and _along(surface, z[0], t) \
                    and _continues(surface, x, z[0]):
                y = z[0]
                break
        if y is None:
            y = _kernel_step(surface, x, t, h)
        if y is None:
            return pts[1:], "lost"
        if not _inside(box, y) or _exit_beyond(box, x, y) <= tol.CURVE_MERGE * h / max(1, tol.CURVE_TRACE_STEP):
            # Outside, or so near the face it is heading for that the end
            # placed on the face would be a hair from it (2.3e-8 of the
            # box: zero-area triangles between them, fuzz s1-72): the end.
            pts.append(_clip(surface, box, x, y, h))
            return pts[1:], "box"
        if back_at_start(y, pts, h):
            return pts[1:], "closed"
        if earlier is not None and n > 0:
            d, i = earlier.query(y)
            if d < 0.5 * h and abs(np.dot(earlier_tangents[i], _unit(y - x))) > 0.9 \
                    and (d <= 1e-9 * h or abs(np.dot(_unit(earlier_points[i] - y), _unit(y - x))) > 0.9):
                # Running along an earlier trace (not across it, as at a
                # crossing): the same curve, traced from its other end,
                # its vertex ahead or behind along the curve.  Not one
                # beside it: past a cone's apex on the curve, a branch
                # near the other branches there was joined to one of them
                # 1.2 cells across (fuzz s4-210: the branch beyond never
                # traced).
                pts.append(earlier_points[i])
                return pts[1:], "joined"
        t = _unit(y - x)
        pts.append(y)
    return pts[1:], "lost"


def trace_curves(surface: Surface, box: np.ndarray, samples: np.ndarray, h: float) -> list[tuple[np.ndarray, bool]]:
    """Polylines (points, closed) through all ``samples``, vertices ``h`` apart.

    Traces that lose the curve (near a special point Newton cannot pass,
    where two cuspidal edges meet) are joined at a point of the singular
    locus between their ends.
    """
    box = np.asarray(box, float)
    if len(samples) == 0:
        return []
    order = np.lexsort(samples.T[::-1])
    samples = samples[order]
    tree = cKDTree(samples)
    covered = np.zeros(len(samples), bool)
    diameter = float(np.linalg.norm(box[:, 1] - box[:, 0]))
    max_steps = int(8 * diameter / h) + 16
    spread = 3.0 * h
    out = []
    lost = []  # (line, end) of traces that lost the curve
    earlier_points = np.zeros((0, 3))
    earlier_tangents = np.zeros((0, 3))
    earlier = None
    for i in range(len(samples)):
        if covered[i]:
            continue
        x0 = samples[i]
        near = samples[tree.query_ball_point(x0, spread)]
        covered[i] = True
        if len(near) < 3:
            continue
        t0 = _principal(near)
        # The sample met only a sample's residual (_limit): as the trace's
        # first vertex it is corrected to a vertex's, as every other one
        # is (it stayed ~1e-6 of the box off the curve, fuzz s1-72).
        z, ok = _correct_vertex(surface, x0[None], t0[None], h)
        if not ok[0]:
            # Not on the curve to a vertex's residual: a sample in a valley
            # of small F and grad F beside it (by a degenerate point of the
            # locus, fuzz s1-73), where no trace should start; the curve's
            # other samples start it.
            continue
        x0 = z[0]
        t0 = _start_direction(surface, x0, t0)
        fwd, how_f = _trace_one_way(surface, box, x0, t0, h, max_steps, earlier, earlier_points, earlier_tangents)
        back, how_b = ([], "closed") if how_f == "closed" else \
            _trace_one_way(surface, box, x0, -t0, h, max_steps, earlier, earlier_points, earlier_tangents)
        # The samples' principal direction is the chord of the arc they
        # lie on: at a curve's end on the box, off its tangent by half the
        # arc's turn, Newton across it slides further than the step and
        # the trace that way is lost at once (fuzz s1-542, s1-746: half
        # the curve's end an "end of the trace").  It is tried again along
        # the first step the other way.
        if how_b == "lost" and not back and fwd:
            back, how_b = _trace_one_way(surface, box, x0, -_unit(fwd[0] - x0), h, max_steps, earlier,
                                         earlier_points, earlier_tangents)
        elif how_f == "lost" and not fwd and back:
            fwd, how_f = _trace_one_way(surface, box, x0, -_unit(back[0] - x0), h, max_steps, earlier,
                                        earlier_points, earlier_tangents)
        pts = np.array(back[::-1] + [x0] + fwd)
        if len(pts) < 2:
            # No curve through it (an isolated point's samples): its
            # neighbours need no trace either.
            covered[tree.query_ball_point(x0, spread)] = True
            continue
        for idx in tree.query_ball_point(pts, 1.5 * h):
            covered[idx] = True
        k = len(out)
        out.append((pts, how_f == "closed"))
        if how_b == "lost":
            lost.append((k, 0))
        if how_f == "lost":
            lost.append((k, -1))
        tangent = np.gradient(pts, axis=0) if len(pts) > 1 else np.zeros_like(pts)
        tangent /= np.maximum(np.linalg.norm(tangent, axis=1, keepdims=True), 1e-300)
        earlier_points = np.vstack([earlier_points, pts])
        earlier_tangents = np.vstack([earlier_tangents, tangent])
        earlier = cKDTree(earlier_points)
    return _join_lost(surface, out, lost, h)


def _join_lost(surface: Surface, lines: list, lost: list, h: float) -> list:
    """Lines whose trace was lost, joined at a singular point between their ends."""
    if not lost:
        return lines
    ends = np.array([lines[k][0][e] for k, e in lost])
    # Each lost end's direction, outwards (towards where the curve was lost).
    out = np.array([lines[k][0][e] - lines[k][0][1 if e == 0 else -2] if len(lines[k][0]) > 1 else np.zeros(3)
                    for k, e in lost])
    pairs = cKDTree(ends).query_pairs(tol.CURVE_JOIN * h, output_type="ndarray")
    g = nx.Graph()
    g.add_nodes_from(range(len(lost)))
    g.add_edges_from(pairs.tolist())
    lines = [(p.copy(), c) for p, c in lines]
    for comp in sorted(nx.connected_components(g), key=min):
        comp = sorted(comp)
        if len(comp) < 2:
            continue
        # Where no singular point is found between the ends, the first end
        # (on the curve) is the meeting point.
        if len(comp) >= 3:
            meet = _meeting_point(surface, ends[comp], out[comp], h)
        else:  # one curve lost from both sides: a point between the ends
            z, ok = _correct(surface, ends[comp].mean(axis=0)[None], None, tol.CURVE_JOIN * h)
            meet = z[0] if ok[0] else None
        if meet is None:
            meet = ends[comp[0]]
        # A point of higher type there (a cone's apex on the curve) is
        # where the traces meet, exactly.
        flat = _flat_point(surface, meet, tol.CURVE_JOIN * h)
        if flat is not None:
            meet = flat
        for c in comp:
            k, e = lost[c]
            p, closed = lines[k]
            lines[k] = (np.vstack([meet[None], p]) if e == 0 else np.vstack([p, meet[None]]), closed)
    return lines


def _meeting_point(surface: Surface, ends: np.ndarray, directions: np.ndarray, h: float) -> np.ndarray | None:
    """The point of the singular locus where traces lost near ``ends`` meet, or None.

    Traces are lost where curves of singular points meet and the locus is
    not a smooth curve (two cuspidal edges crossing, as on Crixxi).  The
    lines from the ends along their directions nearly meet there (least
    squares); Newton puts that point on the locus.  Along the curve the
    minimum of :func:`_degeneracy` (which vanishes only at the meeting
    point) is searched too, and the better of the two kept.
    """
    t = directions / np.maximum(np.linalg.norm(directions, axis=1, keepdims=True), 1e-300)
    proj = np.eye(3)[None] - t[:, :, None] * t[:, None, :]
    a, b = proj.sum(axis=0), np.einsum("kij,kj->i", proj, ends)
    start = ends.mean(axis=0)
    if np.linalg.cond(a) < 1e6:
        x = np.linalg.solve(a, b)
        if np.linalg.norm(x - start) <= tol.CURVE_JOIN * h:
            start = x
    z, ok = _correct(surface, start[None], None, tol.CURVE_JOIN * h)
    if not ok[0]:
        return None
    rank1 = _rank_one(surface, ends)
    u = t[0]

    def point(s):
        return _correct(surface, (z[0] + s * u)[None], u[None], 2 * h)[0][0]

    def measure(s):
        # Newton converges slowly next to the meeting point (the locus is
        # more degenerate there): its point is measured even if it has not
        # reached rounding level, or the search would shun the minimum.
        y = point(s)
        return _degeneracy(surface, y, rank1) if np.isfinite(y).all() else np.inf

    best = _golden(measure, -h, h, tol.CURVE_CROSSING_STEPS)
    y, good = _correct(surface, point(best)[None], None, h)
    # The lines' meeting point is often nearer already (the search can be
    # led off by points Newton left short of the locus): the less
    # degenerate of the two is kept.
    if good[0] and _degeneracy(surface, y[0], rank1) < _degeneracy(surface, z[0], rank1):
        return y[0]
    return z[0]


def _flat_point(surface: Surface, x0: np.ndarray, reach: float) -> np.ndarray | None:
    """The point within ``reach`` of x0 on the locus where the Hessian of F vanishes too, or None.

    Where curves of singular points meet at a point of higher type (the
    apex of a cubic cone on a double curve of the cone and another sheet:
    fuzz s1-270, F vanishing to fourth order there), the traces are lost
    short of it, and Newton from between their ends (or along a trace)
    stops anywhere on the locus near it: the curves' meeting vertex was
    0.3 cells off the apex (1.5 cells on a turned copy).  Gauss-Newton
    on the Hessian's entries (Jacobian: the third derivatives), linear
    where they vanish too, goes to such a point if there is one; the
    point kept is the one of smallest Hessian, when that is at most
    ``CURVE_FLAT`` of the Hessian at x0 and the point is on the locus.
    """
    iu = np.triu_indices(3)
    x = np.asarray(x0, float).copy()
    with np.errstate(all="ignore"):
        h0 = float(np.abs(surface.hessian(x[None])[0]).max())
        if not np.isfinite(h0) or h0 == 0.0:
            return None
        best, best_h = None, h0
        for _ in range(tol.CURVE_FLAT_NEWTON):
            t = surface.third_derivatives(x)
            h = surface.hessian(x[None])[0]
            step = np.linalg.lstsq(t[iu[0], iu[1], :], -h[iu], rcond=None)[0]
            if not np.isfinite(step).all():
                break
            x = x + step
            if np.linalg.norm(x - x0) > reach or np.linalg.norm(step) <= 1e-15 * max(1.0, float(np.abs(x).max())):
                break
            size = float(np.abs(surface.hessian(x[None])[0]).max())
            if size < best_h:
                best, best_h = x.copy(), size
    if best is None or best_h > tol.CURVE_FLAT * h0:
        return None
    if residual(surface, best[None])[0] > _vertex_limit(surface):
        return None
    return best


def _golden(f, lo: float, hi: float, steps: int) -> float:
    """Minimum of f on [lo, hi] by golden section."""
    g = (np.sqrt(5.0) - 1) / 2
    c, d = hi - g * (hi - lo), lo + g * (hi - lo)
    fc, fd = f(c), f(d)
    for _ in range(steps):
        if fc <= fd:
            hi, d, fd = d, c, fc
            c = hi - g * (hi - lo)
            fc = f(c)
        else:
            lo, c, fc = c, d, fd
            d = lo + g * (hi - lo)
            fd = f(d)
    return (lo + hi) / 2


def _rank_one(surface: Surface, x: np.ndarray) -> bool:
    """Whether the Hessian has rank one at the curve points x (k, 3): a cuspidal or tacnode edge."""
    sv = np.linalg.svd(surface.hessian(np.asarray(x, float).reshape(-1, 3)), compute_uv=False)
    return bool(np.median(sv[:, 1] / np.maximum(sv[:, 0], 1e-300)) <= tol.CURVE_RANK_RTOL ** 0.5)


def third_derivatives(surface: Surface, x: np.ndarray) -> np.ndarray:
    """The tensor of third derivatives of F at one point x: (3, 3, 3)."""
    return surface.third_derivatives(np.asarray(x, dtype=float))


def _degeneracy(surface: Surface, x: np.ndarray, rank_one: bool) -> float:
    """How far the singular locus at x is from meeting itself.

    Where two curves of rank-2 type cross, the Hessian's second singular
    value vanishes.  Along a cuspidal edge the Hessian has rank one and
    the cubic terms of F on its kernel plane are l^3 (l vanishing on the
    tangent): where two cuspidal edges cross, that cubic vanishes, so its
    size there is the measure (it falls as the cube of the distance).
    """
    h = surface.hessian(x[None])[0]
    _, sv, vt = np.linalg.svd(h)
    if not rank_one:
        return float(sv[1])
    k1, k2 = vt[1], vt[2]
    t = third_derivatives(surface, x)
    cubic = [np.einsum("ijk,i,j,k->", t, a, b, c) for a, b, c in ((k1, k1, k1), (k1, k1, k2), (k1, k2, k2), (k2, k2, k2))]
    return float(np.abs(cubic).sum()) ** (1.0 / 3.0)


def _principal(points: np.ndarray) -> np.ndarray:
    return np.linalg.svd(points - points.mean(axis=0), full_matrices=False)[2][0]


def densify(surface: Surface, polylines: list, pieces: int) -> list:
    """Each step of each polyline divided into ``pieces`` by Newton across its chord, all at once."""
    if pieces <= 1 or not polylines:
        return polylines
    starts, chords, owners = [], [], []
    for k, (p, closed) in enumerate(polylines):
        q = np.vstack([p, p[:1]]) if closed else p
        a, b = q[:-1], q[1:]
        for j in range(1, pieces):
            starts.append(a + (j / pieces) * (b - a))
            chords.append(np.broadcast_to(0, a.shape) + (b - a))
            owners.append(np.stack([np.full(len(a), k), np.arange(len(a)), np.full(len(a), j)], 1))
    q = np.concatenate(starts)
    d = np.concatenate(chords)
    owner = np.concatenate(owners)
    length = np.linalg.norm(d, axis=1)
    t = d / np.maximum(length, 1e-300)[:, None]
    x, ok = _correct_vertex(surface, q, t, float(length.max()) / pieces)
    out = []
    for k, (p, closed) in enumerate(polylines):
        mine = owner[:, 0] == k
        n_seg = len(p) if closed else len(p) - 1
        grid = np.zeros((n_seg, pieces, 3))
        good = np.ones((n_seg, pieces), bool)
        grid[:, 0] = p[:n_seg]
        grid[owner[mine, 1], owner[mine, 2]] = x[mine]
        good[owner[mine, 1], owner[mine, 2]] = ok[mine]
        # A point Newton could not put on the curve is left out.
        dense = grid.reshape(-1, 3)[good.ravel()]
        if not closed:
            dense = np.vstack([dense, p[-1:]])
        out.append((dense, closed))
    return out


# ---------------------------------------------------------------- crossings
def _second_singular_value(surface: Surface, x: np.ndarray) -> np.ndarray:
    return np.linalg.svd(surface.hessian(x), compute_uv=False)[..., 1]


def _crossing_point(surface: Surface, p: np.ndarray, i: int, h: float) -> np.ndarray:
    """Where two curves cross along polyline ``p`` near vertex i.

    On double curves, where the Hessian's second singular value vanishes;
    on cuspidal edges (Hessian of rank one all along, so that measure is
    flat) where :func:`_degeneracy`, the kernel cubic, does.
    """
    a, b = p[max(i - 2, 0)], p[min(i + 2, len(p) - 1)]
    t = _unit(b - a)
    # Read off the curve beside the crossing (at it the rank drops anyway).
    rank1 = _rank_one(surface, np.stack([a, b]))

    def point(s):
        z, _ = _correct(surface, (p[i] + s * t)[None], t[None], 2 * h)
        return z[0]

    def measure(s):
        y = point(s)
        if not np.isfinite(y).all():
            return np.inf
        return _degeneracy(surface, y, True) if rank1 else _second_singular_value(surface, y)

    x = point(_golden(measure, -2.0 * h, 2.0 * h, tol.CURVE_CROSSING_STEPS))
    # Where Newton left the point off the locus (two branches of a curve
    # passing within a step without crossing: fuzz s1-638, a "crossing"
    # 0.025 off F = 0), the vertex of the trace there, on the curve, is
    # the crossing instead.
    if not (np.isfinite(x).all() and residual(surface, x[None])[0] <= _vertex_limit(surface)):
        return p[i].copy()
    return x


def _graph(polylines: list, surface: Surface, h: float, box: np.ndarray | None = None):
    """One vertex array and edge list for all polylines, crossings merged into shared vertices."""
    pts, edges, line_of = [], [], []
    base = 0
    for k, (p, closed) in enumerate(polylines):
        n = len(p)
        pts.append(p)
        line_of.append(np.full(n, k))
        idx = base + np.arange(n)
        e = np.stack([idx[:-1], idx[1:]], 1)
        if closed:
            e = np.vstack([e, [[idx[-1], idx[0]]]])
        edges.append(e)
        base += n
    P = np.concatenate(pts)
    E = np.concatenate(edges)
    line = np.concatenate(line_of)
    local = np.concatenate([np.arange(len(p)) for p, _ in polylines])
    arc, total = [], np.zeros(len(polylines))
    for k, (p, closed) in enumerate(polylines):
        a = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
        total[k] = a[-1] + (np.linalg.norm(p[-1] - p[0]) if closed else np.inf)
        arc.append(a)
    arc = np.concatenate(arc)
    # Vertices of different traces (or far apart along one) closer than
    # a step: a crossing.  Each cluster of them becomes one vertex.
    pairs = cKDTree(P).query_pairs(1.0 * h, output_type="ndarray")
    if len(pairs):
        i, j = pairs[:, 0], pairs[:, 1]
        along = np.abs(arc[i] - arc[j])
        along = np.minimum(along, total[line[i]] - along)
        far = (line[i] != line[j]) | (along > 3.0 * h)
        pairs = pairs[far]
    crossings = []
    if len(pairs):
        g = nx.Graph()
        g.add_edges_from(pairs.tolist())
        for comp in sorted(nx.connected_components(g), key=min):
            comp = sorted(comp)
            i = comp[0]
            k = line[i]
            p = polylines[k][0]
            # Line ends that coincide were joined at a point already
            # placed (_join_lost, or a trace run into an earlier one).
            placed = [m for m in comp if local[m] in (0, len(polylines[line[m]][0]) - 1)
                      and not polylines[line[m]][1]]
            same = [m for m in placed if np.linalg.norm(P[m] - P[placed[0]]) <= 1e-9 * h] if placed else []
            x = P[same[0]].copy() if len(same) >= 2 else _crossing_point(surface, p, int(local[i]), h)
            flat = _flat_point(surface, x, 2.0 * h)
            if flat is not None:
                x = flat
            if box is not None and not _inside(box, x):
                # Curves meeting beyond the box (a plane crossing a cone's
                # double line 0.04 past the face, fuzz s1-186): their ends
                # on the box are each their own.
                continue
            # All members within a step of the crossing (on every trace)
            # become that one vertex.
            near = np.nonzero(np.linalg.norm(P - x, axis=1) <= 0.75 * h)[0]
            members = sorted(set(comp) | set(near.tolist()))
            # Keep at most the nearest vertex of each trace near x.
            keep = {}
            for m in members:
                keep.setdefault(int(line[m]), []).append(m)
            chosen = []
            for lm in keep.values():
                lm.sort(key=lambda m: np.linalg.norm(P[m] - x))
                chosen.append(lm[0])
            crossings.append((x, chosen))
    remap = np.arange(len(P))
    # Points that coincide (a trace clipped twice at the same place on the
    # box) are one vertex.
    same = cKDTree(P).query_pairs(tol.SINGULAR_MERGE * h, output_type="ndarray")
    for i, j in sorted(same.tolist(), reverse=True):
        remap[remap == max(i, j)] = remap[min(i, j)]
    for x, chosen in crossings:
        target = chosen[0]
        P[target] = x
        remap[np.isin(remap, remap[chosen])] = remap[target]
    E = remap[E]
    E = E[E[:, 0] != E[:, 1]]
    E = _drop_chords(P, np.unique(np.sort(E, axis=1), axis=0))
    E = _drop_doubled_paths(P, E, h)
    used = np.zeros(len(P), bool)
    used[E.ravel()] = True
    new = np.cumsum(used) - 1
    cross_vertices = np.unique([new[remap[c[0]]] for _, c in crossings]).astype(np.int64) if crossings else np.zeros(0, np.int64)
    return P[used], new[E], cross_vertices


def _drop_chords(P: np.ndarray, E: np.ndarray) -> np.ndarray:
    """The curve graph's edges (m, 2) without the longest edge of each triangle.

    Where curves run closer than a step (curves tangent at the point
    where they meet), merging crossings can join two vertices that a
    trace also joins through a third: two paths, one the chord of the
    other, along one curve.  The strips zip to both (edges of three
    triangles); the path is kept.
    """
    from scipy.sparse import coo_matrix

    for _ in range(8):
        n = len(P)
        if len(E) < 3:
            return E
        a = coo_matrix((np.ones(2 * len(E)), (np.concatenate([E[:, 0], E[:, 1]]), np.concatenate([E[:, 1], E[:, 0]]))),
                       shape=(n, n)).tocsr()
        # Edges (i, j) with a common neighbour: (A @ A)[i, j] > 0.
        common = np.asarray((a @ a)[E[:, 0], E[:, 1]]).ravel()
        tri = np.nonzero(common > 0)[0]
        if len(tri) == 0:
            return E
        length = np.linalg.norm(P[E[:, 0]] - P[E[:, 1]], axis=1)
        # The longest edge of its triangles goes: an edge in a triangle
        # whose two other edges are both shorter.
        drop = np.zeros(len(E), bool)
        index = {(int(i), int(j)): k for k, (i, j) in enumerate(E.tolist())}
        for k in tri.tolist():
            i, j = E[k]
            for c in np.intersect1d(a[i].indices, a[j].indices).tolist():
                ki, kj = index[tuple(sorted((int(i), c)))], index[tuple(sorted((int(j), c)))]
                if length[k] > max(length[ki], length[kj]):
                    drop[k] = True
        if not drop.any():
            return E
        E = E[~drop]
    return E


def _drop_doubled_paths(P: np.ndarray, E: np.ndarray, h: float) -> np.ndarray:
    """The curve graph's edges (m, 2) without the longer of two paths that run within a step of each other.

    Curves tangent where they meet (the Tuelle surface's three curves at
    its triple point) run closer than a step for many steps: merging
    crossings there can leave two paths between the same two crossings,
    one on each curve, less than a step apart: one curve at the mesh's
    resolution.  The strips zip to both (edges of three triangles).  A
    cycle of the graph with just two vertices of degree above two, whose
    two paths between them are each within ``CURVE_DOUBLE_PATH`` steps of
    the other, loses the longer path.  Two curves that really part (two
    circles crossing twice) are further apart than that.
    """
    if len(E) < 2:
        return E
    g = nx.Graph()
    g.add_edges_from(E.tolist())
    reach = tol.CURVE_DOUBLE_PATH * h
    drop = set()
    changed = True
    while changed:
        changed = False
        for cycle in sorted(nx.cycle_basis(g), key=lambda c: (len(c), min(c))):
            if len(cycle) > tol.CURVE_DOUBLE_PATH_EDGES:
                continue
            branch = [i for i, v in enumerate(cycle) if g.degree(v) > 2]
            if len(branch) != 2:
                continue
            i, j = branch
            one = cycle[i:j + 1]
            two = cycle[j:] + cycle[:i + 1]
            if len(one) < 3 and len(two) < 3:
                continue
            arc = [float(np.linalg.norm(np.diff(P[q], axis=0), axis=1).sum()) for q in (one, two)]
            near = [float(_point_polyline_distance(P[q[1:-1]], P[r]).max(initial=0.0))
                    for q, r in ((one, two), (two, one))]
            if max(near) > reach:
                continue
            longer = one if (arc[0], len(one)) > (arc[1], len(two)) else two
            edges = list(zip(longer[:-1], longer[1:]))
            g.remove_edges_from(edges)
            g.remove_nodes_from([v for v in longer[1:-1] if g.degree(v) == 0])
            drop.update((min(a, b), max(a, b)) for a, b in edges)
            changed = True
            break
    if not drop:
        return E
    keep = np.array([(int(a), int(b)) not in drop for a, b in E.tolist()], bool)
    return E[keep]


def _point_polyline_distance(x: np.ndarray, line: np.ndarray) -> np.ndarray:
    """Distance from each point of x (k, 3) to the polyline through ``line`` (n, 3)."""
    if len(x) == 0:
        return np.zeros(0)
    a, b = line[:-1], line[1:]
    d = b - a
    dd = np.maximum((d * d).sum(axis=1), 1e-300)
    t = np.clip(((x[:, None, :] - a) * d).sum(axis=2) / dd, 0.0, 1.0)
    return np.linalg.norm(x[:, None, :] - (a + t[..., None] * d), axis=2).min(axis=1)


# ---------------------------------------------------------------- types
def _tangents(points: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Unit tangent at each graph vertex: the sum of its edges' directions, signed alike.

    Edges are stored in any orientation; at each vertex every incident
    edge is counted in the orientation agreeing with the vertex's first
    edge (at a path vertex: the chord from one neighbour to the other).
    """
    t = np.zeros_like(points)
    if len(edges) == 0:
        return np.tile([1.0, 0, 0], (len(points), 1))
    d = points[edges[:, 1]] - points[edges[:, 0]]
    vertex = edges.T.ravel()                     # each incidence: its vertex ...
    edge = np.tile(np.arange(len(edges)), 2)     # ... and its edge
    _, first = np.unique(vertex, return_index=True)
    ref = np.zeros_like(points)
    ref[vertex[first]] = d[edge[first]]
    sign = np.where(np.einsum("ki,ki->k", d[edge], ref[vertex]) >= 0, 1.0, -1.0)
    np.add.at(t, vertex, sign[:, None] * d[edge])
    norm = np.linalg.norm(t, axis=1, keepdims=True)
    return np.where(norm > 0, t / np.maximum(norm, 1e-300), np.array([1.0, 0, 0]))


def transversal_types(surface: Surface, points: np.ndarray, tangents: np.ndarray, radius: float):
    """Transversal type of the curve at each point: (names, sheets, half_sheets).

    In the plane normal to the tangent, G(u, v) = F(p + u n1 + v n2) has a
    plane curve singularity at 0.  The 2 x 2 Hessian of G gives its rank
    (2: A1, with det < 0 two real sheets, det > 0 an isolated real line;
    1: A_k, k >= 2; 0: D4 and beyond); the arcs of G = 0 on the circle of
    ``radius`` give the half-sheets (2: a cuspidal edge, 4: a tacnode
    edge, 6: three sheets).
    """
    k = len(points)
    if k == 0:
        return [], np.zeros(0, np.int64), np.zeros(0, np.int64)
    t = tangents
    helper = np.where(np.abs(t[:, :1]) < 0.9, np.array([1.0, 0, 0]), np.array([0, 1.0, 0]))
    n1 = np.cross(t, helper)
    n1 /= np.linalg.norm(n1, axis=1, keepdims=True)
    n2 = np.cross(t, n1)
    h = surface.hessian(points)
    N = np.stack([n1, n2], axis=2)  # (k, 3, 2)
    hn = np.einsum("kia,kij,kjb->kab", N, h, N)
    lam = np.linalg.eigvalsh(hn)  # ascending
    big = np.abs(lam).max(axis=1)
    small = np.abs(lam).min(axis=1)
    scale = np.abs(h).max(axis=(1, 2))
    theta = np.linspace(0, 2 * np.pi, tol.CURVE_CIRCLE_SAMPLES, endpoint=False)
    ring = radius * (np.cos(theta)[None, :, None] * n1[:, None, :] + np.sin(theta)[None, :, None] * n2[:, None, :])
    g = surface(points[:, None, :] + ring)
    sign = g >= 0  # a zero counts as positive (F + eps)
    arcs = (sign != np.roll(sign, 1, axis=1)).sum(axis=1)
    coeff = surface.scale
    names, sheets = [], np.zeros(k, np.int64)
    for i in range(k):
        a = int(arcs[i])
        if big[i] <= tol.CURVE_RANK_RTOL * coeff:
            rank = 0
        elif small[i] <= tol.CURVE_RANK_RTOL * max(big[i], scale[i]):
            rank = 1
        else:
            rank = 2
        if rank == 2 and small[i] <= tol.CURVE_RANK_MARGIN * big[i] and a != (0 if lam[i, 0] * lam[i, 1] > 0 else 4):
            rank = 1  # a small eigenvalue of rounding noise, the circle says (a cusp read off the curve)
        if rank == 2:
            if lam[i, 0] * lam[i, 1] < 0:
                name, s = "A1 double curve", 2
            else:
                name, s = "A1 isolated line", 0
        elif rank == 1:
            name, s = {2: ("A2 cuspidal edge", 1), 4: ("A3 tacnode edge", 2), 0: ("A3 isolated line", 0)}.get(
                a, (f"A_k edge, {a // 2} sheets", a // 2))
        else:
            name, s = {6: ("D4 triple curve", 3), 2: ("D4 edge, one real sheet", 1)}.get(
                a, (f"corank 2 edge, {a} arcs", a // 2))
        names.append(name)
        sheets[i] = s
    return names, sheets, arcs.astype(np.int64)


# ---------------------------------------------------------------- all of it
def singular_curves(surface: Surface, box, step: float, level: int = 6) -> CurveSet:
    """The curves of singular points in ``box``, with vertices ``step`` apart.

    Parameters
    ----------
    surface : Surface
    box : (3, 2) array_like
    step : float
        Spacing of the curve's vertices (the mesh's fine cell).
    level : int
        Depth of the candidate search for samples.

    Returns
    -------
    CurveSet
    """
    box = np.asarray(box, dtype=float)
    samples = curve_samples(surface, box, level)
    k = max(1, tol.CURVE_TRACE_STEP)
    # Samples of isolated points gather in small clusters: only clusters
    # longer than a few trace steps can hold a curve.
    samples = _long_clusters(samples, float(np.max(box[:, 1] - box[:, 0])) / (1 << level),
                             tol.CURVE_MIN_STEPS * k * step)
    if len(samples) < 3:
        return CurveSet()
    lines = trace_curves(surface, box, samples, k * step)
    lines = [(p, c) for p, c in lines if _extent(p) >= tol.CURVE_MIN_STEPS * k * step]
    if not lines:
        return CurveSet()
    lines = densify(surface, lines, k)
    P, E, cross = _graph(lines, surface, step, box)
    T = _tangents(P, E)
    names, sheets, arcs = transversal_types(surface, P, T, tol.CURVE_CIRCLE_RADIUS * step)
    out = _pieces(surface, box, P, E, cross, names, sheets, arcs, step)
    # The fine cell along each axis (the lattice's: the box's sides over
    # one power of two, the largest ``step``).
    sides = box[:, 1] - box[:, 0]
    return _tube_widths(surface, out, step, sides * (step / float(sides.max())))


#: Special points whose whole ball (CURVE_MEET_BALL cells) is tube
#: (facets.tubes.MEET_KINDS): no wide tube is asked for inside it.
_MEET_KINDS = ("crossing of cuspidal edges",)


def _tube_widths(surface: Surface, curves: CurveSet, step: float, cell: np.ndarray | None = None) -> CurveSet:
    """Which edges need a wide tube, and its radius: from the branches' separation measured across the curve.

    Across a curve of rank-1 type (A_k, k >= 2) the branches are tangent
    and part as |v|^((k+1)/2) at distance v along the Hessian's kernel:
    the tube must reach where they are ``CURVE_BRANCH_GAP`` cells apart
    (the tacnode's square law gives ``CURVE_TANGENT_RADIUS``, an A4 edge
    more).  Measured, not read off the type: the coefficients set the
    scale.  Pieces that need no more than the tacnode's tube keep the
    tube they had (a cuspidal edge: the usual one), except where their own
    vertices need more: a cusp whose coefficient goes to 0 along the curve
    (x^2 = y^2 z^3 near y = 0) has half-sheets within a cell of each other
    far out there, whatever the piece's median.
    """
    if len(curves.edges) == 0:
        return curves
    reach = branch_reach(surface, curves.points, _tangents(curves.points, curves.edges), step)
    v_wide = np.zeros(len(curves.points), bool)
    need = np.zeros(len(curves.points))
    meets = np.array([sp.point for sp in curves.special if sp.kind in _MEET_KINDS]).reshape(-1, 3)
    in_meet_ball = np.zeros(len(curves.points), bool)
    if len(meets):
        d = np.abs(curves.points[:, None, :] - meets[None]).max(axis=2).min(axis=1)
        in_meet_ball = d <= tol.CURVE_MEET_BALL * step
    cross = crossing_reach(surface, curves.points, _tangents(curves.points, curves.edges), step)
    specials = np.array([sp.point for sp in curves.special if sp.kind != "end on the box"]).reshape(-1, 3)
    near_special = np.zeros(len(curves.points), bool)
    if len(specials):
        d = np.abs(curves.points[:, None, :] - specials[None]).max(axis=2).min(axis=1)
        near_special = d <= tol.CURVE_BALL_GROW * step
    apart = None  # distance (cells) from each vertex to the other curves, when needed
    cramped = 1.0
    for c in curves.pieces:
        # A piece as a whole: its median (where a cusp degenerates at a
        # special point, the balls around it widen the tube).  The tacnode
        # edge (two tangent sheets) is wide however measured.
        r = float(np.median(reach[c.vertices]))
        if c.type.startswith("A1") and c.sheets >= 2:
            # Two sheets crossing at a small angle, as a whole piece, away
            # from the special points: at a pinch point or where curves
            # cross the angle goes to 0 on a piece that is wide apart
            # elsewhere (the balls round the points are for that), and a
            # piece of a few vertices between two of them is all ball.
            away = c.vertices[~near_special[c.vertices]]
            if len(away) >= tol.CURVE_CROSSING_MIN_VERTICES:
                rc = float(np.median(cross[away]))
                # An open piece shorter than a few such radii is all ends
                # on the box (a curve across a thin box): the tube would
                # fill it.
                length = float(np.linalg.norm(np.diff(curves.points[c.vertices], axis=0), axis=1).sum()) / step
                if rc > tol.CURVE_CROSSING_RADIUS and (c.closed or length >= tol.CURVE_CROSSING_MIN_LENGTH * rc):
                    if apart is None:
                        apart = _other_curve_distance(curves, np.full(3, step) if cell is None else cell)
                    # Nor on a piece that bends back within twice the wide
                    # tube's reach (max norm, as _tube_leaves grows it) of
                    # itself, a small loop where a plane nearly tangent to
                    # a sphere cuts it: the wide tube swallowed the lens
                    # between the loop's sheets whole, with no rail on it,
                    # and it was left out of the mesh.  Such a piece gets
                    # the usual tube, and a finer lattice (``cramped``).
                    tube_reach = (min(max(rc, tol.CURVE_TANGENT_RADIUS), tol.CURVE_TANGENT_MAX)
                                  - tol.CURVE_TUBE_RADIUS + tol.CURVE_TUBE_GROW + 0.5)
                    room = 2.0 * tube_reach + 1.0
                    gap = _far_gap(curves.points[c.vertices] / (np.full(3, step) if cell is None else cell),
                                   c.closed, room)
                    if gap < room:
                        cramped = max(cramped, room / max(gap, 1.0))
                    # Nor where the wide tube would take in another curve
                    # (CURVE_WIDE_APART): then the usual tube, as a whole.
                    elif apart[c.vertices].min() > rc + tol.CURVE_WIDE_APART:
                        v_wide[c.vertices] = True
                        need[c.vertices] = rc
            continue
        tacnode = c.sheets >= 2 and not c.type.startswith(("A1", "D4"))
        if tacnode or (c.sheets >= 1 and r > tol.CURVE_TANGENT_RADIUS):
            v_wide[c.vertices] = True
            need[c.vertices] = max(r, tol.CURVE_TANGENT_RADIUS) if tacnode else r
        elif c.sheets >= 1:
            # Only where this stretch needs it: the rest keeps the usual tube;
            # and not inside the balls round crossings of cuspidal edges,
            # which are tube whole (a wide tube there joined other sheets).
            # Needed beyond the usual tube's reach into non-simple leaves
            # (CURVE_TUBE_RADIUS + CURVE_TUBE_GROW), not only beyond the
            # wide tube's least radius: just outside the ball round a
            # crossing of cuspidal edges (rotated Crixxi) the half-sheets
            # are 1.5 cells apart only 8 to 10 cells out, and a lattice
            # edge 5.7 cells out crossed both (an edge of four triangles).
            far = (reach[c.vertices] > tol.CURVE_TUBE_RADIUS + tol.CURVE_TUBE_GROW) & ~in_meet_ball[c.vertices]
            v_wide[c.vertices[far]] = True
            need[c.vertices[far]] = reach[c.vertices[far]]
    wide = v_wide[curves.edges].all(axis=1)
    radius = float(np.max(need[curves.edges[wide]], initial=0.0))
    curves.wide = wide
    curves.cramped = cramped
    curves.wide_radius = min(max(radius, tol.CURVE_TANGENT_RADIUS), tol.CURVE_TANGENT_MAX) if wide.any() else 0.0
    return curves


def _other_curve_distance(curves: CurveSet, cell: np.ndarray) -> np.ndarray:
    """Distance (max norm, cells) from each curve vertex to the nearest vertex of another connected curve.

    Measured as the tubes are (:func:`singmesh.facets.tubes._tube_leaves`);
    inf where there is no other curve.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    n = len(curves.points)
    e = curves.edges
    _, label = connected_components(coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n)),
                                    directed=False)
    out = np.full(n, np.inf)
    for k in np.unique(label):
        mine = label == k
        if mine.all():
            break
        out[mine] = cKDTree(curves.points[~mine] / cell).query(curves.points[mine] / cell, p=np.inf)[0]
    return out


def _far_gap(p: np.ndarray, closed: bool, within: float) -> float:
    """The smallest distance (max norm, cells) between far stretches of a piece's polyline ``p`` (in cells).

    Two vertices are of far stretches when the way between them along the
    piece is more than ``CREASE_LOOP_DETOUR`` times their distance (the two
    sides of a loop: pi/2 across a circle).  Only pairs closer than
    ``within`` are looked at: ``inf`` when there are none.
    """
    pairs = cKDTree(p).query_pairs(within, p=np.inf, output_type="ndarray")
    if len(pairs) == 0:
        return float("inf")
    q = np.vstack([p, p[:1]]) if closed else p
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(q, axis=0), axis=1))])
    way = np.abs(s[pairs[:, 0]] - s[pairs[:, 1]])
    if closed:
        way = np.minimum(way, s[-1] - way)
    far = way > tol.CREASE_LOOP_DETOUR * np.linalg.norm(p[pairs[:, 0]] - p[pairs[:, 1]], axis=1)
    if not far.any():
        return float("inf")
    return float(np.abs(p[pairs[far, 0]] - p[pairs[far, 1]]).max(axis=1).min())


def crossing_reach(surface: Surface, points: np.ndarray, tangents: np.ndarray, step: float) -> np.ndarray:
    """Distance (cells) from each curve point at which two crossing sheets are ``CURVE_BRANCH_GAP`` cells apart.

    Where the Hessian in the normal plane is indefinite, with eigenvalues
    big > 0 > -small, the branches are the lines u = +-sqrt(small / big) v
    to first order: 2 r sqrt(small / big) apart at r along the bisector v.
    0 where the Hessian is definite or of rank < 2; at most
    ``CURVE_TANGENT_MAX``.
    """
    out = np.zeros(len(points))
    if len(points) == 0:
        return out
    N = _normal_plane(tangents)
    lam = np.linalg.eigvalsh(np.einsum("kia,kij,kjb->kab", N, surface.hessian(points), N))
    a = np.abs(lam)
    small, big = a.min(axis=1), a.max(axis=1)
    crossing = (lam[:, 0] * lam[:, 1] < 0) & (small > tol.CURVE_RANK_RTOL * big)
    out[crossing] = np.minimum(tol.CURVE_BRANCH_GAP / (2.0 * np.sqrt(small[crossing] / big[crossing])),
                               tol.CURVE_TANGENT_MAX)
    return out


def branch_reach(surface: Surface, points: np.ndarray, tangents: np.ndarray, step: float) -> np.ndarray:
    """Distance (cells) from each curve point at which its branches are ``CURVE_BRANCH_GAP`` cells apart.

    In the normal plane, with u along the Hessian's larger eigenvector
    and v along its kernel, the branches at v cross the polar curve
    G_u = 0 at u*, and are 2 sqrt(-G(u*, v) / a) apart (a = G_uu / 2).
    0 where the Hessian has rank 2 or 0 (transversal sheets) or there
    are no real branches (an isolated line), and ``CURVE_TANGENT_MAX``
    where they stay closer than that out to it.
    """
    k = len(points)
    out = np.zeros(k)
    if k == 0:
        return out
    N = _normal_plane(tangents)
    hn = np.einsum("kia,kij,kjb->kab", N, surface.hessian(points), N)
    lam, vec = np.linalg.eigh(hn)
    order = np.argsort(np.abs(lam), axis=1)
    small = np.take_along_axis(np.abs(lam), order[:, :1], axis=1)[:, 0]
    big = np.take_along_axis(np.abs(lam), order[:, 1:], axis=1)[:, 0]
    rank1 = (big > 0) & (small <= tol.CURVE_RANK_RTOL * big)
    if not rank1.any():
        return out
    idx = np.nonzero(rank1)[0]
    o = order[idx]
    eu = np.einsum("kia,ka->ki", N[idx], np.take_along_axis(vec[idx], o[:, None, 1:], axis=2)[..., 0])
    ev = np.einsum("kia,ka->ki", N[idx], np.take_along_axis(vec[idx], o[:, None, :1], axis=2)[..., 0])
    radii = np.asarray(tol.CURVE_BRANCH_RADII, float)
    found = np.full(len(idx), np.nan)
    real = np.zeros(len(idx), bool)   # branches seen at all (not an isolated line)
    with np.errstate(all="ignore"):
        for r in radii:
            gap = np.zeros(len(idx))
            for side in (1.0, -1.0):
                base = points[idx] + side * r * step * ev
                u = np.zeros(len(idx))
                for _ in range(tol.CURVE_POLAR_NEWTON):
                    x = base + u[:, None] * eu
                    gu = np.einsum("ki,ki->k", surface.gradient(x), eu)
                    guu = np.einsum("ki,kij,kj->k", eu, surface.hessian(x), eu)
                    u = u - np.where(guu != 0, gu / guu, 0.0)
                x = base + u[:, None] * eu
                a = 0.5 * np.einsum("ki,kij,kj->k", eu, surface.hessian(x), eu)
                q = -surface(x) / a
                gap = np.maximum(gap, np.where(np.isfinite(q) & (q > 0), 2.0 * np.sqrt(np.abs(q)), 0.0))
            hit = np.isnan(found) & (gap >= tol.CURVE_BRANCH_GAP * step)
            found[hit] = r
            real |= gap > 0
    out[idx] = np.where(np.isnan(found), np.where(real, tol.CURVE_TANGENT_MAX, 0.0), found)
    return out


def _long_clusters(x: np.ndarray, gap: float, length: float) -> np.ndarray:
    """The points in clusters (single linkage at ``2 gap``) that extend over ``length`` at least."""
    if len(x) < 3:
        return x
    n, label = linked(x, 2.0 * gap)
    lo = np.full((n, 3), np.inf)
    hi = np.full((n, 3), -np.inf)
    np.minimum.at(lo, label, x)
    np.maximum.at(hi, label, x)
    long = (hi - lo).max(axis=1) >= length
    return x[long[label]]


def _extent(p: np.ndarray) -> float:
    return float(np.ptp(p, axis=0).max()) if len(p) else 0.0


def _pieces(surface, box, P, E, cross, names, sheets, arcs, step) -> CurveSet:
    """Cut the graph at crossings, type changes and box ends; one SingularCurve per piece."""
    g = nx.Graph()
    g.add_nodes_from(range(len(P)))
    g.add_edges_from(E.tolist())
    deg = np.array([g.degree(v) for v in range(len(P))])
    size = float(np.max(box[:, 1] - box[:, 0]))
    on_box = np.any((np.abs(P - box[:, 0]) <= 1e-9 * size) | (np.abs(P - box[:, 1]) <= 1e-9 * size), axis=1)
    special: dict[int, str] = {}
    names, sheets, arcs = _near_crossings(g, P, cross[deg[cross] > 2], list(names), sheets.copy(), arcs.copy(),
                                          2.0 * tol.CURVE_CIRCLE_RADIUS * step)
    for v in cross.tolist():
        if deg[v] <= 2:
            continue  # two traces of one curve joined end to end
        branch = {names[w] for w in g.neighbors(v)}
        if deg[v] >= 6:
            special[v] = "triple point"
        elif branch == {"A2 cuspidal edge"} and _transversal_branches(P, v, list(g.neighbors(v))):
            special[v] = "crossing of cuspidal edges"
        else:
            special[v] = "crossing of curves"
    for v in np.nonzero(deg != 2)[0].tolist():
        if v not in special:
            special[v] = "end on the box" if on_box[v] else ("crossing of curves" if deg[v] > 2 else "end of the trace")
    names = list(names)
    P = P.copy()
    for v, x in _tangencies(surface, g, P, names, special, deg, step).items():
        special[v] = "change of type"
        P[v] = x
    jobs = []
    for v in np.nonzero(deg == 2)[0].tolist():
        if v in special:
            continue
        a, b = list(g.neighbors(v))
        if names[a] == names[b] and names[v] != names[a]:
            names[v] = names[a]  # one vertex read otherwise: noise
        elif names[a] != names[b] and names[v] not in (names[a], names[b]):
            # A vertex of lower rank between two types: the special point
            # itself (a pinch point on a split plane).
            special[v] = "pinch point" if {names[a], names[b]} == {"A1 double curve", "A1 isolated line"} \
                else "change of type"
            # ... placed exactly: its neighbours bracket the change.
            jobs.append((v, a, b, names[a], names[b]))
    _place_changes(surface, P, jobs, step)
    # Changes of type along an edge: the special point is placed there.
    extra_pts, extra_names, extra_sheets, extra_arcs = [], [], [], []
    new_edges = []
    n = len(P)
    change = [(a, b) for a, b in E.tolist() if not (names[a] == names[b] or a in special or b in special)]
    placed = _type_changes(surface, P[[a for a, _ in change]], P[[b for _, b in change]],
                           [names[a] for a, _ in change], [names[b] for _, b in change], step)
    placed = iter(placed)
    for a, b in E.tolist():
        if names[a] == names[b] or a in special or b in special:
            new_edges.append((a, b))
            continue
        x = next(placed)
        v = n + len(extra_pts)
        extra_pts.append(x)
        pinch = {names[a], names[b]} == {"A1 double curve", "A1 isolated line"}
        extra_names.append("pinch point" if pinch else "change of type")
        extra_sheets.append(0)
        extra_arcs.append(0)
        special[v] = "pinch point" if pinch else "change of type"
        new_edges += [(a, v), (v, b)]
    if extra_pts:
        P = np.vstack([P, extra_pts])
        names = list(names) + extra_names
        sheets = np.concatenate([sheets, extra_sheets])
        arcs = np.concatenate([arcs, extra_arcs])
    E = np.array(new_edges, np.int64).reshape(-1, 2)
    # A vertex next to a special point placed between two vertices is
    # merged into it (no edge of a fraction of a step).
    remap = np.arange(len(P))
    for a, b in E.tolist():
        for u, w in ((a, b), (b, a)):
            if u in special and w not in special and np.linalg.norm(P[u] - P[w]) < tol.CURVE_MERGE * step:
                remap[w] = u
    E = remap[E]
    E = np.unique(np.sort(E[E[:, 0] != E[:, 1]], axis=1), axis=0)
    # Only the vertices still on an edge (or special) remain.
    used = np.zeros(len(P), bool)
    used[E.ravel()] = True
    used[list(special)] = True
    new = np.cumsum(used) - 1
    P, E = P[used], new[E]
    names = [nm for nm, u in zip(names, used) if u]
    sheets, arcs = sheets[used], arcs[used]
    special = {int(new[v]): kind for v, kind in special.items()}
    g = nx.Graph()
    g.add_nodes_from(range(len(P)))
    g.add_edges_from(E.tolist())
    sp_vertices = sorted(special)
    sp_index = {v: i for i, v in enumerate(sp_vertices)}
    specials = [SpecialPoint(point=P[v].copy(), kind=special[v]) for v in sp_vertices]
    pieces = []
    seen = set()
    for a, b in sorted(E.tolist()):
        if (a, b) in seen or (b, a) in seen:
            continue
        path = _walk(g, a, b, special, seen)
        closed = path[0] == path[-1] and path[0] not in special
        verts = path[:-1] if closed else path
        inner = [v for v in verts if v not in special] or verts
        kinds = [names[v] for v in inner]
        # The most common kind; a tie (a piece of two vertices read two
        # ways) goes to the kind with more arcs, whose tube holds all the
        # sheets, then by name: not by the set's order, which changes with
        # PYTHONHASHSEED (fuzz s4-746 came out two ways).
        most_arcs = {}
        for v, k in zip(inner, kinds):
            most_arcs[k] = max(most_arcs.get(k, 0), int(arcs[v]))
        name = max(most_arcs, key=lambda k: (kinds.count(k), most_arcs[k], k))
        s = int(np.median([sheets[v] for v in inner]))
        half = int(np.median([arcs[v] for v in inner]))
        ends = (-1, -1) if closed else (sp_index.get(path[0], -1), sp_index.get(path[-1], -1))
        pieces.append(SingularCurve(points=P[verts], type=name, sheets=s, half_sheets=half, closed=closed,
                                    ends=ends, vertices=np.asarray(verts, np.int64)))
    return CurveSet(points=P, edges=E, pieces=pieces, special=specials,
                    special_vertex=np.asarray(sp_vertices, np.int64))


def _eigen_ratio(surface: Surface, x: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Signed ratio small / large of the eigenvalues of the Hessian in the plane normal to t, at x (k, 3).

    Negative along a double curve, positive along an isolated line; zero
    where the two (real or complex) sheets through the curve touch.
    """
    frames = np.stack([_normal_frame(ti) for ti in t])  # (k, 3, 2)
    hn = np.einsum("kia,kij,kjb->kab", frames, surface.hessian(x), frames)
    lam = np.linalg.eigvalsh(hn)
    big = np.where(np.abs(lam[:, 0]) >= np.abs(lam[:, 1]), lam[:, 0], lam[:, 1])
    small = np.where(np.abs(lam[:, 0]) >= np.abs(lam[:, 1]), lam[:, 1], lam[:, 0])
    with np.errstate(all="ignore"):
        return np.where(big != 0, small / np.where(big != 0, big, 1.0), 0.0)


def _tangencies(surface: Surface, g: nx.Graph, P: np.ndarray, names: list, special: dict, deg: np.ndarray,
                step: float) -> dict:
    """Points of an A1 curve where its two sheets touch without the type changing on either side.

    Along a double curve (or an isolated line) the normal Hessian's
    eigenvalue ratio r may touch zero at one point and keep its sign: the
    sheets become tangent there (Tobel x^3 z + x^2 + y z^3 + z^4 - 3xyz on
    the y-axis: A1, A3 at 0, A1 again; Kolibri's cusp point).  Both
    neighbouring vertices read the same type, so no change of type is
    seen, yet near it the two sheets stay within a cell of each other
    several cells out and the tube, not widened there, bridged them (an
    edge of four triangles off the curve).  Such a point is a vertex v
    where |r| has a local minimum that the parabola through v and its two
    neighbours puts at ``CURVE_TANGENCY_RTOL`` of theirs or below (|r|
    falls as the square of the distance to a double zero); it is moved
    there along the chord and Newton put it back on the curve.

    Returns {vertex: its new point}.
    """
    cand = []
    for v in np.nonzero(deg == 2)[0].tolist():
        if v in special:
            continue
        a, b = list(g.neighbors(v))
        if a in special or b in special or names[a] != names[b] or not names[a].startswith("A1"):
            continue
        cand.append((v, a, b))
    if not cand:
        return {}
    v, a, b = np.array(cand, np.int64).T
    t = P[b] - P[a]
    t /= np.maximum(np.linalg.norm(t, axis=1, keepdims=True), 1e-300)
    m = np.abs(_eigen_ratio(surface, np.concatenate([P[a], P[v], P[b]]), np.concatenate([t, t, t])))
    ma, mv, mb = m.reshape(3, -1)
    da = np.linalg.norm(P[v] - P[a], axis=1)
    db = np.linalg.norm(P[b] - P[v], axis=1)
    lowest = (mv <= ma) & (mv <= mb)
    # The parabola m0 + m1 s + m2 s^2 through (-da, ma), (0, mv), (db, mb).
    with np.errstate(all="ignore"):
        sa, sb = (ma - mv) / da, (mb - mv) / db
        m2 = (sa + sb) / (da + db)
        m1 = sb - m2 * db
        s_min = np.where(m2 > 0, -m1 / (2 * m2), 0.0)
        low = np.where(m2 > 0, mv - m1 * m1 / (4 * m2), mv)
    hit = lowest & (low <= tol.CURVE_TANGENCY_RTOL * np.maximum(ma, mb)) & np.isfinite(low)
    if not hit.any():
        return {}
    rows = np.nonzero(hit)[0]
    along = np.clip(s_min[rows], -0.5 * da[rows], 0.5 * db[rows])
    start = P[v[rows]] + along[:, None] * t[rows]
    y, ok = _correct(surface, start, t[rows], step, each=True, limit=_vertex_limit(surface), polish=True)
    return {int(v[r]): (y[i] if ok[i] else P[v[r]].copy()) for i, r in enumerate(rows)}


def _transversal_branches(P: np.ndarray, v: int, neighbours: list) -> bool:
    """Whether the edges at v leave in two directions at an angle (two curves crossing).

    Two traces of one curve side by side also make a cluster of vertices
    of degree four, but their branches are all parallel.
    """
    d = P[neighbours] - P[v]
    d /= np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-300)
    return bool((np.abs(d @ d[0]) < 0.9).any())


def _near_crossings(g: nx.Graph, P: np.ndarray, cross: np.ndarray, names: list, sheets: np.ndarray,
                    arcs: np.ndarray, radius: float):
    """Types of the vertices within ``radius`` of a crossing taken from their branch further out.

    The circle that reads the transversal type (:func:`transversal_types`)
    meets the other curve's sheets near a crossing and reads nonsense
    there (an "A3 isolated line" where two cuspidal edges cross): each
    branch has the type of its first vertex beyond ``radius``.
    """
    for v in cross.tolist():
        for w in g.neighbors(v):
            path, prev, cur = [], v, w
            while np.linalg.norm(P[cur] - P[v]) < radius and g.degree(cur) == 2:
                path.append(cur)
                prev, cur = cur, next(u for u in g.neighbors(cur) if u != prev)
            if np.linalg.norm(P[cur] - P[v]) < radius:
                continue  # the branch ends near the crossing: nothing to go by
            for u in path:
                names[u], sheets[u], arcs[u] = names[cur], sheets[cur], arcs[cur]
    return names, sheets, arcs


def _walk(g: nx.Graph, a: int, b: int, special: dict, seen: set) -> list[int]:
    """The path through edge (a, b) between special vertices (or round a loop)."""
    seen.add((a, b))

    def extend(prev, cur, stop):
        out = []
        while cur not in special and cur != stop:
            nxt = [w for w in g.neighbors(cur) if w != prev]
            if len(nxt) != 1:
                break
            w = nxt[0]
            seen.add((cur, w))
            out.append(w)
            prev, cur = cur, w
        return out

    forward = extend(a, b, a)
    path = [a, b] + forward
    if path[-1] == a:
        return path
    backward = extend(b, a, path[-1])
    return backward[::-1] + path


def _place_changes(surface: Surface, P: np.ndarray, jobs: list, step: float) -> None:
    """P[v] = the type change between P[a] and P[b] for each job (v, a, b, name_a, name_b), in place.

    All at once, unless a job's bracket is another job's vertex (which must
    be placed first): then one by one, in order.
    """
    if not jobs:
        return
    moved = {v for v, *_ in jobs}
    if any(a in moved or b in moved for _, a, b, _, _ in jobs):
        for v, a, b, name_a, name_b in jobs:
            P[v] = _type_changes(surface, P[a][None], P[b][None], [name_a], [name_b], step)[0]
        return
    idx = [[v, a, b] for v, a, b, _, _ in jobs]
    v, a, b = np.array(idx, np.int64).T
    P[v] = _type_changes(surface, P[a], P[b], [j[3] for j in jobs], [j[4] for j in jobs], step)


def _type_changes(surface: Surface, a: np.ndarray, b: np.ndarray, names_a: list, names_b: list,
                  step: float) -> np.ndarray:
    """Where the transversal type changes between a[i] and b[i] (k, 3), by bisection, all at once.

    Between two A1 types (a pinch point) the determinant of the normal
    Hessian changes sign: bisection on its sign, to rounding, on points of
    the chord first (no Newton: a Hessian each), then on points Newton put
    on the curve once the bracket is narrow.  Otherwise the type itself is
    bisected, to where it is read reliably.  Each bracket is halved as if
    alone (Newton stops point by point: ``_correct(each=True)``); the
    brackets only share the evaluations.
    """
    k = len(a)
    out = np.zeros((k, 3))
    if k == 0:
        return out
    a, b = np.asarray(a, float), np.asarray(b, float)
    t = np.array([_unit(b[i] - a[i]) for i in range(k)])
    length = np.array([float(np.linalg.norm(b[i] - a[i])) for i in range(k)])
    pinch = np.array([na.startswith("A1") and nb.startswith("A1") for na, nb in zip(names_a, names_b)])
    frames = [_normal_frame(t[i]) for i in range(k)]
    lo, hi = np.zeros(k), np.ones(k)
    x = a.copy()
    place = np.where(pinch, tol.CURVE_PLACE, tol.CURVE_TYPE_PLACE) * step
    sign_lo = np.zeros(k)
    if pinch.any():
        sign_lo[pinch] = np.sign(_normal_dets(surface, a[pinch], [frames[i] for i in np.nonzero(pinch)[0]]))
    live = np.nonzero((hi - lo) * length > place)[0]

    def on_curve(rows, u):
        return _correct(surface, a[rows] + u[:, None] * (b[rows] - a[rows]), t[rows], step, each=True)[0]

    while len(live):
        mid = (lo[live] + hi[live]) / 2
        # Pinch brackets: points on the chord while wide; on the curve
        # once narrow, as the type brackets throughout.
        newton = ~pinch[live] | ((hi[live] - lo[live]) * length[live] <= tol.CURVE_CHORD_PLACE * step)
        xs = a[live] + mid[:, None] * (b[live] - a[live])
        if newton.any():
            xs[newton] = on_curve(live[newton], mid[newton])
        x[live] = xs
        upper = np.zeros(len(live), bool)
        stop = np.zeros(len(live), bool)
        p = pinch[live]
        if p.any():
            rows = live[p]
            f = np.sign(_normal_dets(surface, xs[p], [frames[i] for i in rows]))
            stop[p] = f == 0
            upper[p] = f != sign_lo[rows]
        if (~p).any():
            rows = live[~p]
            read = [transversal_types(surface, y[None], t[i][None], tol.CURVE_CIRCLE_RADIUS * step)[0][0]
                    for y, i in zip(xs[~p], rows)]
            upper[~p] = [nm != names_a[i] for nm, i in zip(read, rows)]
        go = ~stop
        hi[live[go & upper]] = mid[go & upper]
        lo[live[go & ~upper]] = mid[go & ~upper]
        live = live[go]
        live = live[(hi[live] - lo[live]) * length[live] > place[live]]
    out[:] = x
    if pinch.any():
        rows = np.nonzero(pinch)[0]
        out[rows] = on_curve(rows, (lo[rows] + hi[rows]) / 2)
    # Next to a degenerate point of the locus Newton converges slowly and
    # stops with a residual below the vertex's limit (relative: F and grad F
    # are tiny there) but the point 1.7e-6 off the curve (fuzz s1-72, a
    # pinch point): a second round from there goes on to the curve.
    finite = np.isfinite(out).all(axis=1)
    if finite.any():
        rows = np.nonzero(finite)[0]
        y, good = _correct(surface, out[rows], t[rows], step, each=True, limit=_vertex_limit(surface),
                           polish=True)
        out[rows] = np.where(good[:, None], y, out[rows])
    # Each point is a vertex of the curve, so it must be on it to rounding:
    # where Newton cannot put it there (next to a point where the locus is
    # itself singular, as the swallowtail point), the nearer of a and b
    # (both on the curve) is the special point instead.
    finite = np.isfinite(out).all(axis=1)
    on = np.zeros(k, bool)
    on[finite] = _rows_eval(lambda y: residual(surface, y), out[finite], True) <= _vertex_limit(surface)
    nearer_a = np.linalg.norm(out - a, axis=1) <= np.linalg.norm(out - b, axis=1)
    fallback = np.where(nearer_a[:, None], a, b)
    return np.where(on[:, None], out, fallback)


def _normal_frame(t: np.ndarray) -> np.ndarray:
    """An orthonormal basis (3, 2) of the plane normal to the unit vector t."""
    helper = np.array([1.0, 0, 0]) if abs(t[0]) < 0.9 else np.array([0, 1.0, 0])
    n1 = _unit(np.cross(t, helper))
    n2 = np.cross(t, n1)
    return np.stack([n1, n2], axis=1)


def _normal_dets(surface: Surface, x: np.ndarray, frames: list) -> np.ndarray:
    """Determinants of the Hessian at x (k, 3) restricted to each point's normal plane."""
    return np.array([float(np.linalg.det(N.T @ surface.hessian(x[i]) @ N)) for i, N in enumerate(frames)])
