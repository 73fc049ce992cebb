"""Classify isolated singular points of real surfaces F(x, y, z) = 0.

:func:`classify` takes a surface and a point at which F and grad F vanish
(known to ~1e-12) and returns a :class:`SingularityType`: the corank of the
Hessian, the Milnor number, the ADE type (A_k, D_k, E6, E7, E8, or
"non-simple"), the real form in the sign notation of the thesis seed
(Definition 10), the number of real branches through the point and, for
A-type points, the local axis used to triangulate around them.

Method
------
1. Taylor polynomial of F at the point, in floating point
   (``Surface.taylor``; for a polynomial, Horner's rule on the monomial
   tensor: :func:`singmesh.skeleton.splitting.compose`).
2. Hessian eigen-decomposition.  Eigenvalues with ``|lambda| <= RANK * S``
   are zero (S: the largest Taylor coefficient of degree >= 2, see
   :mod:`singmesh.tolerances`); this gives the corank and the signature.
3. Corank 0 is A1 (Morse lemma); corank 3 is never simple.
4. Corank 1 or 2: rotate to the eigenbasis and apply the splitting lemma
   (:func:`singmesh.skeleton.splitting.split`): solve ``dG/dw = 0`` for
   the non-degenerate variables as power series in the kernel variables t,
   so that ``F ~ g(t) + sum lambda_i / 2 w_i^2``.
5. Corank 1: ``g(t) = c t^(k+1) + ...`` gives A_k.
6. Corank 2, Arnold's determinator on the binary cubic C of g:
   three distinct lines (discriminant != 0) -> D4; a double line -> D_k
   with k from the polar curve (below); a triple line -> E6 / E7 / E8 from
   the coefficients of y^4, x y^3, y^5 in coordinates where C = x^3;
   C = 0 -> non-simple.
   D_k: in coordinates where C = x^2 y, the polar curve ``g_x = 0`` has a
   smooth branch x = y s(y) tangent to the double line, and the critical
   value ``h(y) = g(y s(y), y)`` of x -> g(x, y) along it has order k - 1.
   (Proof: mu = i(g_x, g_y) sums the orders of g_y = h' along the two
   branches of the node g_x = 0: 2 along the branch tangent to y = 0,
   k - 2 along this one, and mu(D_k) = k.)  Completing the square in x
   makes g = y x'^2 + h(y) to the order that matters, so the sign of the
   leading coefficient of h is the sign of y^(k-1) in the normal form.

Real forms (Definition 10 of the seed) and the names used
-----------------------------------------------------------
The germs ``F`` and ``-F`` have the same zero set, and the point of the
classification is the shape of the surface, so real forms equivalent under
a real coordinate change (reflections included) combined with F -> -F get
one name.  The equivalences follow from x -> -x, y -> -y, z -> -z, swapping
the two squared variables, and F -> -F on the normal forms:

=========  ======================================  ===================
family     classes (normal-form sign pairs)        name used
=========  ======================================  ===================
A1         {++}; {+-, -+, --}                      A1++ ; A1--
A_k, odd   {++}; {+-, -+}; {--}        (k >= 3)    Ak++ ; Ak+- ; Ak--
A_k, even  {++, --}; {+-, -+}                      Ak-- ; Ak+-
D4         {++, +-}; {-+, --}                      D4+- ; D4--
D_k, odd   {++, --}; {+-, -+}                      Dk-- ; Dk+-
D_k, even  {++, +-}; {-+, --}          (k >= 6)    Dk+- ; Dk--
E6         {++, --}; {+-, -+}                      E6++ ; E6+-
E7         {++, +-, -+, --}                        E7++
E8         {++, +-, -+, --}                        E8++
=========  ======================================  ===================

The representatives are the ones whose geometry and triangulation vectors
the thesis describes ("we only discuss A_n-- and A_n+-", "D_n+- and D_n--",
"E6++, E6+-, E7++ and E8++"), so that a name can be looked up there
directly; A_k++ for odd k is the isolated real point x^(k+1) + y^2 + z^2
(no other sign pair is equivalent to it), and A1+- is the same cone as A1--
(x^2 - y^2 - z^2 = -(z^2 + y^2 - x^2)), named A1-- as in the thesis.
Classes in different rows of one family are really different: the sign
pattern of the non-degenerate part of the Hessian (A), the number of real
lines of the cubic (D4) or of real branches (D_k even), or the tangent cones
of the regions {g >= 0} and {g <= 0} (D_k odd, E6) tell them apart.

Real branches (components of the surface on a small sphere around the
point): a germ ``g(x, y) + lambda z^2`` is the double cover of the region
{-sign(lambda) g >= 0}; with r >= 1 real branches of the curve g = 0 that
region has r sectors, giving r branches, and with r = 0 the surface is two
sheets or a single point.  Hence A_k: 1 (k even), 2 (k odd, +- or --), 0
(k odd, ++); D_k: 2 (k odd), 1 (k even, +-), 3 (k even, --); E6: 1, E7: 2,
E8: 1.

Tolerances are in :mod:`singmesh.tolerances` (``CLASSIFY_*``).
"""

