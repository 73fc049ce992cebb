"""Centre a degenerate singular point: where its unfolding vanishes.

A degenerate point (A_k with k >= 2, D_k, E_k) is not a regular solution of
F = grad F = 0: double precision fixes it only to about eps**(1/(k+1)),
and once the coefficients are rounded (15-digit decimals, a float
rotation) the polynomial typed has no singular point there at all, only a
small region where F and grad F are zero to the precision of the input
(2e-6 wide for a rotated A3, 5e-4 for an A5).  Its *centre* is well
defined: after the splitting lemma F ~ g(t) + sum mu_i w_i^2 / 2, and the
centre is where the terms of g that a shift of the point would create
vanish, conditions that are regular equations in the shift:

==========  =========================================================
type        conditions on g at the centre (coordinates of the frame)
==========  =========================================================
A_k         d^k g / dt^k = 0        (g ~ t^(k+1): the k-th derivative is ~ t)
D4          g_uu = g_uv = g_vv = 0  (the cubic is non-degenerate)
D_k, k > 4  g_XX = g_XY = 0         (cubic X^2 Y)
E6          g_XX = g_YYY = 0        (X^3 + Y^4)
E7          g_XX = g_XYY = 0        (X^3 + X Y^3)
E8          g_XX = g_YYYY = 0       (X^3 + Y^5)
X9 or worse all of g's 2- and 3-jet = 0 (corank 2, the cubic vanishes)
P8 or worse all of F's 2-jet = 0      (corank 3)
==========  =========================================================

The last two are non-simple: F and grad F vanish to the precision of the
input over a wide region around them (|grad F| ~ d^5 a distance d from
x^2 + y^6 + z^4: 1e-12 up to 4e-3 away), where a point reads as a simpler
type (an E6) and stays put; without a centre of their own every start in
that region was a "singular point" of its own.

At an exact singular point all of them hold, so the centre of a rounded
polynomial lies within the rounding (divided by the leading coefficient)
of the exact point, about 1e-15 instead of eps**(1/(k+1)).  Off the
centre the classifier may read a smaller type (an A5 seen from 4e-4 away
looks like an A3); the step for that type still moves towards the centre
(by a fixed fraction), so the steps are repeated until the type and the
point settle.
"""

from __future__ import annotations

from math import comb, factorial

import numpy as np
from numpy.polynomial import polynomial as P

from singmesh import tolerances as tol
from singmesh.surface import Surface

from .classify import NOTE_CORANK3, NOTE_CUBE, NOTE_ZERO_CUBIC, Frame, SingularityType, analyse
from .splitting import compose, derivative, split

#: Derivatives of g (in the frame's kernel coordinates) that vanish at the
#: centre, by type; A_k is handled apart (the k-th derivative).
_CONDITIONS = {
    "D4": [(2, 0), (1, 1), (0, 2)],
    "E6": [(2, 0), (0, 3)],
    "E7": [(2, 0), (1, 2)],
    "E8": [(2, 0), (0, 4)],
}


#: Non-simple classes with a centre: g is F itself (corank 3) or the
#: residual in the two kernel variables (corank 2).
_NON_SIMPLE = {
    NOTE_CORANK3: [a for a in np.ndindex(3, 3, 3) if sum(a) == 2],
    NOTE_ZERO_CUBIC: [a for a in np.ndindex(4, 4) if sum(a) in (2, 3)],
    # X^3 + Y^6 (J10) in the frame of the cube: g_XX fixes X; Y, which it
    # leaves free, is fixed by g's order along it (_along_flat).
    NOTE_CUBE: [(2, 0)],
}


def conditions(t: SingularityType) -> list[tuple[int, ...]] | None:
    """Multi-indices of the derivatives of g that vanish at the centre, or None."""
    if t.name == "non-simple":
        return _NON_SIMPLE.get(t.note)
    if t.milnor is None or t.name == "A1":
        return None
    if t.name.startswith("A"):
        return [(t.milnor,)]
    if t.name.startswith("D") and t.milnor >= 5:
        return [(2, 0), (1, 1)]
    return _CONDITIONS.get(t.name)


def _derivative_at(c: np.ndarray, alpha: tuple[int, ...], sigma: np.ndarray) -> float:
    d = c
    for axis, n in enumerate(alpha):
        for _ in range(n):
            d = derivative(d, axis)
    if c.ndim == 1:
        return float(P.polyval(sigma[0], d))
    if c.ndim == 3:
        return float(P.polyval3d(sigma[0], sigma[1], sigma[2], d))
    return float(P.polyval2d(sigma[0], sigma[1], d))


