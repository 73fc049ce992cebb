"""A surface equation as a polynomial F(x, y, z), and its evaluation.

The text is read by :mod:`singmesh.syntax` (SingSurf's equation language,
which also takes sympy's syntax): ``^`` for powers, implicit
multiplication (``2 x y``, ``x(y+1)``), ``lhs = rhs`` for ``lhs - rhs``,
statements over several lines with ``//`` comments, and later
``NAME = EXPR;`` statements defining names in terms of x, y, z, parameters
and each other.  Parameters may also come as keyword arguments.  Constant
subexpressions such as ``sqrt(5)``, ``pi`` or ``cos(2 pi/5)`` are numbers.

The result, :class:`Surface`, holds the exact sympy polynomial, the dense
tensor of its monomial coefficients ``C[i, j, k]`` (the coefficient of
``x**i y**j z**k``) and the tensors of its first and second derivatives,
and evaluates all of them at points.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping

import numpy as np
import sympy

from .errors import SurfaceError
from .syntax import VARIABLES, X, Y, Z, read_equation  # noqa: F401  (X, Y, Z re-exported)
from .tolerances import MAX_DEGREE, ZERO_ULPS


def _differentiate(coeffs: np.ndarray, axis: int) -> np.ndarray:
    """Monomial coefficients of dF/d(axis) from those of F (same shape)."""
    n = coeffs.shape[axis]
    scale = np.arange(n, dtype=float)
    shape = [1, 1, 1]
    shape[axis] = n
    d = coeffs * scale.reshape(shape)
    d = np.roll(d, -1, axis=axis)
    index = [slice(None)] * 3
    index[axis] = n - 1
    d[tuple(index)] = 0.0
    return d


def _powers(values: np.ndarray, n: int) -> np.ndarray:
    """``values[:, None] ** arange(n)`` by repeated products (exact for ints)."""
    out = np.empty(values.shape + (n,), dtype=float)
    out[..., 0] = 1.0
    for i in range(1, n):
        out[..., i] = out[..., i - 1] * values
    return out


def evaluate_tensor(coeffs: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Evaluate the polynomial with monomial tensor ``coeffs`` at ``points``.

    Parameters
    ----------
    coeffs : (nx, ny, nz) ndarray
        ``coeffs[i, j, k]`` multiplies ``x**i y**j z**k``.
    points : (..., 3) ndarray

    Returns
    -------
    values : (...) ndarray
    """
    return evaluate_tensors([coeffs], points)[0]


def evaluate_tensors(tensors, points: np.ndarray) -> list[np.ndarray]:
    """:func:`evaluate_tensor` for several tensors of one shape at the same points.

    The powers of the coordinates are formed once for all of them; each
    value is computed exactly as :func:`evaluate_tensor` computes it alone.
    """
    p = np.asarray(points, dtype=float)
    shape = p.shape[:-1]
    p = p.reshape(-1, 3)
    # Many points go in blocks: the (K, ny * nz) intermediate of a whole
    # large batch does not fit in cache and costs several times more.
    # Each row's value does not depend on the block (BLAS's gemm), but a
    # block of one row would be gemv: a last single row joins the block before.
    starts = list(range(0, len(p), _BLOCK)) or [0]
    if len(starts) > 1 and len(p) - starts[-1] == 1:
        starts.pop()
    ends = starts[1:] + [len(p)]
    blocks = [_contract(tensors, p[a:b]) for a, b in zip(starts, ends)]
    if len(blocks) == 1:
        return [v.reshape(shape) for v in blocks[0]]
    return [np.concatenate(v).reshape(shape) for v in zip(*blocks)]


#: Points per block in :func:`evaluate_tensors`.
_BLOCK = 8192


def _contract(tensors, p: np.ndarray) -> list[np.ndarray]:
    """The polynomials with monomial tensors ``tensors`` (one shape) at the rows of p (K, 3)."""
    nx, ny, nz = tensors[0].shape
    px, py, pz = _powers(p[:, 0], nx), _powers(p[:, 1], ny)[:, None, :], _powers(p[:, 2], nz)
    out = []
    for coeffs in tensors:
        # Contract one variable at a time (a matrix product, then two
        # row-wise sums): einsum with '...' does not optimise the four-way product.
        t = px @ coeffs.reshape(nx, ny * nz)  # (K, ny*nz)
        # Batched matrix products (BLAS), not einsum's slow generic loop.
        t = np.matmul(py, t.reshape(-1, ny, nz))[:, 0]  # (K, nz)
        out.append(np.einsum("kl,kl->k", t, pz))
    return out