from __future__ import annotations

import argparse
import math
import re
import sys
from dataclasses import dataclass
from fractions import Fraction
from functools import lru_cache
from typing import Sequence

import numpy as np

from singmesh.errors import SurfaceError
from singmesh.surface import Surface
from singmesh.tolerances import (
    CLASSIFY_JET_RTOL,
    CLASSIFY_ORDERS,
    CLASSIFY_RANK_RTOL,
    CLASSIFY_SINGULAR_RTOL,
    INPUT_ROUNDING,
    ZERO_ULPS,
)

from .splitting import compose, degree_grid, derivative, mul, series_order, split

__all__ = ["SingularityType", "NotSingularError", "Frame", "analyse", "analyse_each", "classify", "classify_command"]


#: The notes of the two non-simple classes whose centre is regular to find
#: (:mod:`singmesh.skeleton.centre`): the whole 2-jet, or the kernel's 2-
#: and 3-jet, vanishes there.
NOTE_CORANK3 = "corank 3 (type P8 or worse)"
NOTE_ZERO_CUBIC = "corank 2 and the cubic term vanishes (type X9 or worse)"
NOTE_CUBE = "corank 2, the cubic is a cube and the y^4, x y^3, y^5 terms vanish (type J10 or worse)"


class NotSingularError(SurfaceError):
    """The given point is not a singular point of the surface."""


@dataclass(frozen=True)
class SingularityType:
    """What kind of singular point a point of a surface is.

    Attributes
    ----------
    name : str
        ``"A1"``, ``"A2"``, ..., ``"D4"``, ..., ``"E6"``, ``"E7"``, ``"E8"``,
        or ``"non-simple"``.
    real_form : str or None
        The name with the normalised sign pair of Definition 10, e.g.
        ``"A1--"``, ``"D4--"``, ``"E7++"`` (see the module docstring for the
        representatives); None for non-simple points.
    corank : int
        3 - rank of the Hessian of F.
    milnor : int or None
        Milnor number (k for A_k, D_k, E_k); None when not determined
        (non-simple, possibly infinite).
    branches : int or None
        Number of connected components of the surface on a small sphere
        around the point (0 for an isolated real point); None for
        non-simple points.
    axis : tuple of 3 floats or None
        For A-type points with real branches: the unit triangulation vector
        of the thesis, in world coordinates.  For the half-cone A_k-- (k
        even) it points into the cone; for two-branch A_k the branches lie
        along +axis and -axis.  None for D, E, non-simple and isolated
        points.
    hessian_signature : tuple of 3 ints
        (number of positive, negative, zero eigenvalues) of the Hessian of F.
    jet : str
        The 3-jet of F at the point, in coordinates x, y, z centred there.
    point : tuple of 3 floats
        The point classified.
    note : str
        Extra explanation (why a point is non-simple, etc.).
    """

    name: str
    real_form: str | None
    corank: int
    milnor: int | None
    branches: int | None
    axis: tuple[float, float, float] | None
    hessian_signature: tuple[int, int, int]
    jet: str
    point: tuple[float, float, float]
    note: str = ""

    @property
    def is_simple(self) -> bool:
        """Whether the point is an ADE (simple) singularity."""
        return self.name != "non-simple"

    def describe(self) -> str:
        """One readable line, e.g. ``A1-- (node) at (...): corank 0, ...``."""
        where = "(" + ", ".join(_num(c) for c in self.point) + ")"
        p, m, z = self.hessian_signature
        sig = f"Hessian signature ({p}+, {m}-, {z} zero)"
        if self.name == "non-differentiable":
            return f"non-differentiable at {where}: {self.note}"
        if not self.is_simple:
            line = f"non-simple at {where}: corank {self.corank}, {sig}, 3-jet {self.jet}"
            return line + (f"; {self.note}" if self.note else "")
        nick = _nickname(self)
        head = f"{self.real_form}" + (f" ({nick})" if nick else "")
        nb = self.branches
        parts = [
            f"corank {self.corank}",
            f"Milnor number {self.milnor}",
            sig,
            f"{nb} real branch" + ("" if nb == 1 else "es"),
        ]
        if self.axis is not None:
            parts.append("axis (" + ", ".join(f"{c:.4f}" for c in self.axis) + ")")
        line = f"{head} at {where}: " + ", ".join(parts)
        return line + (f"; {self.note}" if self.note else "")

    def __str__(self) -> str:
        return self.describe()


