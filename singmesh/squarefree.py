"""Square-free part of the surface's polynomial.

F = G^2 H never changes sign across G = 0: the zero set of G is then a
surface of singular points (a doubled sphere is all singular) and no sign
test sees it.  The real surface of F is that of its square-free part
G H, which is what is meshed; the repeated factors are reported.  Done
exactly with sympy for rational coefficients; rounded (float) or
algebraic coefficients are left as they are (no exact gcd exists for the
first, and it is slow for the second).
"""

from __future__ import annotations

from functools import lru_cache

import sympy

from . import tolerances as tol
from .surface import VARIABLES, PolynomialSurface, Surface


def squarefree(surface: Surface) -> tuple[Surface, list[tuple[str, int]]]:
    """The surface of F's square-free part, and F's repeated factors.

    Returns
    -------
    surface : Surface
        ``surface`` itself when F is square-free (or not checked).
    repeated : list of (factor, multiplicity)
        The factors of multiplicity > 1, as text.
    """
    if not surface.is_polynomial:
        return surface, []
    factors = _square_free_factors(surface.expr)
    repeated = [(str(f.as_expr()), k) for f, k in factors if k > 1]
    if not repeated:
        return surface, []
    part = sympy.Mul(*[f.as_expr() for f, _ in factors])
    reduced = PolynomialSurface._from_expr(sympy.expand(part), f"squarefree part of {surface.text}", {},
                                           surface.rounding)
    return PolynomialSurface(text=surface.text, expr=reduced.expr, coeffs=reduced.coeffs, degree=reduced.degree,
                             params=surface.params, rounding=surface.rounding,
                             denominator=surface.denominator, removable=surface.removable), repeated


@lru_cache(maxsize=64)
def _square_free_factors(expr: sympy.Expr) -> tuple:
    """sympy's ``sqf_list`` factors (poly, multiplicity) of ``expr``; () where not checked.

    Cached per expression (sympy's == tells 2.0 from 2): meshing one
    surface again does not factor it again (1.2 ms for the Barth sextic,
    0.3 ms for a sphere).
    """
    poly = sympy.Poly(expr, *VARIABLES)
    if poly.domain not in (sympy.ZZ, sympy.QQ) or len(poly.terms()) > tol.SQUAREFREE_MAX_TERMS:
        return ()
    return tuple(poly.sqf_list()[1])
