"""A surface equation F(x, y, z) = 0: the interface the stages use, and the polynomial.

The text is read by :mod:`singmesh.syntax` (SingSurf's equation language,
which also takes sympy's syntax): ``^`` for powers, implicit
multiplication (``2 x y``, ``x(y+1)``), ``lhs = rhs`` for ``lhs - rhs``,
statements over several lines with ``//`` comments, and later
``NAME = EXPR;`` statements defining names in terms of x, y, z, parameters
and each other.  Parameters may also come as keyword arguments.  Constant
subexpressions such as ``sqrt(5)``, ``pi`` or ``cos(2 pi/5)`` are numbers.

:class:`Surface` is what every stage knows of F (issue #10): values and
Taylor jets at points, bounds on stacked boxes (an opaque ``data`` array
per stack, first axis the box) and roots on lattice segments.
:class:`PolynomialSurface` implements it for a polynomial: the exact sympy
polynomial, the dense tensor of its monomial coefficients ``C[i, j, k]``
(of ``x**i y**j z**k``) for values at points, Bernstein tensors on boxes
(:mod:`singmesh.boxes.polynomial_bounds`) and companion matrices on lines
(:mod:`singmesh.boxes.polynomial_lines`).
"""

from __future__ import annotations

import abc
import itertools
import math
from dataclasses import dataclass, field, replace
from functools import lru_cache
from typing import Mapping

import numpy as np
import sympy

from singmesh.boxes import polynomial_bounds, polynomial_lines
from singmesh.boxes.bernstein import bernstein_on_box
from singmesh.boxes.bernstein import split as bernstein_split
from singmesh.skeleton.splitting import compose, translate_many

from .errors import SurfaceError
from .monomials import _MANY, differentiate, evaluate_tensor, evaluate_tensors, evaluate_tensors_many, powers
from .syntax import VARIABLES, X, Y, Z, read_equation, unused_message  # noqa: F401  (X, Y, Z re-exported)
from . import tolerances as tol
from .tolerances import CANDIDATE_DUST, DISPLAY_DIGITS, MAX_DEGREE, MAX_POWER, PROJECT_HALVINGS, ZERO_ULPS

#: ``offsets[c]``: the corner offset (in halves) of child c of a split box.
CHILD_OFFSETS = np.array(np.meshgrid([0, 1], [0, 1], [0, 1], indexing="ij")).reshape(3, -1).T


class CreaseSystem(abc.ABC):
    """One kind of kink of F: where two smooth functions G1, G2 both vanish.

    A crease of the surface is a curve where F = 0 has a kink (the
    intersection of the two pieces of a Max or Min, the zero of an Abs's
    argument, the crease f = g = 0 of an R-function): the common zeros of
    G1 and G2 hold it, and :meth:`active` says where on them F really has
    a kink on its zero set.  Smooth near the crease, so Newton on (G1, G2)
    converges quadratically onto it.

    Attributes
    ----------
    name : str
        What the kink is, for messages (e.g. ``"Max(z, x**2 ...): 0 = 1"``).
    """

    name: str = ""

    @abc.abstractmethod
    def values(self, points) -> tuple[np.ndarray, np.ndarray]:
        """G1, G2 and their gradients at ``points`` (n, 3): (n, 2) and (n, 2, 3)."""

    @abc.abstractmethod
    def active(self, points) -> np.ndarray:
        """(n,) bool: at these points (on the common zeros of G1, G2), F = 0 has a kink."""

    def newton(self, x: np.ndarray, reach, extra=None) -> tuple[np.ndarray, np.ndarray]:
        """Minimum-norm Newton from points x (k, 3) onto G1 = G2 = 0 (and ``extra``).

        Shared by the stages that put points on such a curve (the creases
        of the skeleton stage, the domain's edges of the facets stage).

        ``extra``: optional (k, 4) rows (normal n, offset c) of a third
        equation n . x = c (a face of the box).  ``reach``: a point that moves
        further is refused.  Returns (points, ok).
        """
        x0 = np.array(x, float).reshape(-1, 3)
        x = x0.copy()
        with np.errstate(all="ignore"):
            for _ in range(tol.CREASE_NEWTON):
                v, g = self.values(x)
                if extra is not None:
                    v = np.concatenate([v, (np.einsum("ki,ki->k", extra[:, :3], x) - extra[:, 3])[:, None]], 1)
                    g = np.concatenate([g, extra[:, None, :3]], 1)
                # A point outside a piece's domain (|x|^2.5 with x < 0 once the
                # Abs is replaced by x) stays where it is, and is refused below.
                bad = ~(np.isfinite(v).all(axis=1) & np.isfinite(g).all(axis=(1, 2)))
                if bad.any():
                    v, g = np.where(bad[:, None], 0.0, v), np.where(bad[:, None, None], 0.0, g)
                step = np.einsum("kij,kj->ki", np.linalg.pinv(g, rcond=1e-13), v)
                step = np.where(np.isfinite(step), step, 0.0)
                x_new = x - step
                # Converged everywhere: steps at rounding level of the points.
                small = np.all(np.abs(step) <= 4 * np.finfo(float).eps * np.maximum(np.abs(x), 1.0))
                x = x_new
                if small:
                    break
            v, g = self.values(x)
            size = np.linalg.norm(g, axis=2) * np.maximum(np.abs(x).max(axis=1), 1.0)[:, None]
            ok = np.all(np.abs(v) <= tol.CREASE_RESIDUAL * np.maximum(size, 1e-300), axis=1)
            if extra is not None:
                ok &= np.abs(np.einsum("ki,ki->k", extra[:, :3], x) - extra[:, 3]) <= 1e-12 * np.abs(x).max(axis=1).clip(1)
            ok &= np.isfinite(x).all(axis=1) & (np.linalg.norm(x - x0, axis=1) <= reach)
        return x, ok

    @abc.abstractmethod
    def may_vanish(self, data: np.ndarray) -> np.ndarray:
        """(N,) bool on a stack of boxes (the surface's ``data``): G1 and G2 may both vanish there."""