def _num(c: float) -> str:
    return f"{c:.10g}"


def _nickname(t: SingularityType) -> str:
    if t.branches == 0:
        return "isolated real point"
    if t.name == "A1":
        return "node"
    if t.name == "A2":
        return "cusp"
    if t.name == "A3":
        return "tacnode"
    if t.name.startswith("A") and t.branches == 1 and t.real_form.endswith("--"):
        return "half-cone"
    if t.branches == 3:
        return "three half-cones"
    return ""


# ----------------------------------------------------------------- classify
def classify(surface: "Surface | str", point: Sequence[float]) -> SingularityType:
    """Classify the singular point ``point`` of ``surface``.

    Parameters
    ----------
    surface : Surface or str or sympy.Expr
        The surface F = 0 (text is parsed with :meth:`Surface.parse`).
    point : sequence of 3 floats
        A singular point, known to about 1e-12 (higher types need it to
        about 1e-9 of the polynomial's scale: an offset delta adds ~ k delta
        to the coefficient that decides A_k versus A_(k-1)).

    Returns
    -------
    SingularityType

    Raises
    ------
    SurfaceError
        Bad surface text or point.
    NotSingularError
        (a SurfaceError) if F or grad F is not zero at the point within
        ``CLASSIFY_SINGULAR_RTOL``.
    """
    s = surface if isinstance(surface, Surface) else Surface.parse(surface)
    return analyse(s, _as_point(point))[0]


@dataclass(frozen=True)
class Frame:
    """Coordinates in which a singular point's type was read (for centring it).

    Attributes
    ----------
    basis : (3, 3) ndarray
        Hessian eigenvectors as columns, the ``corank`` kernel vectors first.
    eigenvalues : (3,) ndarray
        In the same order.
    corank : int
    kernel : (corank, corank) ndarray or None
        Corank 2: columns (X, Y) in the kernel coordinates in which the
        cubic term is X^2 Y (D_k, k >= 5) or X^3 (E_k); the identity for D4.
    order : int
        Truncation order of the power series the type was read from.
    scale : float
        The largest Taylor coefficient of degree >= 2: the rank and jet
        tolerances are relative to it.
    """

    basis: np.ndarray
    eigenvalues: np.ndarray
    corank: int
    kernel: np.ndarray | None
    order: int
    scale: float = 0.0


def analyse_each(s: Surface, points: np.ndarray) -> list:
    """:func:`analyse` (default tolerances) at each row of ``points`` (K, 3).

    The Taylor polynomials and the sizes of F's terms of all the points
    are computed in one pass each (with the bits of each point's own
    calls); the rest is :func:`analyse`'s, point by point.

    Returns
    -------
    list of (SingularityType, Frame), or of the exception (a SurfaceError:
    NotSingularError, no jet) that :func:`analyse` raises at that point
    """
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    if len(points) == 0:
        return []
    try:
        known = list(zip(s.taylor_each(points), *s.magnitudes_each(points)))
    except _NOT_A_POINTS_ANSWER:
        raise
    except Exception:
        # (a point where F has no jet: each point says so on its own)
        known = [None] * len(points)
    out: list = []
    for p, k in zip(points, known):
        # Whatever a point raises is its own answer, raised when (and only
        # if) the caller asks for that point.
        try:
            out.append(analyse(s, p, _known=k))
        except _NOT_A_POINTS_ANSWER:
            raise
        except Exception as e:
            out.append(e)
    return out


