"""Parse a surface equation into a polynomial F(x, y, z) and evaluate it.

The text may be written in sympy syntax or in the SingSurf style: ``^`` for
powers, implicit multiplication (``2 x y``, ``x(y+1)``), ``lhs = rhs`` for
``lhs - rhs``, and named parameters either as keyword arguments or as
trailing definitions (``a x + b y - 1; a = 2; b = 3;``).  Constant
subexpressions such as ``sqrt(5)``, ``pi`` or ``cos(2 pi/5)`` are numbers.

The result, :class:`Surface`, holds the exact sympy polynomial, the dense
tensor of its monomial coefficients ``C[i, j, k]`` (the coefficient of
``x**i y**j z**k``) and the tensors of its first and second derivatives,
and evaluates all of them at points.
"""

from __future__ import annotations

import re
import tokenize
from dataclasses import dataclass, field
from typing import Mapping

import numpy as np
import sympy
from sympy.parsing.sympy_parser import (
    convert_xor,
    implicit_multiplication,
    parse_expr,
    standard_transformations,
)

from .errors import SurfaceError
from .tolerances import MAX_DEGREE, ZERO_ULPS

X, Y, Z = sympy.symbols("x y z", real=True)
VARIABLES = (X, Y, Z)



def _split_names(tokens, local_dict, global_dict):
    """Read an unknown name made of known ones as their product: ``xyz``, ``tx``.

    SingSurf writes ``16xyz``; a name that is itself known (a parameter,
    a function) is never split.
    """
    from tokenize import NAME, OP

    known = [k for k in local_dict if isinstance(local_dict[k], sympy.Symbol)]
    out = []
    for i, tok in enumerate(tokens):
        name = tok[1]
        follows_call = i + 1 < len(tokens) and tokens[i + 1][1] == "("
        if tok[0] == NAME and name not in local_dict and name not in global_dict and not follows_call:
            parts = _segment(name, known)
            if parts and len(parts) > 1:
                for j, part in enumerate(parts):
                    if j:
                        out.append((OP, "*"))
                    out.append((NAME, part))
                continue
        out.append(tok)
    return out


def _segment(name: str, known: list[str]):
    """Split ``name`` into a sequence of ``known`` names, longest first."""
    best = {0: []}
    for i in range(1, len(name) + 1):
        for k in sorted(known, key=len, reverse=True):
            j = i - len(k)
            if j >= 0 and j in best and name[j:i] == k:
                best[i] = best[j] + [k]
                break
    return best.get(len(name))


_TRANSFORMS = (_split_names,) + standard_transformations + (implicit_multiplication, convert_xor)
_NAME = re.compile(r"^[A-Za-z_][A-Za-z_0-9]*$")

