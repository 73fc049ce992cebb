"""A non-polynomial surface F(x, y, z) = 0: interval bounds and Taylor jets.

:class:`ElementarySurface` implements the surface interface (issue #10)
for F built from + - * /, powers (fractional too), sqrt, Abs, Min, Max,
exp, log, sin, cos, tan, asin, acos, atan, sinh, cosh, tanh, asinh, acosh,
atanh.  F is compiled once into an
expression graph (:mod:`singmesh.boxes.intervals`) with its three partial
derivatives; boxes are bounded by vectorised interval arithmetic with
outward rounding (the better of the natural extension and the centred
form F(c) + [grad F](box) . (box - c), intersected), points by floating
point evaluation of the graph, and Taylor expansions by truncated power
series (:mod:`singmesh.jets`).

Box data
--------
A stack of boxes is an (N, 4, 3) float array: rows 0 and 1 are the lower
and upper corners as fractions t of the domain (dyadic, so halving is
exact), rows 2 and 3 the domain's corners a and b.  A corner's coordinate
is ``a + t * (b - a)``, the same double as the octree's
``box[:, 0] + lattice * cell`` for the lattice point t * 2**fine.

Domain rule
-----------
F is *undefined* where sqrt, log or a non-integer power gets a negative
argument (also log of 0 and a negative power of 0), asin or acos one
outside [-1, 1], acosh one below 1, atanh one outside (-1, 1), as in
sympy and numpy, and there is no surface there: values at such points are NaN; on
a box an argument is clipped to the function's domain, so the bounds are
those of F on the part of the box where it is defined, and a box wholly
outside the domain is empty (``excludes_zero`` is True).  Division by an
interval holding 0 (a pole) gives infinite bounds: such boxes are never
simple, and are excluded only where the numerator N of F = N / D
(:meth:`Graph.fraction`: divisors and tan's cosines in D) has one sign on
them (without it every box a pole plane crosses went to the fine level);
a sign change of F across a pole is not a root
(``line_roots`` keeps only roots where |F| is at rounding level relative
to its terms).  Where the surface runs into a pole (x / y = 0, the plane
x = 0, meets the pole y = 0 along the line x = y = 0, where F = 0 / 0),
the boxes that touch the pole hold no vertex on it (F is infinite or
undefined on their faces there); instead, with F = N / D over a common
denominator (sympy's ``cancel``), the curve N = D = 0 is traced as a
crease (:meth:`ElementarySurface.crease_systems`, "pole line") and the
half-sheets on both sides of the pole are zipped to it by the tubes: the
mesh ends exactly on the pole line (its vertices there have F = 0 / 0,
NaN, and a zero normal).  The surface may therefore end where F's domain ends (the
mesh then has a boundary there); :meth:`ElementarySurface.undefined_on`
names a subexpression that is undefined somewhere on given boxes, for a
caller that prefers an error.
"""

from __future__ import annotations

import itertools
from typing import Mapping

import numpy as np
import sympy

from singmesh import tolerances as tol
from singmesh.boxes.intervals import Graph, interval_eval, kink_key, kink_pieces, point_eval
from singmesh.errors import SurfaceError
from singmesh.jets import graph_jets, jet_space
from singmesh.surface import CreaseSystem, Surface, TipSystem, check_variables, polynomial_fraction
from singmesh.syntax import read_equation

_EPS = float(np.finfo(float).eps)
#: Bounds this small are the intervals' outward rounding of an exact zero
#: (boxes.intervals widens by 1e-300 per operation), not a value of F.
_FLAT_FLOOR = 1e-250
_OFFSETS = np.array(np.meshgrid([0, 1], [0, 1], [0, 1], indexing="ij")).reshape(3, -1).T


def _imul(al, ah, bl, bh):
    """Interval product, rounded outwards (0 * inf counts as 0)."""
    with np.errstate(invalid="ignore", over="ignore"):
        p = np.stack([al * bl, al * bh, ah * bl, ah * bh])
    # fmin/fmax skip NaN (0 * inf) without nanmin's warning on all-NaN columns.
    return np.nextafter(np.fmin.reduce(p, axis=0), -np.inf), np.nextafter(np.fmax.reduce(p, axis=0), np.inf)


def _finite_abs(a):
    """|a| where finite, 0 where infinite (NaN stays NaN)."""
    return np.where(np.isinf(a), 0.0, np.abs(a))


def _one_sign(lo, hi):
    """Strictly of one sign on the whole box (NaN: no)."""
    return (lo > 0) | (hi < 0)