#: Errors from outside the computation (a time limit's alarm, which the
#: gallery raises as a TimeoutError; memory): raised at once, never kept
#: as a point's answer.
_NOT_A_POINTS_ANSWER = (OSError, MemoryError)


def analyse(s: Surface, p: np.ndarray, rank_rtol: float = CLASSIFY_RANK_RTOL,
            jet_rtol: float = CLASSIFY_JET_RTOL, _known=None) -> tuple[SingularityType, Frame]:
    """:func:`classify` for a parsed surface, with the frame the type was read in.

    ``rank_rtol`` sets which Hessian eigenvalues count as zero and
    ``jet_rtol`` which Taylor coefficients do (relative to the largest);
    centring reads the type more loosely than naming does.  ``_known``
    (from :func:`analyse_each`): the Taylor polynomial at p and the sizes
    of F's and grad F's terms there, computed already.
    """
    # Taylor polynomial at p (exact up to rounding: no truncation).
    T = s.taylor(p) if _known is None else _known[0]
    if not np.isfinite(T).all():
        # (a root of a sum of squares vanishing there: the apex of
        # sqrt(x^2 + y^2) = |z|; mesh() places such points as tips)
        raise SurfaceError(f"F is not differentiable at ({', '.join(f'{c:.10g}' for c in p)}): "
                           "it has no Taylor jet to classify")
    deg = degree_grid(3, T.shape[0] - 1)
    S = float(np.max(np.abs(T[deg >= 2]), initial=0.0))
    _check_singular(s, p, T, S, None if _known is None else _known[1:])

    hess = T[_HESSIAN_INDEX] * _HESSIAN_FACTOR
    lam, vec = np.linalg.eigh(hess)
    zero = np.abs(lam) <= rank_rtol * S
    signature = (int(np.sum((lam > 0) & ~zero)), int(np.sum((lam < 0) & ~zero)), int(np.sum(zero)))
    corank = signature[2]
    order = np.argsort(np.abs(lam), kind="stable")   # kernel variables first
    lam, vec = lam[order], vec[:, order]
    jet = _format_jet(T, CLASSIFY_JET_RTOL * S)
    common = dict(corank=corank, hessian_signature=signature, jet=jet,
                  point=tuple(float(c) for c in p))
    frame = {"basis": vec, "eigenvalues": lam, "corank": corank, "kernel": None, "order": 0, "scale": S}

    if corank == 0:
        return _a1(lam, vec, common), Frame(**frame)
    if corank == 3:
        return SingularityType(name="non-simple", real_form=None, milnor=None, branches=None,
                               axis=None, note=NOTE_CORANK3, **common), Frame(**frame)

    tol = jet_rtol * S
    mu = lam[corank:]
    for N in CLASSIFY_ORDERS:
        # Rotate to the eigenbasis (kernel first), truncated at order N.
        G = compose(T, np.zeros(3), vec, N)
        g, _ = split(G, corank, mu, N)
        frame["order"] = N
        if corank == 1:
            found = _corank1(g, mu, vec, tol, common)
        else:
            found = _corank2(g, mu, tol, N, common, frame)
        if found is not None:
            return found, Frame(**frame)
    N = max(CLASSIFY_ORDERS)
    if corank == 1:
        note = (f"the residual function vanishes to order {N}: a curve of singular points "
                f"(A_inf) or A_k with k >= {N}")
    else:
        note = (f"the 3-jet has a double line and the polar invariant vanishes to order {N}: "
                f"a curve of singular points (D_inf) or D_k with k > {N + 1}")
    return SingularityType(name="non-simple", real_form=None, milnor=None, branches=None,
                           axis=None, note=note, **common), Frame(**frame)


#: The entries of a Taylor tensor holding the Hessian ((3, 3) index arrays), and their factors
#: (2 on the diagonal: the coefficient of x^2 is F_xx / 2).
_HESSIAN_INDEX = tuple((np.arange(3)[:, None] == c).astype(np.int64) + (np.arange(3)[None, :] == c) for c in range(3))
_HESSIAN_FACTOR = np.where(np.eye(3, dtype=bool), 2.0, 1.0)