# Names the text may use besides x, y, z and the parameters: numbers and
# the functions that make them.  Everything else is an unknown symbol.
_CONSTANTS = {
    name: getattr(sympy, name)
    for name in (
        "sqrt", "cbrt", "root", "exp", "log", "ln", "sin", "cos", "tan",
        "asin", "acos", "atan", "sinh", "cosh", "tanh", "pi", "E", "Rational",
        "Integer", "Float", "binomial", "factorial", "Abs",
    )
    if hasattr(sympy, name)
}
_CONSTANTS["ln"] = sympy.log
_CONSTANTS["abs"] = sympy.Abs
_CONSTANTS.update(nan=sympy.nan, inf=sympy.oo, oo=sympy.oo)
# What the parser's generated code calls; with nothing else in the global
# namespace an unknown name becomes a Symbol (reported), never one of
# sympy's functions (``beta``, ``gamma``, ``S``).
_GLOBALS = {
    "__builtins__": {},
    "Symbol": sympy.Symbol, "Integer": sympy.Integer, "Float": sympy.Float,
    "Rational": sympy.Rational, "Function": sympy.Function,
}


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
    p = np.asarray(points, dtype=float)
    nx, ny, nz = coeffs.shape
    shape = p.shape[:-1]
    p = p.reshape(-1, 3)
    # Contract one variable at a time (a matrix product, then two
    # row-wise sums): einsum with '...' does not optimise the four-way product.
    t = _powers(p[:, 0], nx) @ coeffs.reshape(nx, ny * nz)  # (K, ny*nz)
    t = np.einsum("kjl,kj->kl", t.reshape(-1, ny, nz), _powers(p[:, 1], ny))
    return np.einsum("kl,kl->k", t, _powers(p[:, 2], nz)).reshape(shape)


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
    """

    text: str
    expr: sympy.Expr
    coeffs: np.ndarray
    degree: int
    params: Mapping[str, float] = field(default_factory=dict)

    # ------------------------------------------------------------ building
    @classmethod
    def parse(cls, source, **params) -> "Surface":
        """Parse text (or take a sympy expression) into a :class:`Surface`.

        Parameters
        ----------
        source : str or sympy.Expr or Surface
            The equation.  ``"lhs = rhs"`` means ``lhs - rhs``; trailing
            ``name = value;`` parts define parameters.
        **params
            Parameter values; they override trailing definitions.

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
            expr, text, defs = sympy.sympify(source), str(source), {}
        elif isinstance(source, str):
            text = source
            expr, defs = _parse_text(source)
        else:
            raise SurfaceError(
                f"a surface is given as text or a sympy expression, not {type(source).__name__}"
            )
        values = _resolve_params(defs, params)
        return cls._from_expr(expr, text, values)

    @classmethod
    def _from_expr(cls, expr, text: str, values: Mapping[str, sympy.Expr]) -> "Surface":
        # Symbols may come with other assumptions (a user's sympy expression):
        # identify them by name.
        by_name = {s.name: s for s in expr.free_symbols}
        subs = {by_name[v.name]: v for v in VARIABLES if v.name in by_name}
        subs.update({by_name[k]: v for k, v in values.items() if k in by_name})
        expr = expr.subs(subs)
        unknown = sorted(s.name for s in expr.free_symbols if s not in VARIABLES)
        if unknown:
            raise SurfaceError(
                "unknown symbol%s %s: only x, y, z are variables; give parameters as "
                "keyword arguments or as trailing definitions such as '; %s = 1;'"
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
                   params={k: float(v) for k, v in values.items()})

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
        _, nx, ny, nz = c.shape
        t = np.einsum("ki,cijl->kcjl", _powers(p[:, 0], nx), c)
        t = np.einsum("kcjl,kj->kcl", t, _powers(p[:, 1], ny))
        v = np.einsum("kcl,kl->kc", t, _powers(p[:, 2], nz))
        f = v[:, 0].reshape(shape)
        g = v[:, 1:4].reshape(shape + (3,))
        h = v[:, [4, 5, 6, 5, 7, 8, 6, 8, 9]].reshape(shape + (3, 3))
        return f, g, h

    def __call__(self, points) -> np.ndarray:
        """F at ``points`` (..., 3)."""
        return evaluate_tensor(self.coeffs, points)

    def gradient(self, points) -> np.ndarray:
        """grad F at ``points`` (..., 3), shape (..., 3)."""
        return np.stack([evaluate_tensor(g, points) for g in self.gradient_coeffs], axis=-1)

    def hessian(self, points) -> np.ndarray:
        """Hessian of F at ``points`` (..., 3), shape (..., 3, 3)."""
        h = self.hessian_coeffs
        rows = [np.stack([evaluate_tensor(h[a][b], points) for b in range(3)], -1) for a in range(3)]
        return np.stack(rows, axis=-2)

    def magnitude(self, points) -> np.ndarray:
        """Sum of |terms| of F at ``points``: the scale of F's rounding error."""
        return evaluate_tensor(np.abs(self.coeffs), np.abs(np.asarray(points, float)))

    def is_zero(self, points) -> np.ndarray:
        """Whether F is zero at ``points`` to within its rounding error."""
        v = self(points)
        return np.abs(v) <= ZERO_ULPS * np.finfo(float).eps * self.magnitude(points)

    def __repr__(self) -> str:
        return f"Surface({str(self.expr)!r}, degree={self.degree})"