@dataclass(frozen=True, eq=False)
class Surface:
    """A real algebraic surface F(x, y, z) = 0.

    Build it with :meth:`Surface.parse`.

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
        **params
            Parameter values (numbers, or text in the same language); they
            override the text's definitions of the same names.

        Raises
        ------
        SurfaceError
            If the input is not a usable polynomial in x, y, z.
        """
        if isinstance(source, Surface):
            if not params:
                return source
            source = source.expr
        if isinstance(source, sympy.Basic):
            text = str(source)
            expr, values = _substitute(sympy.sympify(source), params)
            rounding = max([0.0] + [2.0 ** -f._prec for f in expr.atoms(sympy.Float)])
        elif isinstance(source, str):
            text = source
            equation = read_equation(source, params)
            expr, values, rounding = equation.expr, equation.values, equation.rounding
        else:
            raise SurfaceError(
                f"a surface is given as text or a sympy expression, not {type(source).__name__}"
            )
        return cls._from_expr(expr, text, values, rounding)

    @classmethod
    def _from_expr(cls, expr, text: str, values: Mapping[str, sympy.Expr], rounding: float = 0.0) -> "Surface":
        unknown = sorted(s.name for s in expr.free_symbols if s not in VARIABLES)
        if unknown:
            raise SurfaceError(
                "unknown symbol%s %s: only x, y, z are variables; give parameters as "
                "keyword arguments or as definitions such as '; %s = 1;'"
                % ("s" if len(unknown) > 1 else "", ", ".join(unknown), unknown[0])
            )
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
        return cls(text=text, expr=expr, coeffs=coeffs, degree=degree,
                   params={k: float(v) for k, v in values.items()},
                   rounding=max(float(rounding), float(np.finfo(float).eps)))

    # ------------------------------------------------------------ derived
    @property
    def gradient_coeffs(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Monomial tensors of Fx, Fy, Fz (cached)."""
        cache = self.__dict__.setdefault("_cache", {})
        if "grad" not in cache:
            cache["grad"] = tuple(_differentiate(self.coeffs, a) for a in range(3))
        return cache["grad"]

    @property
    def hessian_coeffs(self) -> tuple[tuple[np.ndarray, ...], ...]:
        """Monomial tensors of the second derivatives, ``[a][b]`` (cached)."""
        cache = self.__dict__.setdefault("_cache", {})
        if "hess" not in cache:
            g = self.gradient_coeffs
            cache["hess"] = tuple(
                tuple(_differentiate(g[a], b) for b in range(3)) for a in range(3)
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
        t = _powers(p[:, 0], nx) @ c.transpose(1, 2, 0, 3).reshape(nx, -1)  # (K, ny*m*nz)
        t = np.matmul(_powers(p[:, 1], ny)[:, None, :], t.reshape(-1, ny, m * nz))  # (K, 1, m*nz)
        v = np.matmul(t.reshape(-1, m, nz), _powers(p[:, 2], nz)[:, :, None])[:, :, 0]  # (K, m)
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

    def magnitude(self, points) -> np.ndarray:
        """Sum of |terms| of F at ``points``: the scale of F's rounding error."""
        return evaluate_tensor(np.abs(self.coeffs), np.abs(np.asarray(points, float)))

    def is_zero(self, points) -> np.ndarray:
        """Whether F is zero at ``points`` to within its rounding error."""
        v = self(points)
        return np.abs(v) <= ZERO_ULPS * np.finfo(float).eps * self.magnitude(points)

    def __str__(self) -> str:
        """The expanded polynomial, decimals written as decimals (``0.123`` not ``123/1000``)."""
        subs = {}
        for r in self.expr.atoms(sympy.Rational):
            text = None if r.q == 1 else _decimal(r)
            if text is not None:
                subs[r] = sympy.Float(text, len(text.strip("-").replace(".", "").lstrip("0")))
        return str(self.expr.xreplace(subs))

    def __repr__(self) -> str:
        return f"Surface({str(self)!r}, degree={self.degree})"


# ---------------------------------------------------------------- checks
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
        raise SurfaceError(f"the coefficient of {term} is not finite: {c}")
    return float(value.real)


def _substitute(expr: sympy.Expr, params: Mapping) -> tuple[sympy.Expr, dict]:
    """A user's sympy expression with x, y, z and ``params`` identified by name.

    Symbols may come with other assumptions than ours (``sympy.symbols('x')``).
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