def boxes_where(surface: "Surface", box: np.ndarray, level: int, keep) -> tuple[np.ndarray, np.ndarray]:
    """The boxes at ``level`` of ``box`` kept at every level by ``keep(data) -> (N,) bool``.

    Returns
    -------
    data : the surface's data on the boxes kept
    corner : (K, 3) int64   their lower corners in units of the level's box
    """
    data = surface.enclose(box)
    corner = np.zeros((1, 3), np.int64)
    for _ in range(level):
        children = surface.split(data)
        data = children.reshape((-1,) + children.shape[2:])
        corner = (2 * corner[:, None, :] + CHILD_OFFSETS[None]).reshape(-1, 3)
        k = keep(data)
        data, corner = data[k], corner[k]
        if len(corner) == 0:
            break
    return data, corner


class TipSystem(abc.ABC):
    """Where F is continuous but not differentiable at isolated points of its zero set.

    A root of a sum of squares, sqrt(f1^2 + f2^2) or (f1^2 + f2^2)^(1/3)
    in F, has infinite derivatives where f1 = f2 = 0 (a line, or a point
    with three squares); where that set meets F = 0, the surface has a
    point that is not smooth (the apex of the cone sqrt(x^2 + y^2) = |z|,
    the cusped tip of r^(2/3) + z^2 = 1/2) and grad F = 0 does not say
    so.  The equations E = (F0, f1, ..., fk), F0 being F with the root
    replaced by 0 (F's value where the root vanishes), are smooth there
    and hold such points as common zeros.

    Attributes
    ----------
    name : str
        The root, for messages.
    """

    name: str = ""

    @abc.abstractmethod
    def values(self, points) -> tuple[np.ndarray, np.ndarray]:
        """E and its Jacobian at ``points`` (n, 3): (n, m) and (n, m, 3)."""

    @abc.abstractmethod
    def may_vanish(self, data: np.ndarray) -> np.ndarray:
        """(N,) bool on a stack of boxes (the surface's ``data``): all of E may vanish there."""