def _as_point(point) -> np.ndarray:
    try:
        p = np.asarray(point, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise SurfaceError(f"a point is three numbers, not {point!r}") from None
    if p.shape != (3,):
        raise SurfaceError(f"a point is three numbers, got {p.size}")
    if not np.all(np.isfinite(p)):
        raise SurfaceError(f"the point ({', '.join(f'{c:g}' for c in p)}) is not finite")
    return p


def _unit(a: int) -> tuple[int, int, int]:
    e = [0, 0, 0]
    e[a] = 1
    return tuple(e)


def _check_singular(s: Surface, p: np.ndarray, T: np.ndarray, S: float, sizes=None) -> None:
    """Raise NotSingularError unless F(p) = 0 and grad F(p) = 0 to tolerance.

    ``sizes``: ``s.magnitude(p)`` and ``s.gradient_magnitude(p)`` if known.
    """
    eps = np.finfo(float).eps
    value = float(T[0, 0, 0])
    grad = np.array([T[_unit(a)] for a in range(3)])
    # Rounding error of evaluating F and its gradient at p, and what the
    # rounding of the input's own coefficients can make of them.
    ulps = ZERO_ULPS * eps + INPUT_ROUNDING * s.degree * s.rounding
    magnitude, gradient_magnitude = (s.magnitude(p), s.gradient_magnitude(p)) if sizes is None else sizes
    round_v = ulps * float(magnitude)
    round_g = ulps * float(np.max(gradient_magnitude))
    tol = CLASSIFY_SINGULAR_RTOL * S
    bad = []
    if abs(value) > tol + round_v:
        bad.append(f"F = {value:.3g} is not zero (the point is not on the surface)")
    gnorm = float(np.linalg.norm(grad))
    if gnorm > tol + round_g:
        bad.append(f"|grad F| = {gnorm:.3g} is not zero")
    if bad:
        where = "(" + ", ".join(_num(c) for c in p) + ")"
        raise NotSingularError(
            f"{where} is not a singular point: " + " and ".join(bad)
            + f" (tolerance {tol:.2g} = {CLASSIFY_SINGULAR_RTOL:g} x the polynomial's scale {S:.3g})")


def _make(name, real_form, milnor, branches, axis, common, note="") -> SingularityType:
    if axis is not None:
        axis = _oriented(axis) if isinstance(axis, np.ndarray) else axis
    return SingularityType(name=name, real_form=real_form, milnor=milnor, branches=branches,
                           axis=axis, note=note, **common)


def _oriented(v: np.ndarray, canonical: bool = True) -> tuple[float, float, float]:
    """Unit vector; with ``canonical`` its largest component made positive.

    Two-branch A_k have branches along +v and -v, so the sign is free; fix
    it so that the result does not depend on LAPACK's eigenvector signs.
    """
    v = np.asarray(v, dtype=float)
    v = v / np.linalg.norm(v)
    if canonical and v[np.argmax(np.abs(v))] < 0:
        v = -v
    return tuple(float(c) for c in v)


def _a1(lam, vec, common) -> SingularityType:
    signs = np.sign(lam)
    if abs(signs.sum()) == 3:    # definite: only the point itself is real
        return _make("A1", "A1++", 1, 0, None, common)
    # Indefinite: a cone around the eigenvector whose eigenvalue has the
    # minority sign (x^2 - y^2 - z^2 = 0 is a cone around x).
    minority = -np.sign(signs.sum())
    axis = vec[:, int(np.flatnonzero(signs == minority)[0])]
    return _make("A1", "A1--", 1, 2, axis, common)


def _corank1(g, mu, vec, tol, common) -> SingularityType | None:
    j = series_order(g, tol, start=3)
    if j is None:
        return None
    k = j - 1
    sc = math.copysign(1.0, g[j])
    s1, s2 = (math.copysign(1.0, m) for m in mu)
    kernel = vec[:, 0]
    name = f"A{k}"
    if k % 2 == 1:
        # Normal form c t^(k+1) + mu1 u^2 + mu2 v^2: divide by c (F -> -F
        # allowed) to get x^(k+1) + a y^2 + b z^2 with a = sc s1, b = sc s2.
        a, b = sc * s1, sc * s2
        if a > 0 and b > 0:
            return _make(name, name + "++", k, 0, None, common)
        if a < 0 and b < 0:
            return _make(name, name + "--", k, 2, kernel, common)
        # x^(k+1) + y^2 - z^2: two sheets z = +-sqrt(x^(k+1) + y^2) along
        # the eigenvector whose eigenvalue has the sign opposite to c.
        w = vec[:, 1] if s1 != sc else vec[:, 2]
        return _make(name, name + "+-", k, 2, w, common)
    if s1 == s2:
        # c t^(k+1) = -(mu1 u^2 + mu2 v^2) / 2: a half-cone on the side
        # where sign(c t^(k+1)) = -s1.
        direction = -s1 * sc
        return _make(name, name + "--", k, 1, _oriented(direction * kernel, canonical=False),
                     common)
    return _make(name, name + "+-", k, 1, kernel, common)


def _corank2(g, mu, tol, N, common, frame) -> SingularityType | None:
    """Arnold's determinator on the residual g(u, v) (3-jet and beyond).

    Sets ``frame["kernel"]`` to the (u, v) coordinates the type was read in.
    """
    a, b, c, d = g[3, 0], g[2, 1], g[1, 2], g[0, 3]   # a u^3 + b u^2 v + c u v^2 + d v^3
    norm = max(abs(a), abs(b), abs(c), abs(d))
    sign_mu = math.copysign(1.0, mu[0])
    if norm <= tol:
        return _make("non-simple", None, None, None, None, common, note=NOTE_ZERO_CUBIC)
    disc = b * b * c * c - 4 * a * c ** 3 - 4 * b ** 3 * d - 27 * a * a * d * d + 18 * a * b * c * d
    # |disc| / norm^3 estimates the distance of the cubic from the cubics
    # with a multiple line, in units of a coefficient: compare with tol.
    if abs(disc) / norm ** 3 > tol:
        frame["kernel"] = np.eye(2)
        # Three distinct lines: D4.  Three real lines (disc > 0): D4--,
        # three half-cones; one real line: D4+-, one sheet.
        if disc > 0:
            return _make("D4", "D4--", 4, 3, None, common)
        return _make("D4", "D4+-", 4, 1, None, common)
    # Hessian covariant of the binary cubic: zero iff the cubic is a cube,
    # proportional to L1^2 if the cubic is L1^2 L2.
    hq = np.array([b * b - 3 * a * c, b * c - 9 * a * d, c * c - 3 * b * d])
    if np.max(np.abs(hq)) / norm > tol:
        return _dk(g, hq, (a, b, c, d), sign_mu, tol, N, common, frame)
    return _ek(g, (a, b, c, d), sign_mu, tol, common, frame)


def _dk(g, hq, cubic, sign_mu, tol, N, common, frame) -> SingularityType | None:
    a, b, c, d = cubic
    w, V = np.linalg.eigh(np.array([[hq[0], hq[1] / 2], [hq[1] / 2, hq[2]]]))
    alpha, beta = V[:, int(np.argmax(np.abs(w)))]         # L1 = alpha u + beta v
    # L2 = gamma u + delta v from cubic = L1^2 L2 (least squares; exact up
    # to noise, and the double factor itself is accurate because it comes
    # from the covariant, not from a root finder that would split it).
    A = np.array([[alpha ** 2, 0.0], [2 * alpha * beta, alpha ** 2],
                  [beta ** 2, 2 * alpha * beta], [0.0, beta ** 2]])
    (gamma, delta), *_ = np.linalg.lstsq(A, np.array([a, b, c, d]), rcond=None)
    p1 = np.array([-delta, gamma])
    p1 /= np.linalg.norm(p1)                             # L2(p1) = 0
    p2 = np.array([-beta, alpha])
    p2 /= np.linalg.norm(p2)                             # L1(p2) = 0
    kappa = (alpha * p1[0] + beta * p1[1]) ** 2 * (gamma * p2[0] + delta * p2[1])
    frame["kernel"] = np.column_stack([p1, p2])
    # (u, v) = X p1 + Y p2: the cubic becomes kappa X^2 Y.
    gt = compose(g, np.zeros(2), np.column_stack([p1, p2]), N)
    e = derivative(gt, 0)                                # g_X
    # Branch X = Y s(Y) of the node g_X = 0 (2-jet 2 kappa X Y): substitute
    # and divide by Y^2, E(s, Y) = sum e_ij s^i Y^(i+j-2), then solve
    # E(s(Y), Y) = 0 by the implicit function theorem (dE/ds = 2 kappa).
    q = np.zeros((N + 1, N + 1))                         # q[i] = coefficient of s^i
    for i in range(N + 1):
        for j in range(N + 1):
            k = i + j - 2
            if 0 <= k <= N and e[i, j] != 0.0:
                q[i, k] += e[i, j]
    e11 = q[1, 0]
    s = np.zeros(N + 1)
    for _ in range(N + 2):
        val = q[N].copy()
        for i in range(N - 1, -1, -1):
            val = q[i] + mul(val, s, N)
        s = s - val / e11
    # h(Y) = g~(Y s(Y), Y), the critical value of X -> g~(X, Y).
    ys = np.concatenate([[0.0], s[:-1]])
    acc = gt[N].copy()
    for i in range(N - 1, -1, -1):
        acc = gt[i] + mul(acc, ys, N)
    h = acc
    j = series_order(h, tol, start=3)
    if j is None:
        return None
    k = j + 1
    # Bring the cubic to X^2 Y' with Y = Y' / kappa: the Y'^(k-1) coefficient
    # is h_j / kappa^j, whose sign is the normal form's.
    a_sign = math.copysign(1.0, h[j]) * (math.copysign(1.0, kappa) ** j)
    name = f"D{k}"
    if k % 2 == 0:
        # y x^2 + a y^(k-1) + b z^2, k even: a < 0 gives two more real
        # branches x = +-y^((k-2)/2) (three half-cones); b is irrelevant.
        if a_sign < 0:
            return _make(name, name + "--", k, 3, None, common)
        return _make(name, name + "+-", k, 1, None, common)
    if a_sign * sign_mu > 0:
        return _make(name, name + "--", k, 2, None, common)
    return _make(name, name + "+-", k, 2, None, common)


def _ek(g, cubic, sign_mu, tol, common, frame) -> SingularityType:
    a, b, c, d = cubic
    # The cubic is (alpha u + beta v)^3: its triple root is the mean of the
    # roots, -b / (3a) in u / v (or -c / (3d) in v / u), which is accurate
    # to first order in the noise, unlike np.roots of a triple root.
    if abs(a) >= abs(d):
        dvec = np.array([-b / (3 * a), 1.0])
    else:
        dvec = np.array([1.0, -c / (3 * d)])
    dvec /= np.linalg.norm(dvec)                         # the line L = 0
    n = np.array([-dvec[1], dvec[0]])
    cn = a * n[0] ** 3 + b * n[0] ** 2 * n[1] + c * n[0] * n[1] ** 2 + d * n[1] ** 3
    if cn < 0:
        n = -n                                           # cubic = +|cn| X^3
    N = max(5, g.shape[0] - 1)
    frame["kernel"] = np.column_stack([n, dvec])
    gt = compose(g, np.zeros(2), frame["kernel"], N)
    c04, c13, c05 = gt[0, 4], gt[1, 3], gt[0, 5]
    # Arnold: with 3-jet x^3, the 4-jet x^3 + a y^4 is E6; if a = 0 and the
    # x y^3 coefficient is non-zero, E7; if both vanish, E8 iff y^5 != 0.
    # (These coefficients are invariant under the coordinate changes that
    # keep the 3-jet x^3, and all other terms lie above the Newton diagram.)
    if abs(c04) > tol:
        if math.copysign(1.0, c04) * sign_mu > 0:
            return _make("E6", "E6++", 6, 1, None, common)
        return _make("E6", "E6+-", 6, 1, None, common)
    if abs(c13) > tol:
        return _make("E7", "E7++", 7, 2, None, common)
    if abs(c05) > tol:
        return _make("E8", "E8++", 8, 1, None, common)
    return _make("non-simple", None, None, None, None, common, note=NOTE_CUBE)


def _format_jet(T: np.ndarray, tol: float, order: int = 3) -> str:
    """The terms of degree 2..order of a Taylor tensor as text (x, y, z)."""
    index, monos = _jet_monomials(T.shape[0], order)
    coeffs = T[index].tolist() if len(monos) else []
    terms = []
    for c, mono in zip(coeffs, monos):
        if abs(c) <= tol:
            continue
        mag = abs(c)
        coef = "" if abs(mag - 1.0) <= 1e-9 else f"{mag:.6g} "
        terms.append(("-" if c < 0 else "+", coef + mono))
    if not terms:
        return "0"
    out = ("-" if terms[0][0] == "-" else "") + terms[0][1]
    for sign, text in terms[1:]:
        out += f" {sign} {text}"
    return out


@lru_cache(maxsize=None)
def _jet_monomials(size: int, order: int) -> tuple[tuple, list[str]]:
    """The (i, j, k) index arrays and texts of the monomials of degree 2..order of :func:`_format_jet`, in its order."""
    rows, monos = [], []
    for total in range(2, order + 1):
        for i in range(total, -1, -1):
            for j in range(total - i, -1, -1):
                k = total - i - j
                if max(i, j, k) >= size:
                    continue
                rows.append((i, j, k))
                monos.append(" ".join(v if e == 1 else f"{v}^{e}" for v, e in (("x", i), ("y", j), ("z", k)) if e))
    index = tuple(np.array(c, dtype=np.int64) for c in zip(*rows)) if rows else ()
    return index, monos


# ----------------------------------------------------------------- command
class _ArgumentError(Exception):
    pass


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # report, do not exit
        raise _ArgumentError(message)


def _coordinate(text: str) -> float:
    text = text.strip()
    try:
        return float(text)
    except ValueError:
        pass
    try:
        return float(Fraction(text.strip()))
    except (ValueError, ZeroDivisionError):
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None


def classify_command(args: list[str]) -> int:
    """``singmesh classify "EQUATION" --at X Y Z [--at ...] [name=value ...]``.

    Prints one :meth:`SingularityType.describe` line per point.

    Parameters
    ----------
    args : list of str
        The command-line arguments after ``classify``.

    Returns
    -------
    int
        0 on success; 2 (after one error line on stderr) for a bad
        equation, bad arguments or a point that is not singular.
    """
    parser = _Parser(
        prog="singmesh classify",
        description="Classify singular points of the surface EQUATION = 0 "
                    "(ADE type, real form, Milnor number, real branches).")
    parser.add_argument("equation", help='the surface, e.g. "x^2 + y^2 - z^3"')
    parser.add_argument("--at", nargs=3, type=_coordinate, action="append", required=True,
                        metavar=("X", "Y", "Z"),
                        help="a singular point (repeat for several); numbers or fractions")
    parser.add_argument("params", nargs="*", metavar="name=value",
                        help="parameter values used in EQUATION")
    prog = parser.prog
    args = list(args)
    # argparse takes "-1/2" for an option (only plain negative decimals are
    # recognised as numbers); a leading space keeps the three values after
    # --at positional, and _coordinate strips it again.
    after_at = set()
    for i, arg in enumerate(args):
        if arg == "--at":
            for j in range(i + 1, min(i + 4, len(args))):
                after_at.add(j)
                if re.match(r"^-[\d.]", args[j]):
                    args[j] = " " + args[j]
    # So is an equation starting with a minus ("-x^2 + y^2 - z^2", as
    # ``singmesh mesh`` takes it): only -h and --options are options here.
    for i, arg in enumerate(args):
        if i not in after_at and re.match(r"^-[^-\s]", arg) and arg != "-h":
            args[i] = " " + arg
    try:
        ns = parser.parse_intermixed_args(args)
    except _ArgumentError as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 2
    except SystemExit as exc:   # --help
        return int(exc.code or 0)
    params = {}
    for item in ns.params:
        item = item.strip()  # (the space put before a leading minus above)
        name, sep, value = item.partition("=")
        if not sep or not name.strip() or not value.strip():
            print(f"{prog}: error: a parameter is given as name=value, not {item!r}",
                  file=sys.stderr)
            return 2
        params[name.strip()] = value.strip()
    try:
        surface = Surface.parse(ns.equation.strip(), **params)
        for point in ns.at:
            print(classify(surface, point).describe())
    except SurfaceError as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 2
    return 0