class ElementarySurface(Surface):
    """A surface F = 0 with F a non-polynomial elementary function of x, y, z.

    Build it with :meth:`from_expr` (or :meth:`parse` for text).

    Attributes
    ----------
    text : str
    expr : sympy.Expr          F as read (not expanded)
    params : dict[str, float]
    rounding : float           relative precision of the input's numbers
    is_polynomial : bool       False
    degree : int               order of the Taylor jets used (``tol.TAYLOR_ORDER``)
    scale : float              typical size of F's terms: the largest finite
                               :meth:`magnitude` on the 5 x 5 x 5 grid of
                               [-1, 1]^3 (1.0 if none is finite and nonzero)
    """

    is_polynomial = False

    def __init__(self, text: str, expr: sympy.Expr, params: Mapping[str, float] | None = None,
                 rounding: float = _EPS):
        self.text = text
        self.expr = expr
        self.params = dict(params or {})
        self.rounding = max(float(rounding), _EPS)
        self.degree = tol.TAYLOR_ORDER
        g = Graph()
        self._graph = g
        self._f = g.from_sympy(expr)
        if g.ops[self._f] == "const":
            raise SurfaceError(f"F = {expr} is constant: its zero set is empty or everything")
        self._grad = [g.diff(self._f, a) for a in range(3)]
        self._hess = [[g.diff(self._grad[a], b) for b in range(3)] for a in range(3)]
        # Whether F can have poles (then a derivative of one sign does not
        # make F monotone on a box unless F is bounded there).
        self._kinks = [n for n in g.plan([self._f]) if g.ops[n] in ("abs", "max", "min")]
        # R-functions whose crease is split into arcs by may_vanish.
        self._creases = [n for n in g.plan([self._f]) if g.ops[n] == "rfun" and g.args[n][2] in g.arcs
                         and g.arcs[g.args[n][2]] == tuple(g.args[n][:2])]
        self._poles = any(
            g.ops[n] in ("tan", "log", "atanh") or (g.ops[n] in ("powi", "powr") and g.params[n] < 0)
            for n in g.plan([self._f]))
        # F = N / D, for the boxes a pole crosses (None: F has no quotient).
        self._fraction = None
        if self._poles:
            num, den = g.fraction(self._f)
            self._fraction = None if den == g.one else (num, den)
        s = np.linspace(-1.0, 1.0, 5)
        grid = np.stack(np.meshgrid(s, s, s, indexing="ij"), -1).reshape(-1, 3)
        mag = self.magnitude(grid)
        mag = mag[np.isfinite(mag) & (mag > 0)]
        self.scale = float(mag.max()) if len(mag) else 1.0

    # ------------------------------------------------------------ building
    @classmethod
    def from_expr(cls, expr: sympy.Expr, text: str, params: Mapping = None,
                  rounding: float = 0.0) -> "ElementarySurface":
        """Mirror of ``Surface._from_expr`` for a non-polynomial F.

        Raises
        ------
        SurfaceError
            Unknown symbols (the polynomial path's message), unsupported
            functions, a non-real constant, or a constant F.
        """
        check_variables(expr)
        if not expr.free_symbols:
            raise SurfaceError(f"F = {expr} is constant: its zero set is empty or everything")
        values = {k: float(sympy.N(v)) for k, v in (params or {}).items()}
        return cls(text, expr, values, rounding)

    @classmethod
    def parse(cls, text: str, **params) -> "ElementarySurface":
        """Read text in the surface language (as ``Surface.parse``) into an ElementarySurface."""
        eq = read_equation(text, params)
        return cls.from_expr(eq.expr, text, eq.values, eq.rounding)

    def __repr__(self) -> str:
        return f"ElementarySurface({str(self.expr)!r})"

    def __str__(self) -> str:
        return str(self.expr)

    # ------------------------------------------------------------ points
    def _points(self, points):
        p = np.asarray(points, dtype=float)
        return p.reshape(-1, 3), p.shape[:-1]

    def __call__(self, points) -> np.ndarray:
        """F at ``points`` (..., 3); NaN where F is undefined."""
        p, shape = self._points(points)
        return point_eval(self._graph, [self._f], p)[0].reshape(shape)

    def gradient(self, points) -> np.ndarray:
        """grad F at ``points`` (..., 3): (..., 3).  At a kink, the first active piece's."""
        p, shape = self._points(points)
        return np.stack(point_eval(self._graph, self._grad, p), -1).reshape(shape + (3,))

    def value_gradient(self, points) -> tuple[np.ndarray, np.ndarray]:
        p, shape = self._points(points)
        f, *g = point_eval(self._graph, [self._f] + self._grad, p)
        return f.reshape(shape), np.stack(g, -1).reshape(shape + (3,))

    def hessian(self, points) -> np.ndarray:
        """Hessian of F at ``points`` (..., 3): (..., 3, 3), from second-order jets."""
        return self.jet(points)[2]

    def jet(self, points):
        """F, grad F and the Hessian at ``points`` in one pass (second-order Taylor jets).

        Jets, not the derivative graph: they are defined where F is
        analytic although an intermediate is not (cos(k sqrt(u)) at u = 0).
        """
        p, shape = self._points(points)
        sp = jet_space(2)
        t = graph_jets(self._graph, self._f, p, 2)
        e = sp.index
        g = t[:, [e[(1, 0, 0)], e[(0, 1, 0)], e[(0, 0, 1)]]]
        h = np.empty((len(p), 3, 3))
        for a in range(3):
            for b in range(3):
                k = [0, 0, 0]
                k[a] += 1
                k[b] += 1
                h[:, a, b] = t[:, e[tuple(k)]] * (2.0 if a == b else 1.0)
        return t[:, 0].reshape(shape), g.reshape(shape + (3,)), h.reshape(shape + (3, 3))

    def magnitude(self, points) -> np.ndarray:
        """Size of F's terms at ``points``: the scale of its rounding error."""
        p, shape = self._points(points)
        return point_eval(self._graph, [self._f], p, magnitude=True)[1][0].reshape(shape)

    def gradient_magnitude(self, points) -> np.ndarray:
        """The same for the three partial derivatives: (..., 3)."""
        p, shape = self._points(points)
        return np.stack(point_eval(self._graph, self._grad, p, magnitude=True)[1], -1).reshape(shape + (3,))

    def is_zero(self, points) -> np.ndarray:
        """Whether F is zero at ``points`` to within its rounding error (NaN: no)."""
        p, shape = self._points(points)
        (v,), (m,) = point_eval(self._graph, [self._f], p, magnitude=True)
        # (log at 0 is -inf with an infinite magnitude: not a zero)
        return (np.isfinite(v) & (np.abs(v) <= tol.ZERO_ULPS * _EPS * m)).reshape(shape)

    def taylor(self, point, order: int | None = None) -> np.ndarray:
        """Coefficients T[i, j, k] of u^i v^j w^k in F(point + (u, v, w)), degree <= order.

        ``order=None`` means ``degree``.  NaN where F has no expansion at
        the point (outside its domain, sqrt of 0).
        """
        n = self.degree if order is None else int(order)
        s = graph_jets(self._graph, self._f, np.asarray(point, float).reshape(1, 3), n)[0]
        return jet_space(n).tensor(s)

    # ------------------------------------------------------------ boxes
    def enclose(self, box) -> np.ndarray:
        """The whole domain ``box`` (3, 2) as a stack of one box: (1, 4, 3)."""
        box = np.asarray(box, float)
        data = np.zeros((1, 4, 3))
        data[0, 1] = 1.0
        data[0, 2] = box[:, 0]
        data[0, 3] = box[:, 1]
        return data

    @staticmethod
    def split(data: np.ndarray) -> np.ndarray:
        """The eight children of each box: (N, 8, 4, 3), child c at ``offsets[c]``."""
        lo, hi = data[:, 0], data[:, 1]
        mid = (lo + hi) * 0.5  # exact: dyadic fractions
        out = np.empty((len(data), 8, 4, 3))
        o = _OFFSETS[None].astype(bool)
        out[:, :, 0] = np.where(o, mid[:, None], lo[:, None])
        out[:, :, 1] = np.where(o, hi[:, None], mid[:, None])
        out[:, :, 2] = data[:, None, 2]
        out[:, :, 3] = data[:, None, 3]
        return out

    @staticmethod
    def corners(data: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper corners (N, 3) in space of the boxes in ``data``."""
        a, b = data[:, 2], data[:, 3]
        w = b - a
        return a + data[:, 0] * w, a + data[:, 1] * w

    def _value_bounds(self, lo, hi, grad=None, centre=True):
        """Bounds of F: natural extension, intersected with the centred form.

        ``grad``: bounds of grad F on the boxes (list of 3 (lo, hi)), if known.
        """
        g = self._graph
        res = interval_eval(g, [self._f], lo, hi)
        flo, fhi = res.lo[0], res.hi[0]
        if not centre:
            return flo, fhi
        # Centred form only where it can help: F's bounds straddle 0, the
        # box lies in F's domain (a clipped box need not be connected).
        sel = np.nonzero((flo <= 0) & (fhi >= 0) & ~res.clipped)[0]
        if len(sel) == 0:
            return flo, fhi
        l, h = lo[sel], hi[sel]
        if grad is None:
            r = interval_eval(g, self._grad, l, h)
            gl, gh = r.lo, r.hi
        else:
            gl = [x[0][sel] for x in grad]
            gh = [x[1][sel] for x in grad]
        c = (l + h) * 0.5
        fc = interval_eval(g, [self._f], c, c)
        cl, ch = fc.lo[0], fc.hi[0]
        for a in range(3):
            dl = np.nextafter(l[:, a] - c[:, a], -np.inf)
            dh = np.nextafter(h[:, a] - c[:, a], np.inf)
            pl, ph = _imul(gl[a], gh[a], np.minimum(dl, 0.0), np.maximum(dh, 0.0))
            cl = np.nextafter(cl + pl, -np.inf)
            ch = np.nextafter(ch + ph, np.inf)
        ok = np.isfinite(cl) & np.isfinite(ch)
        flo = flo.copy()
        fhi = fhi.copy()
        flo[sel] = np.where(ok, np.maximum(flo[sel], cl), flo[sel])
        fhi[sel] = np.where(ok, np.minimum(fhi[sel], ch), fhi[sel])
        return flo, fhi

    def _gradient_bounds(self, lo, hi, comps):
        """Bounds of the partial derivatives ``comps`` on boxes: an IntervalResult.

        The natural extension, intersected where it straddles 0 with the
        centred form F_a(c) + [grad F_a](box) . (box - c) when F has no
        Abs/Min/Max (their derivatives jump: the Hessian graph does not
        see the jump) and the box lies in F's domain.  Sigmoid blends'
        derivatives lose a factor of several to dependency otherwise.
        """
        g = self._graph
        r = interval_eval(g, [self._grad[a] for a in comps], lo, hi)
        if self._kinks:
            return r
        for k, a in enumerate(comps):
            gl, gh = r.lo[k], r.hi[k]
            sel = np.nonzero((gl <= 0) & (gh >= 0) & ~r.clipped)[0]
            if len(sel) == 0:
                continue
            l, h = lo[sel], hi[sel]
            c = (l + h) * 0.5
            moving = [b for b in range(3) if np.any(h[:, b] > l[:, b])]
            hb = interval_eval(g, [self._hess[a][b] for b in moving], l, h)
            gc = interval_eval(g, [self._grad[a]], c, c)
            cl, ch = gc.lo[0], gc.hi[0]
            for j, b in enumerate(moving):
                dl = np.nextafter(l[:, b] - c[:, b], -np.inf)
                dh = np.nextafter(h[:, b] - c[:, b], np.inf)
                pl, ph = _imul(hb.lo[j], hb.hi[j], np.minimum(dl, 0.0), np.maximum(dh, 0.0))
                cl = np.nextafter(cl + pl, -np.inf)
                ch = np.nextafter(ch + ph, np.inf)
            ok = np.isfinite(cl) & np.isfinite(ch) & ~hb.clipped
            r.lo[k] = gl.copy()
            r.hi[k] = gh.copy()
            r.lo[k][sel] = np.where(ok, np.maximum(gl[sel], cl), gl[sel])
            r.hi[k][sel] = np.where(ok, np.minimum(gh[sel], ch), gh[sel])
        return r

    def _slack(self, flo, fhi, lo, hi):
        """Room for rounding when reading F's bounds: PRUNE_SLACK of their size,
        and at least F's rounding error at the box centre where that matters."""
        # From the finite bounds: F in [1.6, inf] next to a pole (atanh at
        # 1, log at 0) has no zero, and an infinite slack would say it may.
        size = np.maximum(_finite_abs(flo), _finite_abs(fhi))
        slack = tol.PRUNE_SLACK * size
        near = np.nonzero(np.minimum(np.abs(flo), np.abs(fhi)) <= 1e6 * tol.ZERO_ULPS * _EPS * size)[0]
        if len(near):
            c = (lo[near] + hi[near]) * 0.5
            _, (m,) = point_eval(self._graph, [self._f], c, magnitude=True)
            slack[near] = np.fmax(slack[near], tol.ZERO_ULPS * _EPS * m)
        return slack

    def excludes_zero(self, data: np.ndarray) -> np.ndarray:
        """F certainly has no zero on the closed box (with room for rounding): (N,) bool.

        True also on boxes wholly outside F's domain (no surface there).
        """
        lo, hi = self.corners(data)
        flo, fhi = self._value_bounds(lo, hi)
        slack = self._slack(flo, fhi, lo, hi)
        out = (flo > slack) | (fhi < -slack) | np.isnan(flo) | np.isnan(fhi)
        pole = np.nonzero(~out & (np.isinf(flo) | np.isinf(fhi)))[0]
        if len(pole) and self._fraction is not None:
            out[pole] = self._fraction_excludes(lo[pole], hi[pole])
        return out

    def _fraction_excludes(self, lo, hi) -> np.ndarray:
        """N of F = N / D (:meth:`Graph.fraction`) of one sign on the boxes: (k,) bool.

        For boxes a pole crosses (F's bounds infinite): where every
        subexpression of F is finite, F = 0 implies N = 0, so N of one sign
        (beyond ``PRUNE_SLACK`` of its size, for rounding) leaves no zero of
        F in the box, on either side of the pole.  Without this every box
        a pole plane crosses was split to the finest level.
        """
        r = interval_eval(self._graph, [self._fraction[0]], lo, hi)
        nlo, nhi = r.lo[0], r.hi[0]
        slack = tol.PRUNE_SLACK * np.maximum(_finite_abs(nlo), _finite_abs(nhi))
        return np.isfinite(nlo) & np.isfinite(nhi) & ((nlo > slack) | (nhi < -slack))

    def _continuous(self, lo, hi):
        """Where F is bounded on the boxes (no pole): (N,) bool."""
        if not self._poles:
            return np.ones(len(lo), bool)
        r = interval_eval(self._graph, [self._f], lo, hi)
        return np.isfinite(r.lo[0]) & np.isfinite(r.hi[0])

    def _face(self, lo, hi, n, side):
        """The faces normal to ``n`` of boxes (side 0: low, 1: high), as degenerate boxes."""
        lo, hi = lo.copy(), hi.copy()
        side = np.broadcast_to(np.asarray(side), (len(lo),))
        plane = np.where(side == 1, hi[:, n], lo[:, n])
        lo[:, n] = plane
        hi[:, n] = plane
        return lo, hi

    def _face_without_loops(self, lo, hi, n):
        """Whether the curve F + eps = 0 on faces (normal n) has no closed loop."""
        u, v = (n + 1) % 3, (n + 2) % 3
        r = self._gradient_bounds(lo, hi, (u, v))
        # A face partly outside F's domain may hold an end of the surface.
        ok = (_one_sign(r.lo[0], r.hi[0]) | _one_sign(r.lo[1], r.hi[1])) & self._continuous(lo, hi) & ~r.clipped
        rest = np.nonzero(~ok)[0]
        if len(rest):
            # F of one sign on the face: centred form with the face's
            # tangential derivatives (the face is flat along n).
            zero = np.zeros(len(rest))
            grad = [(zero, zero)] * 3
            grad[u] = (r.lo[0][rest], r.hi[0][rest])
            grad[v] = (r.lo[1][rest], r.hi[1][rest])
            flo, fhi = self._value_bounds(lo[rest], hi[rest], grad=grad)
            ok[rest] = ((flo >= 0) | (fhi < 0)) & ~r.clipped[rest]
        return ok

    def simple_axis(self, data: np.ndarray) -> np.ndarray:
        """First axis a such that F_a is of one sign on the box and the curve
        F = 0 on both faces normal to a has no closed loop, else -1: (N,) int64."""
        lo, hi = self.corners(data)
        result = np.full(len(data), -1, np.int64)
        r = self._gradient_bounds(lo, hi, (0, 1, 2))
        # Not simple: boxes with a pole, and boxes partly outside F's domain
        # (the surface may end inside them).
        todo = np.nonzero(self._continuous(lo, hi) & ~r.clipped)[0]
        for a in range(3):
            ok = _one_sign(r.lo[a][todo], r.hi[a][todo])
            cand = todo[ok]
            if len(cand):
                flo, fhi = self._face(lo[cand], hi[cand], a, 0)
                glo, ghi = self._face(lo[cand], hi[cand], a, 1)
                both = self._face_without_loops(np.concatenate([flo, glo]), np.concatenate([fhi, ghi]), a)
                good = both[:len(cand)] & both[len(cand):]
                result[cand[good]] = a
                done = np.zeros(len(data), bool)
                done[cand[good]] = True
                todo = todo[~done[todo]]
            if len(todo) == 0:
                break
        return result

    def face_modes(self, data: np.ndarray, n: int, side, rows: np.ndarray | None = None) -> np.ndarray:
        """0: F_v of one sign on the face (graph over u); 1: F_u of one sign; 2: neither.

        With ``rows``, the boxes ``data[rows]`` only (``side`` theirs)."""
        lo, hi = self.corners(data if rows is None else data[rows])
        lo, hi = self._face(lo, hi, n, side)
        u, v = (n + 1) % 3, (n + 2) % 3
        r = self._gradient_bounds(lo, hi, (u, v))
        cont = self._continuous(lo, hi) & ~r.clipped
        over_u = _one_sign(r.lo[1], r.hi[1]) & cont
        over_v = _one_sign(r.lo[0], r.hi[0]) & cont
        return np.where(over_u, 0, np.where(over_v, 1, 2)).astype(np.int64)

    def may_vanish(self, data: np.ndarray, axes=(0, 1, 2)) -> np.ndarray:
        """F and its partial derivatives along ``axes`` may all vanish on the box: (N,) bool.

        At kinks (Abs, Min, Max) a box passes when some one piece active on
        it may have F and those derivatives all zero: every combination of
        the pieces of the kinks that straddle the box is tried (a crease
        where no piece is singular, the cube's edges, is not a candidate).
        Beyond ``KINK_COMBINATIONS`` combinations the box passes.  The
        continuous kinks of R-functions (sqrt(f^2 + g^2) where f = g = 0)
        keep the hull of the derivatives: their creases pass.
        """
        lo, hi = self.corners(data)
        keep = self._may_vanish(lo, hi, axes, None)
        idx = np.nonzero(keep)[0]
        kinks = self._kinks + self._creases
        if len(idx) == 0 or not kinks:
            return keep
        pieces = kink_pieces(self._graph, kinks, lo[idx], hi[idx])
        flags = np.concatenate(pieces, axis=1)
        straddle = np.stack([p.sum(axis=1) > 1 for p in pieces], 1)
        some = straddle.any(axis=1)
        if not some.any():
            return keep
        idx, flags = idx[some], flags[some]
        patterns, inverse = np.unique(flags, axis=0, return_inverse=True)
        inverse = inverse.reshape(-1)
        widths = [p.shape[1] for p in pieces]
        starts = np.concatenate([[0], np.cumsum(widths)])
        for g_i, pattern in enumerate(patterns):
            members = idx[inverse == g_i]
            choices = []
            for k, node in enumerate(kinks):
                act = np.nonzero(pattern[starts[k]:starts[k + 1]])[0]
                if len(act) > 1:
                    choices.append((kink_key(self._graph, node), act))
            n_combos = int(np.prod([len(c[1]) for c in choices]))
            if n_combos > tol.KINK_COMBINATIONS:
                continue  # kept: too many pieces to try
            found = np.zeros(len(members), bool)
            for combo in itertools.product(*[c[1] for c in choices]):
                force = {c[0]: np.full(len(members), j) for c, j in zip(choices, combo)}
                found |= self._may_vanish(lo[members], hi[members], axes, force, value=False)
                if found.all():
                    break
            keep[members] = found
        return keep

    def _may_vanish(self, lo, hi, axes, force, value=True):
        """The hull test of may_vanish (with pieces forced at kinks: derivatives only)."""
        keep = np.ones(len(lo), bool)
        if len(axes):
            if force is None:
                r = self._gradient_bounds(lo, hi, tuple(axes))
            else:
                r = interval_eval(self._graph, [self._grad[a] for a in axes], lo, hi, force=force)
            for k in range(len(axes)):
                gl, gh = r.lo[k], r.hi[k]
                # The slack from the finite bound only: a derivative in
                # [5, inf] (asin or sqrt at its domain's end) is not 0.
                size = np.maximum(_finite_abs(gl), _finite_abs(gh))
                s = tol.CANDIDATE_SLACK * size
                keep &= (gl <= s) & (gh >= -s)
        idx = np.nonzero(keep)[0]
        if value and len(idx):
            flo, fhi = self._value_bounds(lo[idx], hi[idx])
            slack = np.maximum(tol.CANDIDATE_SLACK * np.maximum(_finite_abs(flo), _finite_abs(fhi)),
                               self._slack(flo, fhi, lo[idx], hi[idx]))
            keep[idx] = (flo <= slack) & (fhi >= -slack)
        return keep

    # ------------------------------------------------------------ kinks
    def crease_systems(self) -> list[CreaseSystem]:
        """The kinks of F as pairs of smooth functions whose common zeros hold the creases.

        A Max or Min node with arguments a_1 ... a_k gives, for each pair
        i < j, G1 = F with the node replaced by a_i and G2 = a_i - a_j;
        an Abs node of a: G1 = F with the node replaced by a, G2 = a; an
        R-function f + g +- sqrt(f^2 + g^2): G1 = f, G2 = g; and where F has
        poles, F = N / D over a common denominator: G1 = N, G2 = D (the
        pole line, where the surface runs into a pole; not a kink, but
        meshed as one: the mesh ends on it).
        """
        if getattr(self, "_crease_systems", None) is None:
            g, f = self._graph, self._f
            out = []
            for k in self._kinks:
                op, args = g.ops[k], g.args[k]
                if op == "abs":
                    a = args[0]
                    out.append(_Kink(self, "Abs crease", g.substitute(f, k, a), a,
                                     g.substitute(f, k, g.neg(a)), (), op))
                    continue
                for i, j in itertools.combinations(range(len(args)), 2):
                    others = tuple(args[m] for m in range(len(args)) if m not in (i, j))
                    out.append(_Kink(self, f"{op} crease of arguments {i}, {j}", g.substitute(f, k, args[i]),
                                     g.sub(args[i], args[j]), g.substitute(f, k, args[j]),
                                     (args[i],) + others, op))
            for k in self._creases:
                fa, ga = g.args[k][:2]
                out.append(_Kink(self, "R-function crease", fa, ga, None, (), "rfun"))
            pole = self._pole_line()
            if pole is not None:
                out.append(pole)
            self._crease_systems = out
        return self._crease_systems

    def tip_systems(self) -> list[TipSystem]:
        """sqrt and powers 0 < p < 1 of sums of two or three squares: :class:`TipSystem` each."""
        return self._roots()[0]

    def root_crease_systems(self) -> list[TipSystem]:
        """sqrt and powers 0 < p < 1 of |u| or u^2: vanishing along a curve of the surface (cuspidal creases)."""
        return self._roots()[1]

    def _roots(self) -> tuple[list, list]:
        """The roots in F that make it non-differentiable where they vanish: (tips, cuspidal creases).

        A root of a sum of two or three squares vanishes on a line or a
        point (tips where that meets F = 0); a root of |u| or u^2 on a
        surface (a curve of F = 0).  An R-function's own root vanishes
        along its crease, traced as one: neither.
        """
        if getattr(self, "_root_systems", None) is None:
            g, f = self._graph, self._f
            tips, creases = [], []
            plan = g.plan([f])
            rfun_roots = {g.args[n][2] for n in plan if g.ops[n] == "rfun"}
            for n in plan:
                op, p = g.ops[n], g.params[n]
                if n in rfun_roots or not (op == "sqrt" or (op == "powr" and 0.0 < float(p) < 1.0)):
                    continue
                a = g.args[n][0]
                squares = g._squares(a) or []
                f0 = g.substitute(f, n, g.zero)  # F where the root vanishes
                if 2 <= len(squares) <= 3:
                    tips.append(_Tip(self, f"{op} of a sum of {len(squares)} squares", [f0] + list(squares)))
                elif g.ops[a] == "abs" or len(squares) == 1:
                    base = g.args[a][0] if g.ops[a] == "abs" else squares[0]
                    creases.append(_Tip(self, f"{op} of |u| or u^2 (u = 0 on a surface)", [f0, base]))
            self._root_systems = (tips, creases)
        return self._root_systems

    def domain_edge_systems(self) -> list[CreaseSystem]:
        """A root sqrt(u) or u^p (0 < p < 1) of F, u not a sum of squares nor |v| or v^2: where u = 0 on the
        surface it ends, F finite there.  (G1, G2) = (F with the root replaced by 0, u) each.  Likewise
        asin(u) and acos(u) at u = +-1, acosh(u) at u = 1: (F with the function replaced by its value
        there, 1 -+ u or u - 1)."""
        if getattr(self, "_domain_edge_systems", None) is None:
            g, f = self._graph, self._f
            plan = g.plan([f])
            rfun_roots = {g.args[n][2] for n in plan if g.ops[n] == "rfun"}
            out = []
            for n in plan:
                op, p = g.ops[n], g.params[n]
                if op in _FINITE_ENDS:
                    # asin, acos, acosh end with a square-root behaviour and
                    # a finite value at the ends of their domain, as sqrt.
                    a = g.args[n][0]
                    for end, value, side in _FINITE_ENDS[op]:
                        lo, hi = np.nextafter(value, -np.inf), np.nextafter(value, np.inf)
                        c = g.const(value, lo if value else value, hi if value else value)
                        # G2 = 1 - a, 1 + a or a - 1: zero at the end, >= 0 inside
                        g2 = g.sub(g.const(float(end)), a) if side > 0 else g.sub(a, g.const(float(end)))
                        out.append(_Kink(self, "domain edge", g.substitute(f, n, c), g2, None, (), "pole"))
                    continue
                if n in rfun_roots or not (op == "sqrt" or (op == "powr" and 0.0 < float(p) < 1.0)):
                    continue
                a = g.args[n][0]
                if g._squares(a) or g.ops[a] == "abs" or (g.ops[a] == "powi" and g.params[a] == 2):
                    continue
                out.append(_Kink(self, "domain edge", g.substitute(f, n, g.zero), a, None, (), "pole"))
            self._domain_edge_systems = out
        return self._domain_edge_systems

    def _pole_line(self):
        """The curve where the surface runs into a pole of F = N / D, as a crease system (N, D), or None.

        The surface N = 0 meets the pole D = 0 along N = D = 0, where F is
        0 / 0: meshed as a crease there (the half-sheets on the two sides
        of the pole zipped to it), the mesh ends on the pole line instead of
        a few fine cells short of it.
        """
        if not self._poles:
            return None
        # Rational F only: sympy's cancel of a sum of sigmoids 1/(1 + exp(...))
        # with float coefficients runs for many minutes (heuristic gcds of
        # huge expressions), and their denominators have no zeros anyway.
        # Other poles (tan, 1/sin) keep the documented gap of a cell.
        # N, D coprime (sympy's cancel): a common factor (x^2 - y^2 over
        # x - y) would make N = D = 0 a surface, not a line.
        fraction = polynomial_fraction(self.expr)
        if fraction is None or not fraction[0].free_symbols:
            return None
        num, den = fraction
        g = self._graph
        try:
            n, d = g.from_sympy(num), g.from_sympy(den)
        except SurfaceError:
            return None
        return _Kink(self, "pole line", n, d, None, (), "pole")

    def removable_singularity(self, box):
        """Where F is 0 / 0 along the zeros of a denominator in ``box`` with a finite limit: (divisor, point) or None.

        sin(x) / x at x = 0: F has a limit there (1), but its interval
        bounds on every box meeting x = 0 are infinite, so such boxes are
        never simple, the whole of x = 0 in the box goes to the fine
        level, and the lattice values there are NaN.  A divisor ``d`` (the
        base of a negative power) counts when, at every point of d = 0
        found by Newton from a 5^3 grid of the box, F a step
        ``REMOVABLE_STEP`` of the box to either side is finite, the two
        values agree to ``REMOVABLE_JUMP`` of F's scale (a pole, 1 / x,
        has them of opposite signs and huge), and F's bounds on the box
        of that step round it are unbounded (a limit the bounds see,
        exp(-1 / x^2), is no trouble).  Rational F are meshed as N = 0,
        their closure: None.
        """
        if polynomial_fraction(self.expr) is not None:
            return None
        box = np.asarray(box, float)
        size = float(np.max(box[:, 1] - box[:, 0]))
        s = np.linspace(0.0, 1.0, 5)
        grid = box[:, 0] + np.stack(np.meshgrid(s, s, s, indexing="ij"), -1).reshape(-1, 3) * (box[:, 1] - box[:, 0])
        seen = set()
        for node in sympy.preorder_traversal(self.expr):
            if not (isinstance(node, sympy.Pow) and node.base.free_symbols and node.exp.is_negative):
                continue
            if node.base in seen:
                continue
            seen.add(node.base)
            g = Graph()
            d = g.from_sympy(node.base)
            grad = [g.diff(d, a) for a in range(3)]
            p = grid.copy()
            for _ in range(tol.REMOVABLE_NEWTON_STEPS):
                v, *dv = point_eval(g, [d] + grad, p)
                dv = np.stack(dv, 1)
                with np.errstate(all="ignore"):
                    p = p - (v / np.einsum("ij,ij->i", dv, dv))[:, None] * dv
            v, *dv = point_eval(g, [d] + grad, p)
            dv = np.stack(dv, 1)
            n = np.linalg.norm(dv, axis=1)
            ok = (np.isfinite(p).all(axis=1) & np.all((p >= box[:, 0]) & (p <= box[:, 1]), axis=1)
                  & (np.abs(v) <= 1e-12 * np.maximum(n, 1e-300) * size) & (n > 0))
            if ok.sum() < 3:
                continue
            p, normal = p[ok], dv[ok] / n[ok, None]
            step = tol.REMOVABLE_STEP * size
            fp, fm = self(p + step * normal), self(p - step * normal)
            r = interval_eval(self._graph, [self._f], p - step, p + step)
            with np.errstate(invalid="ignore"):
                removable = (np.isfinite(fp) & np.isfinite(fm)
                             & (np.abs(fp - fm) <= tol.REMOVABLE_JUMP * self.scale)
                             & ~(np.isfinite(r.lo[0]) & np.isfinite(r.hi[0])))
            if removable.all():
                return str(node.base), p[0]
        return None

    def ends_near(self, points, radius: float) -> np.ndarray:
        """(k,) bool: F is undefined or unbounded somewhere within ``radius`` (max norm) of each point.

        Interval bounds of F on the cube round each point: some argument
        left its function's domain there (sqrt of a negative number), or a
        bound is infinite (a pole).  Where the surface runs into such
        places the mesh ends up to a cell short of them.
        """
        p = np.asarray(points, float).reshape(-1, 3)
        r = interval_eval(self._graph, [self._f], p - radius, p + radius)
        return r.clipped | ~(np.isfinite(r.lo[0]) & np.isfinite(r.hi[0]))

    def continuous_on(self, lo, hi) -> np.ndarray:
        """(k,) bool: F is certainly defined and bounded on each closed box [lo, hi] (k, 3).

        Interval bounds of F: finite, and no argument leaves its function's
        domain.  Where False the box may hold a pole (tan at pi / 2, where
        F jumps from +inf to -inf without a zero) or an end of F's domain.
        """
        lo = np.asarray(lo, float).reshape(-1, 3)
        if getattr(self, "_limited", None) is None:
            # (F without poles and defined everywhere, the gyroid: no bounds to read)
            self._limited = self._poles or any(True for _ in _domain_conditions(self.expr))
        if not self._limited or not len(lo):
            return np.ones(len(lo), bool)
        r = interval_eval(self._graph, [self._f], lo, np.asarray(hi, float).reshape(-1, 3))
        return ~r.clipped & np.isfinite(r.lo[0]) & np.isfinite(r.hi[0])

    def undefined_everywhere(self, box) -> bool:
        """Whether F is certainly undefined on the whole of ``box`` (3, 2).

        True only where interval arithmetic proves it (the argument of a
        sqrt, log, ... is out of its domain on the whole box, as
        ``sqrt(-1 - x^2)``); a box only partly outside the domain, or one
        the bounds cannot decide, is False.
        """
        lo, hi = self.corners(self.enclose(box))
        flo, fhi = self._value_bounds(lo, hi, centre=False)
        return bool(np.isnan(flo[0]) or np.isnan(fhi[0]))

    def undefined_on(self, data: np.ndarray):
        """A subexpression of F undefined somewhere on one of the boxes, or None.

        Returns ``(text, point)``: the subexpression (sqrt, log or power of
        a possibly negative argument, division by a possibly zero one) and
        a point of the box where it is undefined or infinite (its centre if
        no sample shows it), for a caller that refuses such input with a
        SurfaceError.
        """
        lo, hi = self.corners(data)
        for node, arg, strict in _domain_conditions(self.expr):
            g = Graph()
            n = g.from_sympy(arg)
            r = interval_eval(g, [n], lo, hi)
            # (-1e-300: the outward rounding of an exact 0, as 1 - y at y = 1)
            bad = (r.lo[0] < -1e-300) if strict is False else (r.lo[0] <= 0) if strict else ((r.lo[0] <= 0) & (r.hi[0] >= 0))
            if bad.any():
                i = int(np.nonzero(bad)[0][0])
                t = np.linspace(0, 1, 9)
                pts = lo[i] + (hi[i] - lo[i]) * np.stack(np.meshgrid(t, t, t, indexing="ij"), -1).reshape(-1, 3)
                val = point_eval(g, [n], pts)[0]
                j = int(np.argmin(val if strict is not None else np.abs(val)))
                return str(node), pts[j]
        return None

    # ------------------------------------------------------------ lattice lines
    def line_roots(self, axis: int, fixed, s0, s1) -> tuple[np.ndarray, np.ndarray]:
        """Zeros of F on the segments {coordinate ``axis`` = s in [s0, s1], the
        others (cyclic order) = ``fixed``}: every sign change at least once,
        double roots to rounding, polished to full precision.

        Returns
        -------
        row : (R,) int64, s : (R,) float64
        """
        fixed = np.asarray(fixed, float).reshape(-1, 2)
        s0 = np.asarray(s0, float).reshape(-1)
        s1 = np.asarray(s1, float).reshape(-1)
        u, v = (axis + 1) % 3, (axis + 2) % 3
        g, f, d = self._graph, self._f, self._grad[axis]
        # (never below a few ulps: a piece must still halve)
        min_width = np.maximum(tol.ELEMENTARY_ROOT_PIECE * np.abs(s1 - s0),
                               8 * np.spacing(np.maximum(np.abs(s0), np.abs(s1))))

        def boxes(row, a, b):
            lo = np.empty((len(row), 3))
            lo[:, axis] = a
            lo[:, u] = fixed[row, 0]
            lo[:, v] = fixed[row, 1]
            hi = lo.copy()
            hi[:, axis] = b
            return lo, hi

        def values(row, s):
            lo, _ = boxes(row, s, s)
            return point_eval(g, [f], lo, magnitude=True)

        row = np.arange(len(s0))
        a, b = s0.copy(), s1.copy()
        br_row, br_a, br_b = [], [], []
        out_row, out_s = [], []
        for _ in range(200):
            if len(row) == 0:
                break
            lo, hi = boxes(row, a, b)
            r = self._gradient_bounds(lo, hi, (axis,))
            dl, dh = r.lo[0], r.hi[0]
            clipped = r.clipped
            grad = [(np.zeros(len(row)), np.zeros(len(row))) for _ in range(3)]
            grad[axis] = (dl, dh)
            flo, fhi = self._value_bounds(lo, hi, grad=grad)
            slack = self._slack(flo, fhi, lo, hi)
            maybe = (flo <= slack) & (fhi >= -slack)
            # A piece across a pole: no zero where N of F = N / D has one
            # sign (the sign change of F there is the pole's), not halved
            # down to the smallest width on every line crossing a pole.
            pole = np.nonzero(maybe & (np.isinf(flo) | np.isinf(fhi)))[0]
            if len(pole) and self._fraction is not None:
                maybe[pole] = ~self._fraction_excludes(lo[pole], hi[pole])
            row, a, b, dl, dh, clipped = row[maybe], a[maybe], b[maybe], dl[maybe], dh[maybe], clipped[maybe]
            flo, fhi = flo[maybe], fhi[maybe]
            if len(row) == 0:
                break
            # Monotone: F' of one sign and F bounded (no pole between) and
            # defined on the whole piece (its end values are then read).
            mono = _one_sign(dl, dh) & np.isfinite(flo) & np.isfinite(fhi) & ~clipped
            small = ~mono & ((b - a) <= min_width[row])
            ends = np.nonzero(mono | small)[0]
            if len(ends):
                er, ea, eb = row[ends], a[ends], b[ends]
                mid = 0.5 * (ea + eb)
                (fv,), (fm,) = values(np.concatenate([er, er, er]), np.concatenate([ea, eb, mid]))
                k = len(ends)
                fa, fb, fmid = fv[:k], fv[k:2 * k], fv[2 * k:]
                zero = np.isfinite(fv) & (np.abs(fv) <= tol.ZERO_ULPS * _EPS * fm)
                change = (fa < 0) != (fb < 0)
                change &= ~np.isnan(fa) & ~np.isnan(fb)
                br_row.append(er[change])
                br_a.append(ea[change])
                br_b.append(eb[change])
                # No sign change: a root only where |F| is at rounding level
                # (an end point, or a double root in a smallest piece).
                rest = ~change
                sm = small[ends]
                cand = np.stack([ea, eb, mid])
                zz = zero.reshape(3, k)
                absv = np.abs(fv).reshape(3, k)
                absv = np.where(zz, absv, np.inf)
                if not sm.all():
                    absv[2, ~sm] = np.inf  # monotone pieces: only their ends
                best = np.argmin(absv, axis=0)
                hit = rest & np.isfinite(absv[best, np.arange(k)])
                out_row.append(er[hit])
                out_s.append(cand[best[hit], np.nonzero(hit)[0]])
            # Pieces on which F is zero to rounding throughout: one root at
            # the middle, not split further (near a double root, F is below
            # rounding on a piece of width ~ sqrt(eps); a line lying in the
            # surface gets a root per such piece, which costs nothing).
            split = np.nonzero(~mono & ~small)[0]
            if len(split) == 0:
                row = row[:0]
                break
            row, a, b = row[split], a[split], b[split]
            c = (a + b) * 0.5
            k = len(row)
            (fv,), (fm,) = values(np.concatenate([row, row, row]), np.concatenate([a, b, c]))
            cm = fm[2 * k:]
            # A piece on which F is infinite or undefined at both ends and in
            # the middle lies in a pole or outside the domain (x / y on the
            # line y = 0): halving it would go on to the smallest width,
            # doubling the pieces at every step.  It holds no root we could
            # place.
            hopeless = ~np.isfinite(fv).reshape(3, k).any(axis=0)
            # So is, once narrower than ELEMENTARY_UNDEFINED_PIECE of the
            # segment, a piece with F undefined at an end (0 / 0: sin(x) / x
            # at x = 0) and unbounded both ways on it: its half next to that
            # end is unbounded too, down to the smallest width, on every
            # lattice line crossing x = 0.  (Beside a pole, 1 / x + 3, one
            # bound is finite once the piece is one-sided, and decides.)
            hopeless |= ((np.isnan(fv[:k]) | np.isnan(fv[k:2 * k])) & ~np.isfinite(flo[split])
                         & ~np.isfinite(fhi[split])
                         & (b - a <= tol.ELEMENTARY_UNDEFINED_PIECE * np.abs(s1 - s0)[row]))
            # (The absolute floor: where F's terms are all zero, as on a line
            # lying in x / y = 0, its bounds are the outward rounding alone,
            # a few 1e-300, and the piece would be halved to the end.)
            flat = np.maximum(np.abs(flo[split]), np.abs(fhi[split])) <= tol.ZERO_ULPS * _EPS * cm + _FLAT_FLOOR
            flat &= ~hopeless & np.isfinite(cm)   # (not at a pole: F is infinite there)
            row, a, b, c, flat = (row[~hopeless], a[~hopeless], b[~hopeless], c[~hopeless],
                                  flat[~hopeless])
            out_row.append(row[flat])
            out_s.append(c[flat])
            row, a, b, c = row[~flat], a[~flat], b[~flat], c[~flat]
            row = np.concatenate([row, row])
            a, b = np.concatenate([a, c]), np.concatenate([c, b])
        brow = np.concatenate(br_row) if br_row else np.zeros(0, np.int64)
        if len(brow):
            ba, bb = np.concatenate(br_a), np.concatenate(br_b)
            s, good = self._polish(axis, fixed, brow, ba, bb)
            out_row.append(brow[good])
            out_s.append(s[good])
        if not out_row:
            return np.zeros(0, np.int64), np.zeros(0)
        rows = np.concatenate(out_row).astype(np.int64)
        s = np.concatenate(out_s)
        order = np.lexsort((s, rows))
        return rows[order], s[order]

    def _polish(self, axis, fixed, row, a, b):
        """Roots in sign-change brackets [a, b]: Newton kept inside the bracket
        (bisection where it leaves it), to full precision; kept where |F| is
        at rounding level (a sign change across a pole is no root)."""
        u, v = (axis + 1) % 3, (axis + 2) % 3
        g, f, d = self._graph, self._f, self._grad[axis]

        def pts(r, s):
            p = np.empty((len(r), 3))
            p[:, axis] = s
            p[:, u] = fixed[r, 0]
            p[:, v] = fixed[r, 1]
            return p

        width = b - a
        a, b = a.copy(), b.copy()
        fa_neg = point_eval(g, [f], pts(row, a))[0] < 0
        x = 0.5 * (a + b)
        active = np.arange(len(row))
        for _ in range(tol.ELEMENTARY_ROOT_STEPS):
            if len(active) == 0:
                break
            xa = x[active]
            fx, dx = point_eval(g, [f, d], pts(row[active], xa))
            left = (fx < 0) == fa_neg[active]  # the root is right of x
            aa = np.where(left, xa, a[active])
            bb = np.where(left, b[active], xa)
            a[active], b[active] = aa, bb
            with np.errstate(all="ignore"):
                xn = xa - fx / dx
            inside = np.isfinite(xn) & (xn > aa) & (xn < bb)
            xn = np.where(inside, xn, 0.5 * (aa + bb))
            step = np.abs(xn - xa)
            tiny = 2 * np.spacing(np.maximum(np.abs(aa), np.abs(bb)))
            done = (fx == 0) | (step <= tiny) | ((bb - aa) <= tiny)
            x[active] = np.where(fx == 0, xa, xn)
            active = active[~done]
        (fv,), (fm,) = point_eval(g, [f], pts(row, x), magnitude=True)
        good = np.isfinite(fv) & (np.abs(fv) <= tol.ELEMENTARY_ROOT_RESIDUAL * fm)
        if self._poles:
            # A sign change across a pole: F is unbounded next to x.
            delta = 4 * np.spacing(np.maximum(np.abs(a), np.abs(b))) + 1e-300
            lo, hi = pts(row, x - delta), pts(row, x + delta)
            r = interval_eval(g, [f], lo, hi)
            good &= np.isfinite(r.lo[0]) & np.isfinite(r.hi[0])
            # Bisection also closes in on a pole, to a point where F is
            # finite but huge (-0.5 / 1e-300), and relative to its own
            # magnitude that is a zero.  Next to a root |F| grows, next to
            # a pole it falls.
            h = np.maximum(1e-6 * width, 4 * np.spacing(np.abs(x)))
            (fl, fr) = (point_eval(g, [f], pts(row, x - h))[0], point_eval(g, [f], pts(row, x + h))[0])
            with np.errstate(invalid="ignore"):
                good &= np.abs(fv) <= np.fmax(np.abs(fl), np.abs(fr))
        return x, good


#: Functions with a finite value at an end of their domain, approached as a
#: square root: op -> (end, value there, +1 if the domain is below the end).
_FINITE_ENDS = {"asin": ((1.0, np.pi / 2, 1), (-1.0, -np.pi / 2, -1)),
                "acos": ((1.0, 0.0, 1), (-1.0, np.pi, -1)),
                "acosh": ((1.0, 0.0, -1),)}


def _domain_conditions(expr: sympy.Expr):
    """(subexpression, argument, strict) for each function of ``expr`` with a domain:
    it is defined where the argument is >= 0 (strict False), > 0 (True), != 0 (None)."""
    for node in sympy.preorder_traversal(expr):
        if not node.free_symbols:
            continue
        if isinstance(node, sympy.log):
            yield node, node.args[0], True
        elif isinstance(node, sympy.Pow) and not node.exp.free_symbols:
            e = node.exp
            if not e.is_Integer:
                yield node, node.base, bool(e.is_negative)
            elif e.is_negative:
                yield node, node.base, None
        elif isinstance(node, (sympy.asin, sympy.acos)):
            yield node, 1 - node.args[0], False
            yield node, 1 + node.args[0], False
        elif isinstance(node, sympy.acosh):
            yield node, node.args[0] - 1, False
        elif isinstance(node, sympy.atanh):
            yield node, 1 - node.args[0], True
            yield node, 1 + node.args[0], True


class _Kink(CreaseSystem):
    """A kink of an :class:`ElementarySurface`: G1, G2 as nodes of its graph.

    ``other`` is the node of F with the kink's other piece (None for an
    R-function); ``tie`` the tied argument then the others of a Max/Min.
    """

    def __init__(self, surface: ElementarySurface, name: str, g1: int, g2: int, other, tie: tuple, op: str):
        self.name = name
        self._s = surface
        g = surface._graph
        self._nodes = [g1, g2] + [g.diff(n, a) for n in (g1, g2) for a in range(3)]
        self._other = None if other is None else [g.diff(g1, a) for a in range(3)] + [g.diff(other, a)
                                                                                    for a in range(3)]
        self._tie = tie
        self._op = op
        self._g1, self._g2 = g1, g2

    def values(self, points):
        p = np.asarray(points, float).reshape(-1, 3)
        v = point_eval(self._s._graph, self._nodes, p)
        return np.stack(v[:2], 1), np.stack([np.stack(v[2:5], 1), np.stack(v[5:8], 1)], 1)

    def active(self, points):
        p = np.asarray(points, float).reshape(-1, 3)
        g = self._s._graph
        if self._op == "pole":
            # N = D = 0 (Newton put the point there) on a curve (grad N and
            # grad D apart): the surface meets the pole there.
            v, d = self.values(p)
            cross = np.linalg.norm(np.cross(d[:, 0], d[:, 1]), axis=1)
            size = np.linalg.norm(d[:, 0], axis=1) * np.linalg.norm(d[:, 1], axis=1)
            return np.isfinite(v).all(axis=1) & (cross > tol.CREASE_JUMP * size)
        (fv, *grad), (fm, *_) = point_eval(g, [self._s._f] + self._s._grad, p, magnitude=True)
        # On the crease F = G1 (the tie): F at rounding level of its terms,
        # or of its gradient times the point's scale (as Newton's test):
        # on z - y |x|'s crease x = z = 0 every term of F vanishes, and a
        # point 1e-17 off it has F = 3e-18 with terms of the same size.
        size = np.linalg.norm(np.stack(grad, 1), axis=1) * np.maximum(np.abs(p).max(axis=1), 1.0)
        ok = np.abs(fv) <= tol.CREASE_RESIDUAL * np.maximum(np.fmax(fm, size), 1e-300)
        if self._tie:
            vals = point_eval(g, list(self._tie), p, magnitude=True)
            a, ma = vals[0][0], vals[1][0]
            for b, mb in zip(vals[0][1:], vals[1][1:]):
                slack = tol.CREASE_TIE * (ma + mb)
                ok &= (a >= b - slack) if self._op == "max" else (a <= b + slack)
        if self._other is not None:
            d = np.stack(point_eval(g, self._other, p), 1)
            gi, gj = d[:, :3], d[:, 3:]
            jump = np.linalg.norm(gi - gj, axis=1)
            size = np.linalg.norm(gi, axis=1) + np.linalg.norm(gj, axis=1)
            differ = jump > tol.CREASE_JUMP * size
            if self._tie:
                # A Max/Min inside an enclosing Min tied to rounding along
                # a whole face (coplanar faces of two boxes joined by Min,
                # float-rotated): there the enclosing Min picks the other
                # box for both pieces at random, and the jump of F's pieces
                # comes and goes along the edge.  The tied arguments' own
                # gradients (grad G2) differ there; whether F's does is
                # asked a step to either side below.
                _, dv = self.values(p)
                differ |= np.linalg.norm(dv[:, 1], axis=1) > tol.CREASE_JUMP * size
            ok &= differ
            # ... and F's own gradient a step to either side of the tie
            # does too: where an enclosing Min or Max is tied to rounding
            # with an argument of the same gradient (coplanar faces of two
            # boxes joined by Min), which piece is picked at the point is
            # rounding, and the jump there is none.
            # Where that step says no jump, the circle round the crease
            # is asked (:meth:`_around_differ`): only there, as it costs
            # a dozen values of F per point.
            side = self._sides_differ(p)
            redo = np.nonzero(ok & ~side)[0]
            if len(redo):
                side[redo] = self._around_differ(p[redo])
            ok &= side
        return ok & np.isfinite(fv)

    def _around_differ(self, p: np.ndarray) -> np.ndarray:
        """(n,) bool: F = 0 crosses a small circle round the crease at p where F's gradients differ.

        ``CREASE_AROUND`` points on a circle of radius ``CREASE_SIDE_STEP``
        (relative to the point's scale) in the plane across the crease
        (tangent grad G1 x grad G2): F changes sign between neighbours where
        the surface crosses it, and the kink is there when the gradients
        of F at the two crossings differ (a flat face through p crosses it
        twice with one gradient).  Only F's values tell where the crossings
        are: where three faces meet along one line (the rim of a box
        standing on a larger one, joined by Min), the kink's own pieces and
        a step along grad G2 land on ties of the enclosing Min whose piece
        is rounding, and the kink came and went along the rim.  False where
        the plane is not defined (grad G1 along grad G2), or F does not
        cross the circle twice.
        """
        g = self._s._graph
        _, d = self.values(p)
        t = np.cross(d[:, 0], d[:, 1])
        tn = np.linalg.norm(t, axis=1)
        plane = tn > tol.CREASE_JUMP * np.linalg.norm(d[:, 0], axis=1) * np.linalg.norm(d[:, 1], axis=1)
        t = t / np.maximum(tn, 1e-300)[:, None]
        # An orthonormal pair across t.
        a = np.where((np.abs(t[:, :1]) < 0.9), np.array([[1.0, 0, 0]]), np.array([[0, 1.0, 0]]))
        e1 = np.cross(t, a)
        e1 /= np.maximum(np.linalg.norm(e1, axis=1, keepdims=True), 1e-300)
        e2 = np.cross(t, e1)
        k = tol.CREASE_AROUND
        ang = 2 * np.pi * (np.arange(k) + 0.5) / k
        r = tol.CREASE_SIDE_STEP * np.maximum(np.abs(p).max(axis=1), 1.0)
        circle = np.cos(ang)[None, :, None] * e1[:, None] + np.sin(ang)[None, :, None] * e2[:, None]
        ring = p[:, None] + r[:, None, None] * circle
        (f,) = point_eval(g, [self._s._f], ring.reshape(-1, 3))
        f = f.reshape(len(p), k)
        pos = f >= 0
        change = pos != np.roll(pos, -1, axis=1)  # between sample i and i + 1
        two = (change.sum(axis=1) == 2) & np.isfinite(f).all(axis=1) & plane
        out = np.zeros(len(p), bool)
        rows = np.nonzero(two)[0]
        if len(rows):
            i = np.argsort(~change[rows], axis=1, kind="stable")[:, :2]  # the two crossings
            j = (i + 1) % k
            fi = np.take_along_axis(f[rows], i, 1)
            fj = np.take_along_axis(f[rows], j, 1)
            w = fi / (fi - fj)
            ri = np.take_along_axis(ring[rows], i[..., None], 1)
            rj = np.take_along_axis(ring[rows], j[..., None], 1)
            x = ri + w[..., None] * (rj - ri)
            grad = np.stack(point_eval(g, self._s._grad, x.reshape(-1, 3)), 1).reshape(len(rows), 2, 3)
            size = np.linalg.norm(grad, axis=2).sum(axis=1)
            out[rows] = np.linalg.norm(grad[:, 0] - grad[:, 1], axis=1) > tol.CREASE_JUMP * size
        return out

    def _sides_differ(self, p: np.ndarray) -> np.ndarray:
        """(n,) bool: grad F differs a step ``CREASE_SIDE_STEP`` to either side of the tie G2 = 0 at p."""
        g = self._s._graph
        _, d = self.values(p)
        m = d[:, 1] / np.maximum(np.linalg.norm(d[:, 1], axis=1, keepdims=True), 1e-300)
        step = tol.CREASE_SIDE_STEP * np.maximum(np.abs(p).max(axis=1), 1.0)[:, None]
        q = np.concatenate([p + step * m, p - step * m])
        grad = np.stack(point_eval(g, self._s._grad, q), 1)
        a, b = grad[:len(p)], grad[len(p):]
        size = np.linalg.norm(a, axis=1) + np.linalg.norm(b, axis=1)
        return np.linalg.norm(a - b, axis=1) > tol.CREASE_JUMP * size

    def may_vanish(self, data):
        lo, hi = self._s.corners(data)
        r = interval_eval(self._s._graph, [self._g1, self._g2], lo, hi)
        keep = np.ones(len(lo), bool)
        for gl, gh in zip(r.lo, r.hi):
            s = tol.CANDIDATE_SLACK * np.maximum(_finite_abs(gl), _finite_abs(gh))
            keep &= ~((gl > s) | (gh < -s))  # NaN (outside the domain): kept
        return keep


def kink_values(systems: list, points) -> tuple[np.ndarray, np.ndarray] | None:
    """G1, G2 and their gradients of several kinks at the points, in one pass over F's graph.

    Returns (n, k, 2) and (n, k, 2, 3) for the k kinks of ``systems``, or
    None where they are not all kinks of one :class:`ElementarySurface`
    (then each is asked on its own).  One pass costs about what one
    kink's values cost: the kinks share F's graph.
    """
    if not systems or not all(isinstance(s, _Kink) and s._s is systems[0]._s for s in systems):
        return None
    p = np.asarray(points, float).reshape(-1, 3)
    v = point_eval(systems[0]._s._graph, [n for s in systems for n in s._nodes], p)
    v = np.stack(v, 1).reshape(len(p), len(systems), 8)
    return v[:, :, :2], v[:, :, 2:].reshape(len(p), len(systems), 2, 3)


class _Tip(TipSystem):
    """A root of a sum of squares in an :class:`ElementarySurface`: its equations as nodes of the graph."""

    def __init__(self, surface: ElementarySurface, name: str, equations: list):
        self.name = name
        self._s = surface
        g = surface._graph
        self._eq = list(equations)
        self._nodes = self._eq + [g.diff(e, a) for e in self._eq for a in range(3)]

    def values(self, points):
        p = np.asarray(points, float).reshape(-1, 3)
        v = point_eval(self._s._graph, self._nodes, p)
        m = len(self._eq)
        return np.stack(v[:m], 1), np.stack(v[m:], 1).reshape(len(p), m, 3)

    def may_vanish(self, data):
        lo, hi = self._s.corners(data)
        r = interval_eval(self._s._graph, self._eq, lo, hi)
        keep = np.ones(len(lo), bool)
        for gl, gh in zip(r.lo, r.hi):
            s = tol.CANDIDATE_SLACK * np.maximum(np.abs(gl), np.abs(gh))
            keep &= ~((gl > s) | (gh < -s))
        return keep