def _flat_direction(J: np.ndarray) -> np.ndarray | None:
    """The unit direction (2,) that centring conditions with Jacobian J leave free, or None.

    The 2- and 3-jet of g vanish at the centre of x^2 + y^6 + z^4 (a W
    germ), but a shift s along y changes them only by ~s^3: they fix the
    point to (eps / 120)**(1/3) ~ 1e-6 there, and their least-squares step
    along y is noise.  The least right-singular vector of J, where its
    smallest singular value is below ``CENTRE_FLAT`` of its largest.
    """
    _, sv, vt = np.linalg.svd(J)
    if len(sv) < J.shape[1]:
        return vt[-1]  # fewer conditions than directions (the J10 class: g_XX only)
    if sv[0] == 0 or sv[-1] > tol.CENTRE_FLAT * sv[0]:
        return None
    return vt[-1]


def _along_flat(gk: np.ndarray, sigma: np.ndarray, e: np.ndarray, N: int) -> np.ndarray:
    """The centre along the free direction e, where g has its full order along it.

    In coordinates (a, b) along (f, e), f normal to e, a shift t along e
    turns the first term a^i b^(k+1) (i = 0, 1) of g into
    (k + 1) t a^i b^k: its vanishing is a regular equation in t, as the
    centre of an A_k.  The term is b^6 for x^2 + y^6 + z^4 (a W germ) and
    X^3 + Y^6 (J10), a b^5 for X^3 + X Y^5 (E13); of two, the lower.
    """
    basis = np.column_stack([[-e[1], e[0]], e])
    h = compose(gk, sigma, basis, N)
    small = tol.CENTRE_FLAT_SLOPE * float(np.abs(h).max())
    best = None
    for i in (0, 1):
        for k in range(4 - i, N - i):
            if abs(h[i, k + 1]) > small:
                if best is None or k + i < best[0] + best[1]:
                    best = (k, i)
                break
    if best is None:
        return sigma
    k, i = best
    # d^i/da^i d^k/db^k of h at (0, t) is i! k! times the a^i b^k coefficient
    # of h(a, t + b): a polynomial in t, solved by Newton from 0.
    row = h[i, k:] * np.array([comb(k + j, k) for j in range(N + 1 - k)])
    t = 0.0
    for _ in range(tol.CENTRE_NEWTON):
        v = P.polyval(t, row)
        dv = P.polyval(t, P.polyder(row))
        dt = v / dv
        if not np.isfinite(dt):
            return sigma
        t -= dt
        if abs(dt) <= 1e-3 * np.finfo(float).eps * max(abs(t), 1e-300):
            break
    return sigma + t * e


def centring_step(surface: Surface, p: np.ndarray, t: SingularityType, frame: Frame) -> np.ndarray | None:
    """The shift from ``p`` to the centre of its singular point, to first order.

    Returns None for points that have nothing to centre (A1, non-simple
    beyond :data:`_NON_SIMPLE`).
    """
    alphas = conditions(t)
    if alphas is None or frame.corank != len(alphas[0]):
        return None
    m = frame.corank
    N = max(frame.order, max(sum(a) for a in alphas) + 2)
    T = surface.taylor(p)
    if t.name == "non-simple":
        # Its type is not known, nor the order that matters (the x^6 of
        # y^2 z + x^6 - 3 z^6): the whole jet, or the step may lead away.
        N = max(N, T.shape[0] - 1)
    G = compose(T, np.zeros(3), frame.basis, N)
    if m == 3:
        g, phis = G, []  # nothing to split off
    else:
        g, phis = split(G, m, frame.eigenvalues[m:], N, critical=False)
    K = np.eye(m) if frame.kernel is None else frame.kernel
    gk = compose(g, np.zeros(m), K, N) if m == 2 else g
    sigma = np.zeros(m)
    flat = None
    for i in range(tol.CENTRE_NEWTON):
        c = np.array([_derivative_at(gk, a, sigma) for a in alphas])
        J = np.array([[_derivative_at(gk, tuple(np.add(a, np.eye(m, dtype=int)[j])), sigma)
                       for j in range(m)] for a in alphas])
        if not (np.isfinite(c).all() and np.isfinite(J).all()):
            return None
        if i == 0 and t.name == "non-simple" and m == 2:
            flat = _flat_direction(J)
        if t.name == "non-simple":
            # Directions of very different orders (y^6 beside z^4): their
            # columns differ by more than lstsq's rcond and the slow one
            # would be cut; solved with unit columns, each goes on.
            cols = np.maximum(np.linalg.norm(J, axis=0), 1e-300)
            d = np.linalg.lstsq(J / cols, c, rcond=None)[0] / cols
        else:
            d, *_ = np.linalg.lstsq(J, c, rcond=None)
        if flat is not None:
            # Along it the conditions are ~ s^3: their step there is noise.
            d = d - flat * (flat @ d)
        sigma = sigma - d
        if np.abs(d).max() <= 1e-3 * np.finfo(float).eps * max(np.abs(sigma).max(), 1e-300):
            break
    if flat is not None:
        sigma = _along_flat(gk, sigma, flat, N)
    uv = K @ sigma
    if m == 1:
        w = [P.polyval(uv[0], phi) for phi in phis]
    else:
        w = [P.polyval2d(uv[0], uv[1], phi) for phi in phis]
    return frame.basis[:, :m] @ uv + frame.basis[:, m:] @ np.asarray(w, dtype=float).reshape(3 - m)