class Surface(abc.ABC):
    """What the stages know of a surface F(x, y, z) = 0 (issue #10's contract).

    Build one with :meth:`Surface.parse`.

    Attributes
    ----------
    text : str
        The input as given (or the sympy expression printed).
    expr : sympy.Expr
        F, exact where the input was exact.
    params : dict
        The parameter values that were substituted.
    rounding : float
        Relative precision of the input's numbers: half a unit in the last
        digit of its longest rounded decimal (a 15-digit coefficient:
        5e-15), and never below double precision.  A point where F and
        grad F vanish to this precision is singular.
    is_polynomial : bool
    degree : int
        Total degree of a polynomial; otherwise the order of the Taylor
        jets used to classify.  Tolerances scale with it.
    scale : float
        The typical size of F's terms: the denominator of relative
        tolerances (a polynomial's largest coefficient).

    Stacks of boxes
    ---------------
    The box methods take and return ``data``, an opaque float ndarray
    whose first axis is the box.  Callers may index it, concatenate stacks
    and keep it per box, and do nothing else with it.
    """

    __slots__ = ()

    # ------------------------------------------------------------ building
    @classmethod
    def parse(cls, source, **params) -> "Surface":
        """Parse text (or take a sympy expression) into a :class:`Surface`.

        Parameters
        ----------
        source : str or sympy.Expr or Surface
            The equation in SingSurf's language (:mod:`singmesh.syntax`):
            ``"lhs = rhs"`` means ``lhs - rhs``; later ``NAME = EXPR;``
            statements define names, which may use x, y, z and each other.
            A Surface is returned as it is (without ``params``).
        **params
            Parameter values (numbers, or text in the same language); they
            override the text's definitions of the same names.

        Returns
        -------
        Surface
            A :class:`PolynomialSurface` for a polynomial (exact Bernstein
            bounds), else a :class:`singmesh.elementary.ElementarySurface`
            (interval bounds and Taylor jets of the expression).

        Raises
        ------
        SurfaceError
            If the input is not a usable function of x, y, z, or a
            parameter is given that it does not use.
        """
        return cls._parse(source, params)

    @classmethod
    def _parse(cls, source, params: dict, optional=frozenset()) -> "Surface":
        """:meth:`parse`, where the names in ``optional`` may go unused (a definition file's parameters)."""
        if isinstance(source, Surface):
            if not params:
                return source
            source = source.expr
        if isinstance(source, sympy.Basic):
            text = str(source)
            expr, values = _substitute(sympy.sympify(source), params, optional)
            rounding = max([0.0] + [2.0 ** -f._prec for f in expr.atoms(sympy.Float)])
        elif isinstance(source, str):
            text = source
            equation = read_equation(source, params, optional)
            expr, values, rounding = equation.expr, equation.values, equation.rounding
        else:
            raise SurfaceError(
                f"a surface is given as text or a sympy expression, not {type(source).__name__}"
            )
        _check_degree_bound(expr)
        if _is_polynomial(expr):
            return PolynomialSurface._from_expr(expr, text, values, rounding)
        fraction = polynomial_fraction(expr)
        if fraction is not None:
            # F = N / D: F = 0 is N = 0 off D = 0, and its closure is N = 0
            # (N, D coprime meet in a curve at most): the polynomial path
            # meshes it exactly, through the lines where it runs into a pole.
            try:
                surface = PolynomialSurface._from_expr(fraction[0], text, values, rounding)
            except SurfaceError:
                pass  # N over the degree limit: the interval path, as any F
            else:
                return replace(surface, denominator=str(fraction[1]))
        else:
            limit = removable_fraction(expr)
            if limit is not None:
                # F = P D / D: 0 / 0 on D = 0, where its limit is P's value
                # (what a user means by (x^2 - y^2) / (x - y)); P = 0 is
                # meshed, D named in the report's notes.
                try:
                    surface = PolynomialSurface._from_expr(limit[0], text, values, rounding)
                except SurfaceError:
                    pass  # P constant or over the degree limit: refused as a removable singularity
                else:
                    return replace(surface, removable=str(limit[1]))
        # sqrt, abs, Min/Max, exp, trig ...: interval bounds and Taylor jets
        # of the expression tree instead of Bernstein tensors.
        from .elementary import ElementarySurface

        return ElementarySurface.from_expr(expr, text, values, rounding)

    # ------------------------------------------------------------ at points
    @abc.abstractmethod
    def __call__(self, points) -> np.ndarray:
        """F at ``points`` (..., 3): shape (...)."""

    @abc.abstractmethod
    def gradient(self, points) -> np.ndarray:
        """grad F at ``points`` (..., 3): shape (..., 3)."""

    @abc.abstractmethod
    def value_gradient(self, points) -> tuple[np.ndarray, np.ndarray]:
        """F and grad F at ``points`` (..., 3): the values of ``self(points)`` and ``self.gradient(points)``."""

    @abc.abstractmethod
    def hessian(self, points) -> np.ndarray:
        """Hessian of F at ``points`` (..., 3): shape (..., 3, 3)."""

    def hessian_each(self, points) -> np.ndarray:
        """The Hessian at each row of ``points`` (K, 3) as :meth:`hessian` gives it
        for that point alone: (K, 3, 3)."""
        points = np.asarray(points, dtype=float).reshape(-1, 3)
        return np.array([self.hessian(p) for p in points]).reshape(-1, 3, 3)

    @abc.abstractmethod
    def jet(self, points) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """F (...), grad F (..., 3) and the Hessian (..., 3, 3) at ``points`` in one pass."""

    @abc.abstractmethod
    def magnitude(self, points) -> np.ndarray:
        """The size of F's terms at ``points`` (..., 3): the scale of its rounding error, (...)."""

    @abc.abstractmethod
    def gradient_magnitude(self, points) -> np.ndarray:
        """:meth:`magnitude` of the three partial derivatives: (..., 3)."""

    def project(self, points, free: np.ndarray | None = None, iterations: int = 8) -> np.ndarray:
        """Points near the surface moved onto it by Newton steps along grad F.

        Where F is undefined beyond an edge of its domain (``sqrt(x)`` for
        x < 0), a step that leaves the domain is halved until it does not
        (at most ``PROJECT_HALVINGS`` times, else the point stays): a
        surface tangent to the domain's edge (``sqrt(x) + y``) draws full
        steps across it.  A point given outside the domain stays as it is.

        Parameters
        ----------
        points : (K, 3) array_like
        free : (K, 3) or (3,) bool, optional
            The axes along which each point may move (a point on a face of
            the domain stays in that face): the steps go along the free
            part of grad F.  All axes by default.
        iterations : int

        Returns
        -------
        (K, 3) ndarray
        """
        p = np.array(points, dtype=float)
        if iterations <= 0:
            return p
        # F and grad F in one pass (the same values as apart).
        f, g = self.value_gradient(p)
        for i in range(iterations):
            gf = g if free is None else g * free
            gg = np.einsum("ij,ij->i", gf, gf)
            step = np.where(gg > 0, f / np.where(gg > 0, gg, 1.0), 0.0)
            delta = step[:, None] * gf
            q = p - delta
            if i == iterations - 1 and self.is_polynomial:
                # A polynomial is defined everywhere: the last step needs no check.
                return q
            fq, gq = self.value_gradient(q)
            if not self.is_polynomial:
                q, fq, gq = self._inside_domain(p, f, g, delta, q, fq, gq)
            p, f, g = q, fq, gq
        return p

    def _inside_domain(self, p, f, g, delta, q, fq, gq):
        """:meth:`project`'s steps ``p -> q = p - delta`` that left F's domain, halved back into it.

        Rows where F and grad F are finite at ``p`` but not at ``q`` take
        half the step, again, up to ``PROJECT_HALVINGS`` times; those still
        outside stay at ``p``.  Returns the new ``q, F(q), grad F(q)``.
        """
        def undefined(fv, gv):
            return ~(np.isfinite(fv) & np.isfinite(gv).all(axis=-1))

        out = np.flatnonzero(undefined(fq, gq) & ~undefined(f, g))
        if not len(out):
            return q, fq, gq
        q, fq, gq = q.copy(), fq.copy(), gq.copy()
        d = delta[out]
        for _ in range(PROJECT_HALVINGS):
            d = 0.5 * d
            q[out] = p[out] - d
            fq[out], gq[out] = self.value_gradient(q[out])
            still = undefined(fq[out], gq[out])
            out, d = out[still], d[still]
            if not len(out):
                return q, fq, gq
        q[out], fq[out], gq[out] = p[out], f[out], g[out]
        return q, fq, gq

    def is_zero(self, points) -> np.ndarray:
        """Whether F is zero at ``points`` to within its rounding error: bool (...)."""
        v = self(points)
        return np.abs(v) <= ZERO_ULPS * np.finfo(float).eps * self.magnitude(points)

    @abc.abstractmethod
    def taylor(self, point, order: int | None = None) -> np.ndarray:
        """Taylor coefficients of F at ``point`` (3,): (n+1, n+1, n+1).

        ``T[i, j, k]`` is the coefficient of ``u^i v^j w^k`` in
        F(point + (u, v, w)), total degree <= n (zero above it); n is
        ``order``, by default :attr:`degree`.
        """

    def value_gradient_each(self, points) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`value_gradient` (K,), (K, 3) at each row of ``points`` (K, 3), each as a
        call at that point alone gives it."""
        points = np.asarray(points, dtype=float).reshape(-1, 3)
        vg = [self.value_gradient(p) for p in points]
        return (np.array([f for f, _ in vg], dtype=float).reshape(-1),
                np.array([g for _, g in vg], dtype=float).reshape(-1, 3))

    def taylor_each(self, points) -> np.ndarray:
        """:meth:`taylor` (default order) at each row of ``points`` (K, 3): (K, n+1, n+1, n+1)."""
        points = np.asarray(points, dtype=float).reshape(-1, 3)
        return np.array([self.taylor(p) for p in points])

    def magnitude_each(self, points) -> np.ndarray:
        """:meth:`magnitude` (K,) at each row of ``points`` (K, 3), each as a call at that point alone gives it."""
        points = np.asarray(points, dtype=float).reshape(-1, 3)
        return np.array([self.magnitude(p) for p in points], dtype=float).reshape(-1)

    def magnitudes_each(self, points) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`magnitude` (K,) and :meth:`gradient_magnitude` (K, 3) at each row of
        ``points`` (K, 3), each as a call at that point alone gives it."""
        points = np.asarray(points, dtype=float).reshape(-1, 3)
        return (np.array([self.magnitude(p) for p in points], dtype=float).reshape(-1),
                np.array([self.gradient_magnitude(p) for p in points], dtype=float).reshape(-1, 3))

    def third_derivatives(self, point) -> np.ndarray:
        """The tensor of third derivatives of F at ``point`` (3,): (3, 3, 3).

        From :meth:`taylor` of order 3: the derivative along axes (i, j, k)
        is ``a! b! c!`` times the coefficient of the monomial ``u^a v^b w^c``
        they make up.
        """
        T = self.taylor(np.asarray(point, dtype=float).reshape(3), 3)
        out = np.empty((3, 3, 3))
        for i, j, k in itertools.product(range(3), repeat=3):
            alpha = np.bincount([i, j, k], minlength=3)
            out[i, j, k] = T[tuple(alpha)] * float(np.prod([math.factorial(int(n)) for n in alpha]))
        return out

    # ------------------------------------------------------------ on boxes
    def undefined_everywhere(self, box) -> bool:
        """Whether F is certainly undefined on the whole of ``box`` (3, 2).

        False for a polynomial (defined everywhere); a function of
        restricted domain (sqrt, log, ...) proves it by its bounds.
        """
        return False

    def removable_singularity(self, box):
        """(divisor, point) where F is 0 / 0 with a limit along a divisor's zeros in ``box``, or None.

        None for a polynomial (no divisor); see ElementarySurface.
        """
        return None

    def ends_near(self, points, radius: float) -> np.ndarray:
        """(k,) bool: F is undefined or unbounded within ``radius`` of each point (False: a polynomial)."""
        return np.zeros(len(np.asarray(points).reshape(-1, 3)), bool)

    def domain_edge_systems(self) -> list[CreaseSystem]:
        """Where the surface may run out of F's domain with F finite there: (G1, G2) systems whose common
        zeros hold those ends (none for a polynomial)."""
        return []

    def continuous_on(self, lo, hi) -> np.ndarray:
        """(k,) bool: F is certainly defined and bounded on each closed box [lo, hi] (k, 3).

        True for a polynomial.  Where False, the box may hold a pole of F
        or an end of its domain: F may change sign in it without a zero.
        """
        return np.ones(len(np.asarray(lo).reshape(-1, 3)), bool)

    @abc.abstractmethod
    def enclose(self, box) -> np.ndarray:
        """``data`` of the one box ``box`` (3, 2): N = 1."""

    @abc.abstractmethod
    def split(self, data: np.ndarray) -> np.ndarray:
        """The eight children of each box: (N, 8, ...), child c at :data:`CHILD_OFFSETS` [c] halves."""

    @abc.abstractmethod
    def excludes_zero(self, data: np.ndarray) -> np.ndarray:
        """(N,) bool: F certainly has no zero on the closed box (with room for rounding).

        Never True where F vanishes; may be False on an empty box.
        """

    @abc.abstractmethod
    def simple_axis(self, data: np.ndarray) -> np.ndarray:
        """(N,) int64: the first axis a for which the box passes the simplicity test, else -1.

        The test: F_a of one sign on the box, and on both faces normal to a
        the curve F = 0 has no closed loop (a tangential derivative of one
        sign there, or F of one sign on the face).  Never claims a simple
        box that is not.
        """

    @abc.abstractmethod
    def face_modes(self, data: np.ndarray, n: int, side: np.ndarray,
                   rows: np.ndarray | None = None) -> np.ndarray:
        """(N,) int64: how F = 0 lies on the face normal to ``n`` of each box.

        ``side`` (N,) picks the low (0) or high (1) face; with u = (n+1)%3,
        v = (n+2)%3: 0 if the curve is known to be a graph over u (F_v of
        one sign on the face), 1 if over v (F_u of one sign), 2 if neither.
        With ``rows`` (K,), only the boxes ``data[rows]`` (without copying
        their data), ``side`` (K,) and the result (K,) theirs.
        """

    @abc.abstractmethod
    def may_vanish(self, data: np.ndarray, axes: tuple[int, ...]) -> np.ndarray:
        """(N,) bool: F and its partial derivatives along ``axes`` may all vanish on the box.

        Never False on a box holding a singular point (of the boxes below
        the last :meth:`enclose`).
        """

    # ------------------------------------------------------------ kinks
    def crease_systems(self) -> list[CreaseSystem]:
        """The kinks of F that may make creases on the surface (none for a smooth F)."""
        return []

    def tip_systems(self) -> list[TipSystem]:
        """Roots of sums of squares in F, whose zeros on the surface are not smooth points (none for a polynomial)."""
        return []

    def root_crease_systems(self) -> list[TipSystem]:
        """Roots of |u| or u^2 in F, whose zeros on the surface are curves where it is not smooth (none for a polynomial)."""
        return []

    # ------------------------------------------------------------ on lines
    @abc.abstractmethod
    def line_roots(self, axis: int, fixed: np.ndarray, s0: np.ndarray,
                   s1: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The zeros of F on axis-parallel segments: (row (R,) int64, s (R,) float64).

        Segment l is {coordinate ``axis`` = s, the two others (cyclic order
        (axis+1)%3, (axis+2)%3) = ``fixed[l]``}, s in [s0[l], s1[l]].
        Every sign change at least once (nearly double roots may come
        too), to full double precision.
        """


@dataclass(frozen=True, eq=False)
class PolynomialSurface(Surface):
    """A real algebraic surface F(x, y, z) = 0: the :class:`Surface` of a polynomial.

    Build it with :meth:`Surface.parse`.  Its box ``data`` are the Bernstein
    tensors of F on the boxes, (N, n0+1, n1+1, n2+1).

    Attributes
    ----------
    text : str
        The input as given (or the sympy expression printed).
    expr : sympy.Expr
        The expanded polynomial, exact where the input was exact.
    coeffs : (nx, ny, nz) ndarray of float64
        Monomial coefficients, ``coeffs[i, j, k]`` of ``x**i y**j z**k``.
    degree : int
        Total degree.
    params : dict
        The parameter values that were substituted.
    rounding : float
        Relative precision of the coefficients as the input gave them: half
        a unit in the last digit of its longest rounded decimal (a 15-digit
        coefficient: 5e-15), and never below double precision.  A point
        where F and grad F vanish to this precision is singular.
    """

    text: str
    expr: sympy.Expr
    coeffs: np.ndarray
    degree: int
    params: Mapping[str, float] = field(default_factory=dict)
    rounding: float = float(np.finfo(float).eps)
    #: For a rational F = N / D: D (the surface is N = 0), else "".
    denominator: str = ""
    #: For a rational F = P D / D: D (F is 0 / 0 on D = 0; the surface is P = 0, its limit), else "".
    removable: str = ""

    is_polynomial = True

    # ------------------------------------------------------------ building
    @classmethod
    def _from_expr(cls, expr, text: str, values: Mapping[str, sympy.Expr],
                   rounding: float = 0.0) -> "PolynomialSurface":
        """The polynomial ``expr`` (checked, expanded) as a surface."""
        expr, coeffs, degree = _polynomial_tensor(expr)
        # Each surface has its own tensor (the cached one is never handed out).
        return cls(text=text, expr=expr, coeffs=coeffs.copy(), degree=degree,
                   params={k: float(v) for k, v in values.items()},
                   rounding=max(float(rounding), float(np.finfo(float).eps)))

    # ------------------------------------------------------------ derived
    @property
    def gradient_coeffs(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Monomial tensors of Fx, Fy, Fz (cached)."""
        cache = self.__dict__.setdefault("_cache", {})
        if "grad" not in cache:
            cache["grad"] = tuple(differentiate(self.coeffs, a) for a in range(3))
        return cache["grad"]

    @property
    def hessian_coeffs(self) -> tuple[tuple[np.ndarray, ...], ...]:
        """Monomial tensors of the second derivatives, ``[a][b]`` (cached)."""
        cache = self.__dict__.setdefault("_cache", {})
        if "hess" not in cache:
            g = self.gradient_coeffs
            cache["hess"] = tuple(
                tuple(differentiate(g[a], b) for b in range(3)) for a in range(3)
            )
        return cache["hess"]

    @property
    def jet_coeffs(self) -> np.ndarray:
        """F, its 3 first and 6 second derivatives stacked: (10, nx, ny, nz)."""
        cache = self.__dict__.setdefault("_cache", {})
        if "jet" not in cache:
            h = self.hessian_coeffs
            cache["jet"] = np.stack([self.coeffs, *self.gradient_coeffs,
                                     h[0][0], h[0][1], h[0][2], h[1][1], h[1][2], h[2][2]])
        return cache["jet"]

    # ------------------------------------------------------------ evaluation
    def jet(self, points):
        """F, grad F and the Hessian at ``points`` (..., 3) in one pass.

        Returns
        -------
        f : (...), g : (..., 3), h : (..., 3, 3)
        """
        p = np.asarray(points, dtype=float)
        shape = p.shape[:-1]
        p = p.reshape(-1, 3)
        c = self.jet_coeffs
        m, nx, ny, nz = c.shape
        # One variable at a time, as matrix products (BLAS): x against the
        # (x; y, component, z) table, then y and z row by row.
        t = powers(p[:, 0], nx) @ c.transpose(1, 2, 0, 3).reshape(nx, -1)  # (K, ny*m*nz)
        t = np.matmul(powers(p[:, 1], ny)[:, None, :], t.reshape(-1, ny, m * nz))  # (K, 1, m*nz)
        v = np.matmul(t.reshape(-1, m, nz), powers(p[:, 2], nz)[:, :, None])[:, :, 0]  # (K, m)
        f = v[:, 0].reshape(shape)
        g = v[:, 1:4].reshape(shape + (3,))
        h = v[:, [4, 5, 6, 5, 7, 8, 6, 8, 9]].reshape(shape + (3, 3))
        return f, g, h

    def __call__(self, points) -> np.ndarray:
        """F at ``points`` (..., 3)."""
        return evaluate_tensor(self.coeffs, points)

    def gradient(self, points) -> np.ndarray:
        """grad F at ``points`` (..., 3), shape (..., 3)."""
        return np.stack(evaluate_tensors(self.gradient_coeffs, points), axis=-1)

    def value_gradient(self, points) -> tuple[np.ndarray, np.ndarray]:
        """F and grad F at ``points`` (..., 3): the values of ``self(points)`` and ``self.gradient(points)``."""
        f, *g = evaluate_tensors([self.coeffs, *self.gradient_coeffs], points)
        return f, np.stack(g, axis=-1)

    def hessian(self, points) -> np.ndarray:
        """Hessian of F at ``points`` (..., 3), shape (..., 3, 3)."""
        h = self.hessian_coeffs
        v = evaluate_tensors([h[a][b] for a in range(3) for b in range(3)], points)
        rows = [np.stack(v[3 * a:3 * a + 3], -1) for a in range(3)]
        return np.stack(rows, axis=-2)

    def hessian_each(self, points) -> np.ndarray:
        """:meth:`Surface.hessian_each`: one call for all the points (stacked one-row products)."""
        h = self.hessian_coeffs
        v = evaluate_tensors([h[a][b] for a in range(3) for b in range(3)],
                             np.asarray(points, dtype=float).reshape(-1, 3), alone=True)
        rows = [np.stack(v[3 * a:3 * a + 3], -1) for a in range(3)]
        return np.stack(rows, axis=-2)

    def is_zero(self, points) -> np.ndarray:
        """Whether F is zero at ``points`` to within its rounding error: bool (...).

        :meth:`Surface.is_zero`; the sum of |terms| is evaluated only when
        some |F| is below its bound (sum |c|) max(1, |p|)^degree (twice it,
        for the rounding of the sum): at lattice corners F is rarely zero.
        """
        p = np.asarray(points, dtype=float)
        v = self(p)
        eps = ZERO_ULPS * np.finfo(float).eps
        # max(1, |x|, |y|, |z|) per point (not a reduction along the axis of 3: a call per point)
        a = np.abs(p)
        reach = np.maximum(np.maximum(np.maximum(a[..., 0], a[..., 1]), a[..., 2]), 1.0)
        bound = 2.0 * float(np.abs(self.coeffs).sum()) * reach ** self.degree
        small = np.abs(v) <= eps * bound
        if not small.any():
            return np.zeros(v.shape, bool)
        if v.size <= _MANY:
            return np.abs(v) <= eps * self.magnitude(p)
        # Only where |F| is under the bound can it be under eps * sum |terms|
        # (at most the bound): the sum of |terms| is read there alone, by the
        # many-points contraction whose bits do not depend on the other points.
        out = np.zeros(v.shape, bool)
        out[small] = np.abs(v[small]) <= eps * evaluate_tensors_many([np.abs(self.coeffs)], np.abs(p[small]))[0]
        return out

    def magnitude(self, points) -> np.ndarray:
        """Sum of |terms| of F at ``points``: the scale of F's rounding error."""
        return evaluate_tensor(np.abs(self.coeffs), np.abs(np.asarray(points, float)))

    def gradient_magnitude(self, points) -> np.ndarray:
        """Sum of |terms| of Fx, Fy, Fz at ``points``: (..., 3)."""
        p = np.abs(np.asarray(points, float))
        return np.stack(evaluate_tensors([np.abs(g) for g in self.gradient_coeffs], p), axis=-1)

    @property
    def scale(self) -> float:
        """The largest |coefficient| (cached)."""
        cache = self.__dict__.setdefault("_cache", {})
        if "scale" not in cache:
            cache["scale"] = float(np.abs(self.coeffs).max())
        return cache["scale"]

    def taylor(self, point, order: int | None = None) -> np.ndarray:
        """Taylor coefficients at ``point``: exact up to rounding at the default order (the degree)."""
        p = np.asarray(point, dtype=float).reshape(3)
        n = self.degree if order is None else int(order)
        T = compose(self.coeffs, p, np.eye(3), min(n, self.degree))
        if n <= self.degree:
            return T
        out = np.zeros((n + 1,) * 3)
        out[: self.degree + 1, : self.degree + 1, : self.degree + 1] = T
        return out

    def taylor_each(self, points) -> np.ndarray:
        """:meth:`Surface.taylor_each`: all the translations in one pass (the bits of each point's own)."""
        return translate_many(self.coeffs, np.asarray(points, dtype=float).reshape(-1, 3), self.degree)

    def value_gradient_each(self, points) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`Surface.value_gradient_each` in one call (stacked one-row products)."""
        f, *g = evaluate_tensors([self.coeffs, *self.gradient_coeffs],
                                 np.asarray(points, dtype=float).reshape(-1, 3), alone=True)
        return f, np.stack(g, axis=-1)

    def magnitude_each(self, points) -> np.ndarray:
        """:meth:`Surface.magnitude_each` in one call (stacked one-row products)."""
        p = np.abs(np.asarray(points, dtype=float).reshape(-1, 3))
        return evaluate_tensors([np.abs(self.coeffs)], p, alone=True)[0]

    def magnitudes_each(self, points) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`Surface.magnitudes_each` in two calls (stacked one-row products)."""
        p = np.abs(np.asarray(points, dtype=float).reshape(-1, 3))
        mag = evaluate_tensors([np.abs(self.coeffs)], p, alone=True)[0]
        grad = evaluate_tensors([np.abs(g) for g in self.gradient_coeffs], p, alone=True)
        return mag, np.stack(grad, axis=-1)

    def third_derivatives(self, point) -> np.ndarray:
        """Third derivatives at ``point`` (3,) from their monomial tensors (cached)."""
        cache = self.__dict__.setdefault("_cache", {})
        if "third" not in cache:
            h = self.hessian_coeffs
            cache["third"] = [[[differentiate(h[i][j], k) for k in range(3)] for j in range(3)] for i in range(3)]
        c = cache["third"]
        x = np.asarray(point, dtype=float).reshape(3)
        return np.array([[[float(evaluate_tensor(c[i][j][k], x[None])[0]) for k in range(3)] for j in range(3)]
                         for i in range(3)])

    # ------------------------------------------------------------ on boxes
    def enclose(self, box) -> np.ndarray:
        """Bernstein tensor on ``box``, (1, n0+1, n1+1, n2+1); the root of later :meth:`may_vanish` tests."""
        root = bernstein_on_box(self.coeffs, np.asarray(box, dtype=float))[None]
        # Splitting from the root leaves rounding dust of the root's size on
        # coefficients that should be exactly zero (at a singular point on a
        # split plane): tiny next to the box's own coefficients at depth.
        self.__dict__.setdefault("_cache", {})["dust"] = CANDIDATE_DUST * float(np.abs(root).max())
        return root

    def split(self, data: np.ndarray) -> np.ndarray:
        """De Casteljau at the midpoints: (N, 8, n0+1, n1+1, n2+1)."""
        return bernstein_split(data).reshape((len(data), 8) + data.shape[1:])

    def excludes_zero(self, data: np.ndarray) -> np.ndarray:
        """All coefficients clearly of one sign (``PRUNE_SLACK``)."""
        return polynomial_bounds.empty_boxes(data)

    def simple_axis(self, data: np.ndarray) -> np.ndarray:
        """:func:`singmesh.boxes.polynomial_bounds.monotone_axis`."""
        return polynomial_bounds.monotone_axis(data)

    def face_modes(self, data: np.ndarray, n: int, side: np.ndarray,
                   rows: np.ndarray | None = None) -> np.ndarray:
        """:func:`singmesh.boxes.polynomial_bounds.face_modes`."""
        return polynomial_bounds.face_modes(data, n, side, rows)

    def may_vanish(self, data: np.ndarray, axes: tuple[int, ...]) -> np.ndarray:
        """Bernstein coefficients of F and of each derivative of both signs,
        allowing for the dust of the last :meth:`enclose`'s root."""
        dust = self.__dict__.get("_cache", {}).get("dust", 0.0)
        return polynomial_bounds.may_vanish(data, axes, dust)

    # ------------------------------------------------------------ on lines
    def line_roots(self, axis: int, fixed: np.ndarray, s0: np.ndarray,
                   s1: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Companion-matrix roots of F on the segments, Newton-polished."""
        return polynomial_lines.line_roots(self.coeffs, axis, fixed, s0, s1)

    def __str__(self) -> str:
        """The expanded polynomial, decimals written as decimals (``0.123`` not ``123/1000``)."""
        subs = {}
        for r in self.expr.atoms(sympy.Rational):
            text = None if r.q == 1 else _decimal(r)
            if text is not None and len(text.strip("-").replace(".", "").strip("0")) > DISPLAY_DIGITS:
                subs[r] = _short_float(r)  # 1 + 1e-300: 301 digits
            elif text is not None:
                subs[r] = sympy.Float(text, len(text.strip("-").replace(".", "").lstrip("0")))
            elif max(abs(int(r.p)), int(r.q)) >= 10 ** DISPLAY_DIGITS:
                # 1e300 is read as an exact integer of 301 digits: shown
                # as the float it was typed as (display only).
                subs[r] = _short_float(r)
        return str(self.expr.xreplace(subs))

    def __repr__(self) -> str:
        return f"PolynomialSurface({str(self)!r}, degree={self.degree})"


@lru_cache(maxsize=64)
def _polynomial_tensor(expr: sympy.Expr) -> tuple[sympy.Expr, np.ndarray, int]:
    """The polynomial ``expr`` checked and expanded, its monomial tensor (read-only) and degree.

    Cached per expression (sympy's == tells 2.0 from 2 and Floats of other
    precisions apart): meshing one surface again (another box, another
    resolution) does not expand and convert it again (2 of Barth's 4 ms of
    parsing, 0.15 of a sphere's 0.4 ms).
    """
    check_variables(expr)
    _check_polynomial(expr)
    expr = sympy.expand(expr)
    try:
        poly = sympy.Poly(expr, *VARIABLES)
    except sympy.PolynomialError as exc:  # pragma: no cover - caught above
        raise SurfaceError(f"not a polynomial in x, y, z: {exc}") from None
    if poly.is_zero:
        raise SurfaceError("the polynomial is identically zero: every point is on it")
    degree = poly.total_degree()
    if degree > MAX_DEGREE:
        raise SurfaceError(
            f"degree {degree} is over the limit of {MAX_DEGREE} "
            "(Bernstein forms lose too much precision beyond it)"
        )
    if degree == 0:
        raise SurfaceError("the polynomial is a nonzero constant: its zero set is empty")
    dims = [max(m[a] for m in poly.monoms()) + 1 for a in range(3)]
    coeffs = np.zeros(dims)
    for monom, c in poly.terms():
        coeffs[monom] = _to_float(c, monom)
    if not np.any(coeffs):
        raise SurfaceError("all coefficients round to zero in double precision")
    coeffs.flags.writeable = False
    return expr, coeffs, degree


# ---------------------------------------------------------------- checks
def check_variables(expr: sympy.Expr) -> None:
    """Raise SurfaceError naming the symbols of ``expr`` other than x, y, z."""
    unknown = sorted(s.name for s in expr.free_symbols if s not in VARIABLES)
    if unknown:
        raise SurfaceError(
            "unknown symbol%s %s: only x, y, z are variables; give parameters as "
            "keyword arguments or as definitions such as '; %s = 1;'"
            % ("s" if len(unknown) > 1 else "", ", ".join(unknown), unknown[0])
        )


def _degree_bound(expr: sympy.Expr) -> int:
    """An upper bound of the degree in x, y, z of the polynomial parts of ``expr``.

    Sums take the largest, products add, integer powers multiply; the
    argument of a function or of a fractional power is bounded on its own
    (the largest bound met anywhere is returned), its value counts 0.
    Computed on the tree as written, before sympy expands it.
    """
    worst = 0
    seen: dict = {}  # shared subtrees (definitions used twice) once

    def walk(e: sympy.Expr) -> int:
        nonlocal worst
        if e in seen:
            return seen[e]
        if e in VARIABLES:
            d = 1
        elif not e.free_symbols & set(VARIABLES):
            d = 0
        elif isinstance(e, sympy.Add):
            d = max(walk(a) for a in e.args)
        elif isinstance(e, sympy.Mul):
            d = sum(walk(a) for a in e.args)
        elif isinstance(e, sympy.Pow) and e.exp.is_Integer:
            d = abs(int(e.exp)) * walk(e.base)
        else:
            for a in e.args:
                walk(a)
            d = 0
        worst = max(worst, d)
        seen[e] = d
        return d

    walk(expr)
    return worst


def _check_degree_bound(expr: sympy.Expr) -> None:
    """Refuse F whose powers of x, y, z are far over ``MAX_DEGREE`` before sympy expands them."""
    bound = _degree_bound(expr)
    if bound > MAX_POWER:
        raise SurfaceError(f"degree up to {bound} is over the limit of {MAX_DEGREE} "
                           "(Bernstein forms lose too much precision beyond it)")


def _cancelled(expr: sympy.Expr):
    """(N, D), coprime polynomials with F = N / D, for a rational F in x, y, z; else None."""
    if not expr.is_rational_function(*VARIABLES) or not expr.free_symbols <= set(VARIABLES):
        return None
    try:
        return sympy.fraction(sympy.cancel(sympy.together(expr)))
    except (TypeError, ValueError, sympy.PolynomialError):  # pragma: no cover - sympy cannot combine it
        return None


def polynomial_fraction(expr: sympy.Expr):
    """(N, D), coprime polynomials with F = N / D, for a rational F that is not a polynomial; else None."""
    fraction = _cancelled(expr)
    if fraction is None or not fraction[1].free_symbols:
        return None
    return fraction


def removable_fraction(expr: sympy.Expr):
    """(P, D) for a rational F = N / D whose denominator cancels entirely (N = P D, P a polynomial); else None.

    F is 0 / 0 on D = 0 and equals P elsewhere: P is its continuous
    extension.  (The parser reads decimals exactly, so a factor typed
    with 15-digit coefficients cancels exactly too.)
    """
    fraction = _cancelled(expr)
    if fraction is None or fraction[1].free_symbols:
        return None
    # (the divisors as written: sympy's together may already cancel them)
    divisors = list(dict.fromkeys(node.base for node in sympy.preorder_traversal(expr)
                                  if isinstance(node, sympy.Pow) and node.exp.is_negative
                                  and node.base.free_symbols))
    if not divisors:
        return None
    return sympy.expand(fraction[0] / fraction[1]), sympy.Mul(*divisors)


def _is_polynomial(expr: sympy.Expr) -> bool:
    """Whether ``expr`` is a polynomial in x, y, z (other symbols are left to the builder's message)."""
    try:
        _check_polynomial(expr)
    except SurfaceError:
        return False
    return True


def _check_polynomial(expr: sympy.Expr) -> None:
    """Raise SurfaceError naming the first subexpression that is not polynomial."""
    for node in sympy.preorder_traversal(expr):
        if not node.free_symbols:
            continue
        if isinstance(node, sympy.Pow):
            e = node.exp
            if not (e.is_Integer and e >= 0) and node.base.free_symbols:
                raise SurfaceError(f"not a polynomial in x, y, z: it contains {node}")
        elif isinstance(node, sympy.Function) or node.func in (sympy.Abs,):
            raise SurfaceError(
                f"not a polynomial in x, y, z: it contains {node.func.__name__}({', '.join(map(str, node.args))})"
            )
        elif not isinstance(node, (sympy.Add, sympy.Mul, sympy.Symbol, sympy.Pow)):
            raise SurfaceError(f"not a polynomial in x, y, z: it contains {node}")


def _to_float(c: sympy.Expr, monom) -> float:
    value = complex(sympy.N(c, 30))
    term = "x^%d y^%d z^%d" % tuple(monom)
    if value.imag != 0:
        raise SurfaceError(f"the coefficient of {term} is not real: {c}")
    if not np.isfinite(value.real):
        raise SurfaceError(f"the coefficient of {term} is out of the range of double precision: {sympy.N(c, 4)}")
    if value.real == 0 and c != 0:
        # Read as 0 the term would be dropped without a word: x^2 - 1e-400
        # would mesh x^2 (a double plane, no sign change: an empty mesh).
        raise SurfaceError(f"the coefficient of {term} is below the range of double precision "
                           f"(it would be read as 0): {sympy.N(c, 4)}; scale the equation or leave the term out")
    return float(value.real)


def _substitute(expr: sympy.Expr, params: Mapping, optional=frozenset()) -> tuple[sympy.Expr, dict]:
    """A user's sympy expression with x, y, z and ``params`` identified by name.

    Symbols may come with other assumptions than ours (``sympy.symbols('x')``).
    A parameter the expression does not have is refused, unless in ``optional``.
    """
    if not isinstance(expr, sympy.Expr):
        raise SurfaceError(f"{expr} is not an algebraic expression")
    values = {}
    for name, value in params.items():
        try:
            v = sympy.sympify(value)
        except (sympy.SympifyError, TypeError):
            raise SurfaceError(f"parameter {name} = {value!r} is not a number") from None
        if not isinstance(v, sympy.Expr) or v.free_symbols:
            raise SurfaceError(f"parameter {name} = {value!r} is not a number")
        values[name] = v
    names = {sym.name for sym in expr.free_symbols}
    unused = sorted(n for n in values if n not in names and n not in optional)
    if unused:
        raise SurfaceError(unused_message(unused, sorted(names - {"x", "y", "z"})))
    subs = {}
    for sym in expr.free_symbols:
        if sym.name in ("x", "y", "z"):
            subs[sym] = VARIABLES["xyz".index(sym.name)]
        elif sym.name in values:
            subs[sym] = values[sym.name]
    expr = expr.xreplace(subs)
    if expr.has(sympy.nan, sympy.zoo, sympy.oo, -sympy.oo):
        raise SurfaceError("the equation has a NaN or infinite coefficient")
    return expr, values


def _short_float(r: sympy.Rational) -> sympy.Float:
    """The shortest float text of r as a sympy Float of that many digits (15 where r overflows)."""
    value = float(r)
    if not np.isfinite(value):
        return sympy.Float(r, 15)
    mantissa = repr(value).split("e")[0].lstrip("-")
    return sympy.Float(repr(value), max(1, len(mantissa.replace(".", "").lstrip("0").rstrip("0") or "0")))


def _decimal(r: sympy.Rational) -> str | None:
    """The exact decimal of a rational whose denominator is 2^a 5^b, else None."""
    q, twos, fives = int(r.q), 0, 0
    while q % 2 == 0:
        q, twos = q // 2, twos + 1
    while q % 5 == 0:
        q, fives = q // 5, fives + 1
    if q != 1:
        return None
    digits = max(twos, fives)
    text = str(abs(int(r.p)) * 10 ** digits // int(r.q)).rjust(digits + 1, "0")
    return ("-" if r.p < 0 else "") + text[:-digits] + "." + text[-digits:]