# ---------------------------------------------------------------- parsing
def _parse_one(text: str, what: str, names) -> sympy.Expr:
    local = dict(_CONSTANTS)
    local.update({v.name: v for v in VARIABLES})
    local.update({n: sympy.Symbol(n, real=True) for n in names})
    try:
        expr = parse_expr(text, local_dict=local, global_dict=dict(_GLOBALS),
                          transformations=_TRANSFORMS, evaluate=True)
    except SyntaxError as exc:
        where = f" at position {exc.offset}" if exc.offset else ""
        raise SurfaceError(f"syntax error in {what} {text.strip()!r}{where}") from None
    except tokenize.TokenError:
        raise SurfaceError(
            f"syntax error in {what} {text.strip()!r} at position {len(text.rstrip()) + 1}: "
            "unexpected end (unclosed parenthesis?)"
        ) from None
    except (TypeError, ValueError, AttributeError, NameError) as exc:
        raise SurfaceError(f"cannot read {what} {text.strip()!r}: {exc}") from None
    if not isinstance(expr, sympy.Expr):
        raise SurfaceError(f"{what} {text.strip()!r} is not an algebraic expression")
    if expr.has(sympy.nan, sympy.zoo, sympy.oo, -sympy.oo):
        raise SurfaceError(f"{what} {text.strip()!r} has a NaN or infinite coefficient")
    return expr


def _parse_text(text: str) -> tuple[sympy.Expr, dict[str, sympy.Expr]]:
    """Split ``equation; a = 1; b = 2`` and parse each part."""
    if not text.strip():
        raise SurfaceError("the equation is empty")
    parts = [p for p in text.split(";") if p.strip()]
    if not parts:
        raise SurfaceError("the equation is empty")
    equation, definitions = parts[0], parts[1:]
    defs: dict[str, str] = {}
    for d in definitions:
        if d.count("=") != 1:
            raise SurfaceError(f"a definition after ';' must read 'name = value', not {d.strip()!r}")
        name, value = (s.strip() for s in d.split("="))
        if not _NAME.match(name):
            raise SurfaceError(f"{name!r} is not a parameter name")
        if name in ("x", "y", "z"):
            raise SurfaceError(f"{name} is a variable and cannot be given a value")
        defs[name] = value
    names = list(defs)
    if equation.count("=") > 1 or "==" in equation:
        raise SurfaceError(f"the equation {equation.strip()!r} has more than one '='")
    sides = equation.split("=")
    parsed = [_parse_one(s, "the equation", names) if s.strip() else None for s in sides]
    if any(p is None for p in parsed):
        raise SurfaceError(f"one side of '=' is empty in {equation.strip()!r}")
    expr = parsed[0] - parsed[1] if len(parsed) == 2 else parsed[0]
    parsed_defs = {n: _parse_one(v, f"the value of {n}", names) for n, v in defs.items()}
    return expr, parsed_defs


def _resolve_params(defs: dict, kwargs: dict) -> dict[str, sympy.Expr]:
    """Numeric values of all parameters; definitions may use earlier ones."""
    values: dict[str, sympy.Expr] = {}
    for name, value in kwargs.items():
        try:
            values[name] = sympy.sympify(value)
        except (sympy.SympifyError, TypeError):
            raise SurfaceError(f"parameter {name} = {value!r} is not a number") from None
    pending = {n: e for n, e in defs.items() if n not in values}
    for _ in range(len(pending) + 1):
        for name, expr in list(pending.items()):
            known = {s: values[s.name] for s in expr.free_symbols if s.name in values}
            e = expr.subs(known)
            if not any(s.name in pending for s in e.free_symbols):
                values[name] = e
                del pending[name]
    if pending:
        raise SurfaceError("parameters defined in terms of each other: " + ", ".join(pending))
    for name, e in values.items():
        bad = sorted(s.name for s in e.free_symbols)
        if bad:
            raise SurfaceError(f"parameter {name} depends on unknown symbol(s) {', '.join(bad)}")
        num = complex(sympy.N(e, 30))
        if num.imag != 0 or not np.isfinite(num.real):
            raise SurfaceError(f"parameter {name} = {e} is not a finite real number")
    return values


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