def residual(surface: Surface, x: np.ndarray) -> np.ndarray:
    """max(|F|, |grad F|) relative to the size of F's terms at x."""
    f, g = surface.value_gradient(x)
    f, g = np.abs(f), np.abs(g).max(axis=-1)
    scale = np.maximum(surface.magnitude(x), surface.scale)
    return np.maximum(f, g) / scale


def residual_each(surface: Surface, x: np.ndarray) -> np.ndarray:
    """:func:`residual` at each row of ``x`` (K, 3), each as a call at that point alone gives it."""
    f, g = surface.value_gradient_each(x)
    f, g = np.abs(f), np.abs(g).max(axis=-1)
    scale = np.maximum(surface.magnitude_each(x), surface.scale)
    return np.maximum(f, g) / scale


def centre(surface: Surface, p: np.ndarray, reach: float,
           limit: float, first=None) -> tuple[np.ndarray, SingularityType, Frame]:
    """The centre of the singular point near ``p``, its type and frame.

    Parameters
    ----------
    surface : Surface
    p : (3,) ndarray
        A point where F and grad F vanish to the classifier's tolerance.
    reach : float
        Largest total move allowed (the search stops short of leaving
        the neighbourhood of ``p``).
    limit : float
        Largest relative residual (:func:`residual`)
        a step may land on: the centre of a degenerate point is singular to
        the precision of the input, and a node whose small eigenvalue looked
        like a kernel is left where it is (the step would leave it).

    first : (SingularityType, Frame) or SurfaceError, optional
        ``analyse(surface, p)`` if known (:func:`analyse_each`): its result
        or what it raised.

    Raises
    ------
    NotSingularError
        If ``p`` itself is not singular to the classifier's tolerance.
    """
    p = np.asarray(p, dtype=float)
    start = p.copy()
    if first is None:
        first = analyse(surface, p)  # NotSingularError if p is not singular
    elif isinstance(first, Exception):
        raise first
    frame = first[1]
    if frame.corank == 0 and np.abs(frame.eigenvalues).min() > tol.CENTRE_RANK_RTOL * frame.scale:
        # A node even to the loose rank test below: read loosely it is an
        # A1 too, which has nothing to centre (the loop would stop at once).
        return p, first[0], frame
    moved = False
    for _ in range(tol.CENTRE_STEPS):
        # Read the type with a loose rank test: off the centre of a D5 the
        # Hessian has a small eigenvalue (~ the offset), and only corank 2
        # leads to the centre; corank 1 would settle on a nearby A2 point.
        t, frame = analyse(surface, p, rank_rtol=tol.CENTRE_RANK_RTOL, jet_rtol=tol.CENTRE_JET_RTOL)
        step = centring_step(surface, p, t, frame)
        if step is None or not np.isfinite(step).all():
            break
        q = p + step
        if np.linalg.norm(q - start) > reach or float(residual(surface, q[None])[0]) > limit:
            break
        p, moved = q, True
        if np.linalg.norm(step) <= tol.CENTRE_STOP * (1.0 + np.abs(p).max()):
            break
    # Unmoved (a node, or a point already at its centre): the type read at
    # the start is the type (analyse is a function of the point).
    t, frame = analyse(surface, p) if moved else first
    return p, t, frame
