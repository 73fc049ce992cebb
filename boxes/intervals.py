"""Vectorised interval arithmetic over a sympy expression tree, rounded outwards.

An expression in x, y, z is compiled once into a :class:`Graph`: a
hash-consed list of nodes (one per distinct subexpression), each an
operation on earlier nodes.  The graph is evaluated on N stacked boxes at
once, one whole-array operation per node (:func:`interval_eval`), or at N
points in floating point (:func:`point_eval`, :func:`magnitude_eval`).

Bounds are guaranteed: every bound is moved outwards after each
operation (one ulp by ``np.nextafter`` after the correctly rounded ones,
``tol.INTERVAL_FUNCTION_ULPS`` relative ulps after the library's transcendental ones),
constants that are not doubles are enclosed by their two neighbours, and
each function uses its exact monotonicity ranges (sin and cos over their
periods, tan's poles, even/odd/negative/fractional powers, division by an
interval holding 0, Min/Max of any number of arguments, Abs; asin, acos,
atan, asinh, acosh, atanh are monotone).

Derivatives (:meth:`Graph.diff`) are built on the graph itself, so they
share its subexpressions.  Abs, Min and Max are not differentiable on
their kinks: there the derivative node (``sgn``, ``maxd``, ``mind``)
encloses the derivatives of every piece that may be active on the box (a
superset of Clarke's generalized gradient), so that "F_a of one sign on
the box" still means F is strictly monotone along a on it.

Domains (the rule of :mod:`singmesh.elementary`): F is undefined where a
sqrt, log or non-integer power has a negative argument, asin or acos one
outside [-1, 1], acosh one below 1, atanh one outside (-1, 1) (as in sympy
and numpy: no real value), and there is no surface there.  On a box the
argument is clipped to the function's domain (the bound is that of F on
the part of the box where it is defined, and the box is flagged); a box
wholly outside the domain gets NaN bounds, which no test accepts.
Division by an interval holding 0 gives infinite bounds (never excluded).
"""

from __future__ import annotations

import math

import numpy as np
import sympy

from singmesh import tolerances as tol
from singmesh.errors import SurfaceError

FUNCTION_ULPS = tol.INTERVAL_FUNCTION_ULPS
_EPS = float(np.finfo(float).eps)
_TINY = 1e-300
_BIG = float(np.finfo(float).max)
#: Lower bounds this far below 0 are rounding slop of exact zeros
#: (nextafter(0, -inf) after a sum of squares), not a box leaving a domain.
_SLOP = 1e-300
_PI = math.pi


# ------------------------------------------------------------------ graph
class Graph:
    """Expression DAG of x, y, z (nodes 0, 1, 2) with hash-consing.

    Attributes
    ----------
    ops : list of str           operation of each node
    args : list of tuple[int]   argument nodes (earlier nodes)
    params : list               operation parameter (constant value, exponent, ...)
    """

    def __init__(self):
        self.ops: list[str] = []
        self.args: list[tuple] = []
        self.params: list = []
        self._index: dict = {}
        self._sympy: dict = {}
        self._diff: dict = {}
        #: sqrt(f^2 + g^2) node -> (f, g) of an R-function: its crease
        #: (f = g = 0) is split into ARCS pieces by the angle of (f, g).
        self.arcs: dict = {}
        for i in range(3):
            self.node("var", (), i)
        self.zero = self.const(0.0)
        self.one = self.const(1.0)

    # ---------------------------------------------------------- building
    def node(self, op: str, args: tuple = (), param=None) -> int:
        key = (op, args, param)
        if key not in self._index:
            self._index[key] = len(self.ops)
            self.ops.append(op)
            self.args.append(args)
            self.params.append(param)
        return self._index[key]

    def const(self, value: float, lo: float | None = None, hi: float | None = None) -> int:
        """A constant: point value and an enclosure of the exact value."""
        value = float(value)
        lo = value if lo is None else float(lo)
        hi = value if hi is None else float(hi)
        return self.node("const", (), (value, lo, hi))

    def is_const(self, n: int, value: float | None = None) -> bool:
        if self.ops[n] != "const":
            return False
        v, lo, hi = self.params[n]
        return value is None or (lo == hi == value)

    def add(self, a: int, b: int) -> int:
        if self.is_const(a, 0.0):
            return b
        if self.is_const(b, 0.0):
            return a
        return self.node("add", tuple(sorted((a, b))))

    def neg(self, a: int) -> int:
        if self.is_const(a, 0.0):
            return a
        if self.ops[a] == "neg":
            return self.args[a][0]
        if self.ops[a] == "const":
            v, lo, hi = self.params[a]
            return self.const(-v, -hi, -lo)
        return self.node("neg", (a,))

    def sub(self, a: int, b: int) -> int:
        return self.add(a, self.neg(b))

    def mul(self, a: int, b: int) -> int:
        if self.is_const(a, 0.0) or self.is_const(b, 0.0):
            return self.zero
        if self.is_const(a, 1.0):
            return b
        if self.is_const(b, 1.0):
            return a
        if self.is_const(a, -1.0):
            return self.neg(b)
        if self.is_const(b, -1.0):
            return self.neg(a)
        if a == b:
            return self.powi(a, 2)
        return self.node("mul", tuple(sorted((a, b))))

    def powi(self, a: int, n: int) -> int:
        if n == 0:
            return self.one
        if n == 1:
            return a
        return self.node("powi", (a,), int(n))

    def powr(self, a: int, r: float) -> int:
        if float(r).is_integer():
            return self.powi(a, int(r))
        if r == 0.5:
            return self.node("sqrt", (a,))
        return self.node("powr", (a,), float(r))

    # ---------------------------------------------------------- from sympy
    def from_sympy(self, expr: sympy.Expr) -> int:
        """The node of a sympy expression in x, y, z (SurfaceError if unsupported)."""
        if expr in self._sympy:
            return self._sympy[expr]
        n = self._from_sympy(expr)
        self._sympy[expr] = n
        return n

    def _from_sympy(self, e: sympy.Expr) -> int:
        if not e.free_symbols:
            return self._constant(e)
        if e.is_Symbol:
            if e.name in ("x", "y", "z"):
                return "xyz".index(e.name)
            raise SurfaceError(f"unknown symbol {e.name}")
        if e.is_Add:
            r = self._rfunction(e)
            if r is not None:
                return r
            nodes = [self.from_sympy(a) for a in e.args]
            out = nodes[0]
            for n in nodes[1:]:
                out = self.add(out, n)
            return out
        if e.is_Mul:
            nodes = [self.from_sympy(a) for a in e.args]
            out = nodes[0]
            for n in nodes[1:]:
                out = self.mul(out, n)
            return out
        if e.is_Pow:
            base, ex = e.args
            if ex.free_symbols:
                raise SurfaceError(f"a power with a variable exponent is not supported: {e}")
            b = self.from_sympy(base)
            if ex.is_Integer:
                return self.powi(b, int(ex))
            value = complex(sympy.N(ex, 30))
            if value.imag != 0 or not np.isfinite(value.real):
                raise SurfaceError(f"the exponent of {e} is not a real number")
            r = float(value.real)
            if r.is_integer() and abs(r) < 2**31:
                return self.powi(b, int(r))
            return self.powr(b, r)
        unary = {sympy.exp: "exp", sympy.log: "log", sympy.sin: "sin", sympy.cos: "cos",
                 sympy.tan: "tan", sympy.sinh: "sinh", sympy.cosh: "cosh", sympy.tanh: "tanh",
                 sympy.asin: "asin", sympy.acos: "acos", sympy.atan: "atan", sympy.asinh: "asinh",
                 sympy.acosh: "acosh", sympy.atanh: "atanh", sympy.Abs: "abs"}
        if e.func in unary:
            if len(e.args) != 1:
                raise SurfaceError(f"{e.func.__name__} takes one argument: {e}")
            return self.node(unary[e.func], (self.from_sympy(e.args[0]),))
        if e.func in (sympy.Min, sympy.Max):
            nodes = tuple(sorted(set(self.from_sympy(a) for a in e.args)))
            if len(nodes) == 1:
                return nodes[0]
            return self.node("min" if e.func is sympy.Min else "max", nodes)
        name = getattr(e.func, "__name__", str(e.func))
        raise SurfaceError(
            f"unsupported function {name} in {e}: use + - * /, powers, sqrt, abs, min, max, "
            "exp, log, sin, cos, tan, asin, acos, atan, sinh, cosh, tanh, asinh, acosh, atanh")

    def _rfunction(self, e: sympy.Add) -> int | None:
        """The node of an R-function f + g +- sqrt(f^2 + g^2), or None.

        It increases with f and with g, so its bounds on a box are its
        values at the ends of theirs: no overestimation from the
        cancellation between f + g and the root (seed 000's CSG forms).
        """
        for t in e.args:
            sign = 1
            root = t
            if t.is_Mul and len(t.args) == 2 and t.args[0] == -1:
                sign, root = -1, t.args[1]
            if not (root.is_Pow and root.exp == sympy.S.Half and root.base.is_Add
                    and len(root.base.args) == 2
                    and all(a.is_Pow and a.exp == 2 for a in root.base.args)):
                continue
            f, g = (a.base for a in root.base.args)
            rest = e - t
            # sympy writes (-g)^2 as g^2: try both signs of each.
            signs = [(sf, sg) for sf in (1, -1) for sg in (1, -1) if rest - sf * f - sg * g == 0]
            if not signs:
                continue
            f, g = signs[0][0] * f, signs[0][1] * g
            nf, ng = self.from_sympy(f), self.from_sympy(g)
            sq = self.from_sympy(root)
            if nf != ng:
                self.arcs.setdefault(sq, (nf, ng))
            return self.node("rfun", (nf, ng, sq), sign)
        return None

    def _constant(self, c: sympy.Expr) -> int:
        try:
            value = complex(sympy.N(c, 30))
        except (TypeError, ValueError):
            raise SurfaceError(f"the constant {c} is not a number") from None
        if value.imag != 0 or not np.isfinite(value.real):
            raise SurfaceError(f"the constant {c} is not a finite real number")
        v = float(value.real)
        exact = False
        if isinstance(c, sympy.Rational):
            exact = sympy.Rational(v) == c
        elif isinstance(c, sympy.Float):
            exact = c._prec <= 53 and sympy.Float(v, c._prec) == c
        if exact:
            return self.const(v)
        # The double nearest a 30-digit value is within one ulp of the exact one.
        return self.const(v, np.nextafter(v, -np.inf), np.nextafter(v, np.inf))

    # ---------------------------------------------------------- derivatives
    def diff(self, n: int, v: int) -> int:
        """The node of dF/d(variable v) for node F = n (generalized at kinks)."""
        key = (n, v)
        if key in self._diff:
            return self._diff[key]
        d = self._diff_node(n, v)
        self._diff[key] = d
        return d

    def depends(self, n: int, v: int) -> bool:
        key = ("dep", n, v)
        if key not in self._diff:
            op = self.ops[n]
            if op == "var":
                r = self.params[n] == v
            elif op == "const":
                r = False
            else:
                r = any(self.depends(a, v) for a in self.args[n])
            self._diff[key] = r
        return self._diff[key]

    def _diff_node(self, n: int, v: int) -> int:
        if not self.depends(n, v):
            return self.zero
        op, args, p = self.ops[n], self.args[n], self.params[n]
        if op == "var":
            return self.one
        d = [self.diff(a, v) for a in args]
        if op == "add":
            return self.add(d[0], d[1])
        if op == "neg":
            return self.neg(d[0])
        if op == "mul":
            return self.add(self.mul(d[0], args[1]), self.mul(args[0], d[1]))
        a, da = args[0], d[0]
        if op == "powi":
            inner = self.mul(self.const(p), self.powi(a, p - 1))
        elif op == "powr":
            inner = self.mul(self.const(p), self.powr(a, p - 1))
        elif op == "sqrt":
            squares = self._squares(a)
            if squares:
                # sqrt(f1^2 + ... + fk^2) (R-functions): its derivative is
                # sum (fi / sqrt(...)) fi', each ratio in [-1, 1]: bounded
                # where the plain rule's 1/sqrt would be infinite.
                out = self.zero
                for f in squares:
                    # With two squares, the other base rides along: the
                    # ratio's bounds are then exact (see _unit).
                    other = tuple(h for h in squares if h != f) if len(squares) == 2 else ()
                    out = self.add(out, self.mul(self.node("unit", (f, n) + other[:1]), self.diff(f, v)))
                return out
            inner = self.mul(self.const(0.5), self.powi(n, -1))
        elif op == "exp":
            inner = n
        elif op == "log":
            inner = self.powi(a, -1)
        elif op == "sin":
            inner = self.node("cos", (a,))
        elif op == "cos":
            inner = self.neg(self.node("sin", (a,)))
        elif op == "tan":
            inner = self.add(self.one, self.powi(n, 2))
        elif op == "sinh":
            inner = self.node("cosh", (a,))
        elif op == "cosh":
            inner = self.node("sinh", (a,))
        elif op == "tanh":
            inner = self.sub(self.one, self.powi(n, 2))
        elif op in ("asin", "acos"):
            # +-(1 - a^2)^(-1/2): infinite at the domain's ends |a| = 1.
            inner = self.powr(self.sub(self.one, self.powi(a, 2)), -0.5)
            if op == "acos":
                inner = self.neg(inner)
        elif op == "atan":
            inner = self.powi(self.add(self.one, self.powi(a, 2)), -1)
        elif op == "asinh":
            inner = self.powr(self.add(self.one, self.powi(a, 2)), -0.5)
        elif op == "acosh":
            inner = self.powr(self.sub(self.powi(a, 2), self.one), -0.5)
        elif op == "atanh":
            inner = self.powi(self.sub(self.one, self.powi(a, 2)), -1)
        elif op == "abs":
            inner = self.node("sgn", (a,))
        elif op in ("max", "min"):
            return self.node(op + "d", tuple(args) + tuple(d))
        elif op in ("maxd", "mind"):
            # Derivative of the selected piece (the jump between pieces is
            # not seen: only used for second derivatives at points).
            m = len(args) // 2
            return self.node(op, tuple(args[:m]) + tuple(self.diff(b, v) for b in args[m:]))
        elif op == "sgn":
            return self.zero
        elif op == "rfun":
            # (1 +- f / r) f' + (1 +- g / r) g', each factor in [0, 2].
            f, g, r = args
            sign = self.const(float(p))
            out = self.zero
            for h, other in ((f, g), (g, f)):
                factor = self.add(self.one, self.mul(sign, self.node("unit", (h, r, other))))
                out = self.add(out, self.mul(factor, self.diff(h, v)))
            return out
        elif op == "unit":
            # d(f/r) = (f' - (f/r) r') / r
            f, r = args[:2]
            return self.mul(self.sub(self.diff(f, v), self.mul(n, self.diff(r, v))), self.powi(r, -1))
        else:  # pragma: no cover
            raise AssertionError(op)
        return self.mul(inner, da)

    def _squares(self, n: int) -> list[int] | None:
        """[f1, ..., fk] if node n is f1^2 + ... + fk^2 (k >= 2), else None."""
        terms, stack = [], [n]
        while stack:
            m = stack.pop()
            if self.ops[m] == "add":
                stack.extend(self.args[m])
            elif self.ops[m] == "powi" and self.params[m] == 2:
                terms.append(self.args[m][0])
            else:
                return None
        return terms if len(terms) >= 2 else None

    def substitute(self, root: int, old: int, new: int) -> int:
        """The node of ``root`` with node ``old`` replaced by node ``new``.

        Used for the pieces of a kink (a Max with one of its arguments in
        its place): the nodes that do not reach ``old`` are shared.
        """
        done: dict = {old: new}
        for n in self.plan([root]):
            if n in done:
                continue
            args = self.args[n]
            new_args = tuple(done.get(a, a) for a in args)
            if new_args == args:
                done[n] = n
                continue
            op, p = self.ops[n], self.params[n]
            if op == "add":
                done[n] = self.add(*new_args)
            elif op == "mul":
                done[n] = self.mul(*new_args)
            elif op == "neg":
                done[n] = self.neg(new_args[0])
            elif op == "powi":
                done[n] = self.powi(new_args[0], p)
            elif op in ("max", "min"):
                uniq = tuple(sorted(set(new_args)))
                done[n] = uniq[0] if len(uniq) == 1 else self.node(op, uniq)
            else:
                done[n] = self.node(op, new_args, p)
        return done[root]

    def fraction(self, root: int) -> tuple[int, int]:
        """Nodes (N, D) with F = N / D wherever F (node ``root``) and all its subexpressions are finite.

        Built bottom-up: a quotient or a negative power puts its divisor in
        D, tan(a) is sin(a) / cos(a), sums and products combine the
        fractions of their operands; every other node (exp, sqrt, Min, ...)
        is its own numerator over 1.  Where every subexpression of F is
        finite at a point, every factor of D is nonzero and finite there
        (cos(a) != 0 where tan(a) is finite, a divisor's numerator != 0
        where the quotient is), so F = 0 there implies N = 0: bounds of N
        of one sign on a box exclude F's zeros from it, also on boxes a
        pole crosses, where F's own bounds are infinite (N is bounded:
        tan(2 x) + tan(2 y) - z is sin(2 x + 2 y) - z cos(2 x) cos(2 y)
        over cos(2 x) cos(2 y)).  D is ``one`` where F has no quotient.
        """
        memo: dict = {}
        for n in self.plan([root]):
            op, args, p = self.ops[n], self.args[n], self.params[n]
            if op in ("add", "mul"):
                (an, ad), (bn, bd) = memo[args[0]], memo[args[1]]
                if ad == bd == self.one:
                    memo[n] = (n, self.one)
                elif op == "mul":
                    memo[n] = (self.mul(an, bn), self.mul(ad, bd))
                elif ad == bd:
                    memo[n] = (self.add(an, bn), ad)
                else:
                    memo[n] = (self.add(self.mul(an, bd), self.mul(bn, ad)), self.mul(ad, bd))
            elif op == "neg":
                an, ad = memo[args[0]]
                memo[n] = (n, ad) if ad == self.one else (self.neg(an), ad)
            elif op == "powi":
                an, ad = memo[args[0]]
                if p > 0:
                    memo[n] = (n, ad) if ad == self.one else (self.powi(an, p), self.powi(ad, p))
                else:
                    memo[n] = (self.one if ad == self.one else self.powi(ad, -p), self.powi(an, -p))
            elif op == "tan":
                memo[n] = (self.node("sin", args), self.node("cos", args))
            else:
                memo[n] = (n, self.one)
        return memo[root]

    def plan(self, outputs) -> list[int]:
        """Nodes needed for ``outputs``, in evaluation order."""
        need = set()
        stack = list(outputs)
        while stack:
            n = stack.pop()
            if n in need:
                continue
            need.add(n)
            stack.extend(self.args[n])
        return sorted(need)

    def last_uses(self, order: list[int]) -> dict[int, int]:
        """The last node of ``order`` that reads each node: after it the node's
        values can be dropped (evaluations keep only what is still needed)."""
        last = {}
        for n in order:
            for a in self.args[n]:
                last[a] = n
        return last



# ------------------------------------------------------------------ intervals
def _down(x):
    return np.nextafter(x, -np.inf)


def _up(x):
    return np.nextafter(x, np.inf)


def _widen(lo, hi, rel=FUNCTION_ULPS * _EPS, tiny=(_TINY, _TINY)):
    """[lo, hi] widened by ``rel`` relative (and a tiny absolute amount).

    An overflowed bound (lo = +inf, hi = -inf) becomes the largest double:
    the true value may be finite.
    """
    wl = np.where(lo == np.inf, _BIG, lo - (np.abs(lo) * rel + tiny[0]))
    wh = np.where(hi == -np.inf, -_BIG, hi + (np.abs(hi) * rel + tiny[1]))
    return wl, wh


def _mig_mag(lo, hi):
    """Smallest and largest |x| on [lo, hi]."""
    mig = np.where(lo > 0, lo, np.where(hi < 0, -hi, 0.0))
    mag = np.maximum(np.abs(lo), np.abs(hi))
    return mig, mag


def _recip(lo, hi):
    """1 / [lo, hi]: infinite where the interval holds 0, NaN for [0, 0]."""
    with np.errstate(divide="ignore", invalid="ignore"):
        rlo = _down(1.0 / hi)
        rhi = _up(1.0 / lo)
    straddle = (lo < 0) & (hi > 0)
    rlo = np.where(straddle | ((hi == 0) & (lo < 0)), -np.inf, rlo)
    rhi = np.where(straddle | ((lo == 0) & (hi > 0)), np.inf, rhi)
    undefined = (lo == 0) & (hi == 0)
    rlo = np.where(undefined, np.nan, rlo)
    rhi = np.where(undefined, np.nan, rhi)
    return rlo, rhi


def _powi(lo, hi, n):
    if n < 0:
        plo, phi = _powi(lo, hi, -n)
        return _recip(plo, phi)
    if n == 2:
        mig, mag = _mig_mag(lo, hi)
        # (0^2 is exactly 0: [0, 0] stays [0, 0], as for the other powers)
        return np.maximum(_down(mig * mig), 0.0), np.where(mag == 0, 0.0, _up(mag * mag))
    if n == 1:
        return lo, hi
    with np.errstate(over="ignore", invalid="ignore"):
        if n % 2 == 0:
            lo, hi = _mig_mag(lo, hi)
        plo, phi = np.power(lo, n), np.power(hi, n)
    # An exact zero stays zero (0^n is exact): 1 / x^3 on [0, 1] is [1, inf].
    plo, phi = _widen(plo, phi, tiny=(np.where(lo == 0, 0.0, _TINY), np.where(hi == 0, 0.0, _TINY)))
    if n % 2 == 0:
        plo = np.maximum(plo, 0.0)
    return plo, phi


def _contains(lo, hi, c, period):
    """Whether some c + k * period lies in [lo, hi] (conservatively: maybe)."""
    margin = 1e-9 + 4 * _EPS * (np.abs(lo) + np.abs(hi)) / period
    with np.errstate(invalid="ignore"):
        k = np.ceil((lo - c) / period - margin)
        return c + k * period <= hi + margin * period


def _periodic(lo, hi, fn, top, bottom, period=2 * _PI):
    """Bounds of sin or cos: maxima at top + 2 k pi, minima at bottom + 2 k pi."""
    with np.errstate(invalid="ignore"):
        a, b = fn(lo), fn(hi)
    rlo, rhi = np.minimum(a, b), np.maximum(a, b)
    whole = ~((hi - lo) < period)  # also infinite bounds
    rhi = np.where(whole | _contains(lo, hi, top, period), 1.0, rhi)
    rlo = np.where(whole | _contains(lo, hi, bottom, period), -1.0, rlo)
    rlo, rhi = _widen(rlo, rhi)
    nan = np.isnan(lo) | np.isnan(hi)
    return (np.where(nan, np.nan, np.maximum(rlo, -1.0)),
            np.where(nan, np.nan, np.minimum(rhi, 1.0)))


#: The inverse functions with a bounded domain: its ends, whether an end is
#: a pole (atanh: infinite there, so not in the domain), the numpy function.
_DOMAINS = {"asin": (-1.0, 1.0, False, np.arcsin), "acos": (-1.0, 1.0, False, np.arccos),
            "acosh": (1.0, np.inf, False, np.arccosh), "atanh": (-1.0, 1.0, True, np.arctanh)}


def _inverse(op, lo, hi):
    """Bounds of asin, acos, acosh or atanh on [lo, hi], clipped to the domain.

    Returns (lo, hi, out): ``out`` where the interval leaves the domain (the
    bounds are then those on its part inside), NaN bounds where it lies
    wholly outside (no value: no surface there, as for sqrt).  All are
    monotone: increasing but acos.
    """
    a, b, pole, fn = _DOMAINS[op]
    with np.errstate(invalid="ignore", divide="ignore"):
        out = (lo <= a) | (hi >= b) if pole else (lo < a) | (hi > b)
        cl, ch = np.clip(lo, a, b), np.clip(hi, a, b)
        if op == "acos":
            rl, rh = _widen(fn(ch), fn(cl))
            rl = np.maximum(rl, 0.0)
        else:
            rl, rh = _widen(fn(cl), fn(ch))
            if op == "acosh":
                rl = np.maximum(rl, 0.0)
    bad = (hi <= a) | (lo >= b) if pole else (hi < a) | (lo > b)
    bad |= np.isnan(lo) | np.isnan(hi)
    return np.where(bad, np.nan, rl), np.where(bad, np.nan, rh), out & ~bad


def _unit(fl, fh, gl, gh):
    """Bounds of f / sqrt(f^2 + g^2) on [fl, fh] x [gl, gh] (NaN where unknown).

    It increases with f; for f > 0 it falls as |g| grows, for f < 0 it
    rises: the extremes are at f's ends with |g| at its own.
    """
    mig, mag = _mig_mag(gl, gh)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        g1 = np.where(fl >= 0, mag, mig)
        g2 = np.where(fh >= 0, mig, mag)
        # hypot: no overflow of the squares (1e200 / inf would read 0).
        lo = fl / np.hypot(fl, g1)
        hi = fh / np.hypot(fh, g2)
    # Two roundings (hypot within one ulp): 4 ulps is room enough.
    lo = lo - (np.abs(lo) * 4 * _EPS + _TINY)
    hi = hi + (np.abs(hi) * 4 * _EPS + _TINY)
    return lo, hi


def _rfun(fl, fh, gl, gh, rl, rh, sign):
    """Bounds of f + g + sign sqrt(f^2 + g^2) (increasing in f and g).

    The values at (fl, gl) and (fh, gh), each rounded outwards; where
    those are not finite, the plain sum's bounds (r = [rl, rh] the root's).
    """
    def root(f, g, up):
        if up:
            return _up(np.sqrt(_up(_up(f * f) + _up(g * g))))
        return _down(np.sqrt(np.maximum(_down(_down(f * f) + _down(g * g)), 0.0)))

    with np.errstate(invalid="ignore", over="ignore"):
        if sign > 0:
            lo = _down(_down(fl + gl) + root(fl, gl, False))
            hi = _up(_up(fh + gh) + root(fh, gh, True))
            plain_lo, plain_hi = _down(_down(fl + gl) + rl), _up(_up(fh + gh) + rh)
        else:
            lo = _down(_down(fl + gl) - root(fl, gl, True))
            hi = _up(_up(fh + gh) - root(fh, gh, False))
            plain_lo, plain_hi = _down(_down(fl + gl) - rh), _up(_up(fh + gh) - rl)
    lo = np.where(np.isfinite(lo), np.fmax(lo, plain_lo), plain_lo)
    hi = np.where(np.isfinite(hi), np.fmin(hi, plain_hi), plain_hi)
    nan = np.isnan(fl) | np.isnan(gl) | np.isnan(fh) | np.isnan(gh)
    return np.where(nan, np.nan, lo), np.where(nan, np.nan, hi)


#: Pieces of an R-function's crease: arcs of the angle t of (f, g),
#: [j pi/4, (j+1) pi/4]; on each, the ranges of cos t and sin t (widened).
ARCS = 8
_T = np.arange(ARCS + 1) * (2 * _PI / ARCS)
_ARC_RANGES = [
    (np.minimum(fn(_T[:-1]), fn(_T[1:])) - 1e-12, np.maximum(fn(_T[:-1]), fn(_T[1:])) + 1e-12)
    for fn in (np.cos, np.sin)
]


def kink_key(graph: Graph, n: int):
    """The key of a max, min, abs or R-function node for ``interval_eval``'s ``force``."""
    op = graph.ops[n]
    if op == "abs":
        return ("abs", graph.args[n][0])
    if op == "rfun":
        return ("arc", graph.args[n][2])
    return (op, tuple(graph.args[n]))


def kink_pieces(graph: Graph, kinks, lo, hi) -> list[np.ndarray]:
    """Which pieces of each kink node may be active on each box: (N, m) bool each.

    A max's argument i is active where its upper bound reaches the largest
    lower bound (a min's: the other way); abs has the pieces (+, -).
    """
    args = sorted({a for k in kinks for a in graph.args[k][:2 if graph.ops[k] == "rfun" else None]})
    r = interval_eval(graph, args, lo, hi)
    L = dict(zip(args, r.lo))
    H = dict(zip(args, r.hi))
    out = []
    for k in kinks:
        op, a = graph.ops[k], graph.args[k]
        if op == "abs":
            out.append(np.stack([H[a[0]] >= 0, L[a[0]] <= 0], 1))
        elif op == "rfun":
            # Every arc where the box may reach the crease f = g = 0; one
            # piece (the plain bounds) elsewhere.
            crease = (L[a[0]] <= 0) & (H[a[0]] >= 0) & (L[a[1]] <= 0) & (H[a[1]] >= 0)
            act = np.repeat(crease[:, None], ARCS, axis=1)
            act[:, 0] = True
            out.append(act)
        elif op == "max":
            floor = np.maximum.reduce([L[b] for b in a])
            out.append(np.stack([H[b] >= floor for b in a], 1))
        else:
            ceil = np.minimum.reduce([H[b] for b in a])
            out.append(np.stack([L[b] <= ceil for b in a], 1))
    return out


class IntervalResult:
    """Bounds of the outputs on N boxes.

    Attributes
    ----------
    lo, hi : list of (N,) arrays, one per output
    clipped : (N,) bool   some argument left a function's domain on the box
    """

    def __init__(self, lo, hi, clipped):
        self.lo, self.hi, self.clipped = lo, hi, clipped


def interval_eval(graph: Graph, outputs, lo: np.ndarray, hi: np.ndarray, force: dict | None = None) -> IntervalResult:
    """Bounds of the output nodes on the boxes [lo, hi] (each (N, 3)).

    Every true value of an output at a point of a box where it is defined
    lies in the bounds (outward rounding throughout).

    ``force`` maps a kink (:func:`kink_key` of a max, min or abs node) to
    the piece chosen on each box, (N,) int (for abs: 0 the positive
    piece, 1 the negative one): the derivatives at that kink are then the
    chosen piece's alone, NaN where that piece is not active on the box.
    """
    lo = np.asarray(lo, float)
    hi = np.asarray(hi, float)
    n_boxes = len(lo)
    order = graph.plan(outputs)
    last = graph.last_uses(order)
    keep = set(outputs)
    L: dict = {}
    H: dict = {}
    clipped = np.zeros(n_boxes, bool)
    with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
        for n in order:
            op, args, p = graph.ops[n], graph.args[n], graph.params[n]
            if op == "var":
                L[n], H[n] = lo[:, p], hi[:, p]
                continue
            if op == "const":
                L[n], H[n] = np.full(n_boxes, p[1]), np.full(n_boxes, p[2])
                continue
            al, ah = L[args[0]], H[args[0]]
            if op == "add":
                bl, bh = L[args[1]], H[args[1]]
                rl, rh = _down(al + bl), _up(ah + bh)
                # Adding an exact [0, 0] is exact (y + z on the line
                # y = z = 0): no outward rounding for a sqrt to magnify.
                za, zb = (al == 0) & (ah == 0), (bl == 0) & (bh == 0)
                rl, rh = np.where(za, bl, np.where(zb, al, rl)), np.where(za, bh, np.where(zb, ah, rh))
            elif op == "neg":
                rl, rh = -ah, -al
            elif op == "mul":
                bl, bh = L[args[1]], H[args[1]]
                if graph.ops[args[0]] == "const" and graph.params[args[0]][1] == graph.params[args[0]][2]:
                    c = graph.params[args[0]][1]
                    rl, rh = (c * bl, c * bh) if c >= 0 else (c * bh, c * bl)
                else:
                    p1, p2, p3, p4 = al * bl, al * bh, ah * bl, ah * bh
                    rl = np.fmin(np.fmin(p1, p2), np.fmin(p3, p4))
                    rh = np.fmax(np.fmax(p1, p2), np.fmax(p3, p4))
                # A factor exactly [0, 0] (x y on the lattice plane y = 0)
                # times a finite one is exactly 0: rounded outwards it would
                # be +-5e-324, which a sqrt makes 2e-162 (sqrt(x y) - z on
                # the line y = z = 0, where F is 0 throughout, then looked
                # like no flat piece and was halved without end).
                zero = (((al == 0) & (ah == 0) & np.isfinite(bl) & np.isfinite(bh))
                        | ((bl == 0) & (bh == 0) & np.isfinite(al) & np.isfinite(ah)))
                rl, rh = np.where(zero, 0.0, _down(rl)), np.where(zero, 0.0, _up(rh))
            elif op == "powi":
                rl, rh = _powi(al, ah, p)
            elif op == "sqrt":
                clipped |= al < -_SLOP
                rl = _down(np.sqrt(np.maximum(al, 0.0)))
                rh = _up(np.sqrt(ah))
                rl = np.where(ah < 0, np.nan, np.maximum(rl, 0.0))
            elif op == "powr":
                clipped |= al < -_SLOP if p > 0 else al <= _SLOP
                x0 = np.maximum(al, 0.0)
                a, b = np.power(x0, p), np.power(ah, p)
                rl, rh = (a, b) if p > 0 else (b, a)
                # The exponent is rounded to a double: x^r moves by up to
                # |r| |ln x| eps/2 relative.
                # Each bound with the slack of its own end: 0^r (log 0 =
                # -inf) must not widen the other end's finite power to 0.
                sa = (FUNCTION_ULPS + abs(p) * np.abs(np.log(x0))) * _EPS
                sb = (FUNCTION_ULPS + abs(p) * np.abs(np.log(ah))) * _EPS
                sa = np.where(np.isfinite(sa), sa, 1.0)
                sb = np.where(np.isfinite(sb), sb, 1.0)
                sl, sh = (sa, sb) if p > 0 else (sb, sa)
                rl = np.maximum(rl - (rl * sl + _TINY), 0.0)
                rh = rh + (rh * sh + _TINY)
                bad = ah < 0 if p > 0 else ah <= 0
                rl, rh = np.where(bad, np.nan, rl), np.where(bad, np.nan, rh)
            elif op == "exp":
                rl, rh = _widen(np.exp(al), np.exp(ah))
                rl = np.maximum(rl, 0.0)
            elif op == "log":
                clipped |= al <= _SLOP
                rl, rh = _widen(np.log(np.maximum(al, 0.0)), np.log(ah))
                bad = ah <= 0
                rl, rh = np.where(bad, np.nan, rl), np.where(bad, np.nan, rh)
            elif op == "sin":
                rl, rh = _periodic(al, ah, np.sin, _PI / 2, -_PI / 2)
            elif op == "cos":
                rl, rh = _periodic(al, ah, np.cos, 0.0, _PI)
            elif op == "tan":
                pole = ~((ah - al) < _PI) | _contains(al, ah, _PI / 2, _PI)
                rl, rh = _widen(np.tan(al), np.tan(ah))
                rl = np.where(pole, -np.inf, rl)
                rh = np.where(pole, np.inf, rh)
                nan = np.isnan(al) | np.isnan(ah)
                rl, rh = np.where(nan, np.nan, rl), np.where(nan, np.nan, rh)
            elif op == "sinh":
                rl, rh = _widen(np.sinh(al), np.sinh(ah))
            elif op == "cosh":
                mig, mag = _mig_mag(al, ah)
                rl, rh = _widen(np.cosh(mig), np.cosh(mag))
                rl = np.maximum(rl, 1.0)
            elif op == "tanh":
                rl, rh = _widen(np.tanh(al), np.tanh(ah))
                rl, rh = np.maximum(rl, -1.0), np.minimum(rh, 1.0)
            elif op in ("asin", "acos", "acosh", "atanh"):
                rl, rh, out = _inverse(op, al, ah)
                clipped |= out
            elif op == "atan":
                rl, rh = _widen(np.arctan(al), np.arctan(ah))
            elif op == "asinh":
                rl, rh = _widen(np.arcsinh(al), np.arcsinh(ah))
            elif op == "abs":
                rl, rh = _mig_mag(al, ah)
                nan = np.isnan(al) | np.isnan(ah)
                rl, rh = np.where(nan, np.nan, rl), np.where(nan, np.nan, rh)
            elif op == "max":
                rl, rh = al, ah
                for a in args[1:]:
                    rl, rh = np.maximum(rl, L[a]), np.maximum(rh, H[a])
            elif op == "min":
                rl, rh = al, ah
                for a in args[1:]:
                    rl, rh = np.minimum(rl, L[a]), np.minimum(rh, H[a])
            elif op == "sgn":
                rl = np.where(al > 0, 1.0, -1.0)
                rh = np.where(ah < 0, -1.0, 1.0)
                key = ("abs", args[0])
                if force and key in force:
                    neg = force[key] == 1
                    rl = np.where(neg, np.where(al <= 0, -1.0, np.nan), np.where(ah >= 0, 1.0, np.nan))
                    rh = rl
                nan = np.isnan(al) | np.isnan(ah)
                rl, rh = np.where(nan, np.nan, rl), np.where(nan, np.nan, rh)
            elif op == "rfun":
                rl, rh = _rfun(al, ah, L[args[1]], H[args[1]], L[args[2]], H[args[2]], p)
            elif op == "unit":
                # f / r with |f| <= r: in [-1, 1] whatever the quotient's bounds.
                il, ih = _recip(L[args[1]], H[args[1]])
                p1, p2, p3, p4 = al * il, al * ih, ah * il, ah * ih
                rl = np.maximum(_down(np.fmin(np.fmin(p1, p2), np.fmin(p3, p4))), -1.0)
                rh = np.minimum(_up(np.fmax(np.fmax(p1, p2), np.fmax(p3, p4))), 1.0)
                if len(args) == 3:
                    ul, uh = _unit(al, ah, L[args[2]], H[args[2]])
                    rl, rh = np.fmax(rl, ul), np.fmin(rh, uh)
                key = ("arc", args[1])
                if force and key in force and args[0] in graph.arcs.get(args[1], ()):
                    # (f, g) / r = (cos t, sin t) with t in the chosen arc.
                    role = graph.arcs[args[1]].index(args[0])
                    arc_lo, arc_hi = _ARC_RANGES[role][0][force[key]], _ARC_RANGES[role][1][force[key]]
                    rl, rh = np.maximum(rl, arc_lo), np.minimum(rh, arc_hi)
                    empty = rl > rh
                    rl, rh = np.where(empty, np.nan, rl), np.where(empty, np.nan, rh)
                nan = np.isnan(al) | np.isnan(ah) | np.isnan(L[args[1]])
                rl, rh = np.where(nan, np.nan, rl), np.where(nan, np.nan, rh)
            elif op in ("maxd", "mind"):
                m = len(args) // 2
                vl = [L[a] for a in args[:m]]
                vh = [H[a] for a in args[:m]]
                if op == "maxd":
                    floor = np.maximum.reduce(vl)
                    active = [h >= floor for h in vh]
                else:
                    ceil = np.minimum.reduce(vh)
                    active = [low <= ceil for low in vl]
                key = (op[:3], tuple(args[:m]))
                if force and key in force:
                    pick = force[key]
                    active = [act & (pick == j) for j, act in enumerate(active)]
                rl = np.full(n_boxes, np.inf)
                rh = np.full(n_boxes, -np.inf)
                for act, d in zip(active, args[m:]):
                    rl = np.where(act, np.minimum(rl, L[d]), rl)
                    rh = np.where(act, np.maximum(rh, H[d]), rh)
                none = ~np.logical_or.reduce(active)
                rl, rh = np.where(none, np.nan, rl), np.where(none, np.nan, rh)
            else:  # pragma: no cover
                raise AssertionError(op)
            L[n], H[n] = rl, rh
            for a in args:
                if last.get(a) == n and a not in keep:
                    L.pop(a, None)
                    H.pop(a, None)
    return IntervalResult([L[o] for o in outputs], [H[o] for o in outputs], clipped)


# ------------------------------------------------------------------ points
def _sgn(a):
    """Abs's slope at points: that of the positive piece at 0 (as the jets take it)."""
    return np.where(a < 0, -1.0, np.where(np.isnan(a), np.nan, 1.0))


_UNARY = {"exp": np.exp, "log": np.log, "sin": np.sin, "cos": np.cos, "tan": np.tan,
          "sinh": np.sinh, "cosh": np.cosh, "tanh": np.tanh, "abs": np.abs, "sqrt": np.sqrt,
          "asin": np.arcsin, "acos": np.arccos, "atan": np.arctan, "asinh": np.arcsinh,
          "acosh": np.arccosh, "atanh": np.arctanh, "sgn": _sgn}


#: Functions with a square-root end of their domain (Hoelder exponent 1/2 there).
_HOLDER = ("sqrt", "asin", "acos", "acosh")


def point_eval(graph: Graph, outputs, points: np.ndarray, magnitude: bool = False):
    """Values of the output nodes at points (N, 3) in floating point.

    NaN where an argument leaves a function's domain.  With ``magnitude``
    also the size of each value's terms, the scale of its rounding error:
    sums become sums of magnitudes, products products, and a function
    f(u) has |f(u)| + |f'(u)| mag(u) (its own rounding and the propagated
    error of u; at most sqrt(2 mag(u) / eps) for sqrt, asin, acos and
    acosh, finite at the ends of their domains).

    Returns
    -------
    values : list of (N,) arrays  (and mags : list of (N,) arrays)
    """
    points = np.asarray(points, float)
    n_pts = len(points)
    order = graph.plan(outputs)
    last = graph.last_uses(order)
    keep = set(outputs)
    V: dict = {}
    M: dict = {}
    with np.errstate(all="ignore"):
        for n in order:
            op, args, p = graph.ops[n], graph.args[n], graph.params[n]
            if op == "var":
                V[n] = points[:, p]
                if magnitude:
                    M[n] = np.abs(V[n])
                continue
            if op == "const":
                V[n] = np.full(n_pts, p[0])
                if magnitude:
                    M[n] = np.full(n_pts, abs(p[0]))
                continue
            a = V[args[0]]
            dm = None  # |f'(u)| for the magnitude of f(u)
            if op == "add":
                r = a + V[args[1]]
                if magnitude:
                    M[n] = M[args[0]] + M[args[1]]
            elif op == "neg":
                r = -a
                if magnitude:
                    M[n] = M[args[0]]
            elif op == "mul":
                r = a * V[args[1]]
                if magnitude:
                    M[n] = M[args[0]] * M[args[1]]
            elif op == "powi":
                r = a * a if p == 2 else np.power(a, float(p))
                if magnitude:
                    if p > 0:
                        M[n] = np.power(M[args[0]], float(p))
                    else:
                        dm = abs(p) * np.abs(np.power(a, float(p - 1)))
            elif op == "powr":
                r = np.power(a, p)
                dm = abs(p) * np.abs(np.power(a, p - 1))
            elif op in ("max", "min"):
                vals = np.stack([V[b] for b in args])
                r = vals.max(axis=0) if op == "max" else vals.min(axis=0)
                # NaN anywhere makes the result NaN (max would too).
                if magnitude:
                    M[n] = np.stack([M[b] for b in args]).max(axis=0)
            elif op == "rfun":
                r = a + V[args[1]] + p * V[args[2]]
                if magnitude:
                    M[n] = M[args[0]] + M[args[1]] + M[args[2]]
            elif op == "unit":
                den = V[args[1]]
                r = np.where(den == 0, 0.0, a / np.where(den == 0, 1.0, den))
                if magnitude:
                    M[n] = np.abs(r)
            elif op in ("maxd", "mind"):
                m = len(args) // 2
                vals = np.stack([V[b] for b in args[:m]])
                pick = np.argmax(vals, axis=0) if op == "maxd" else np.argmin(vals, axis=0)
                ds = np.stack([V[b] for b in args[m:]])
                r = np.take_along_axis(ds, pick[None], 0)[0]
                r = np.where(np.isnan(vals).any(axis=0), np.nan, r)
                if magnitude:
                    M[n] = np.take_along_axis(np.stack([M[b] for b in args[m:]]), pick[None], 0)[0]
            else:
                r = _UNARY[op](a)
                if magnitude:
                    if op == "exp":
                        dm = r
                    elif op == "log":
                        dm = 1.0 / np.abs(a)
                    elif op == "sin":
                        dm = np.abs(np.cos(a))
                    elif op == "cos":
                        dm = np.abs(np.sin(a))
                    elif op == "tan":
                        dm = 1.0 + r * r
                    elif op == "sinh":
                        dm = np.cosh(a)
                    elif op == "cosh":
                        dm = np.abs(np.sinh(a))
                    elif op == "tanh":
                        dm = 1.0 - r * r
                    elif op == "sqrt":
                        dm = 0.5 / r  # capped below (_HOLDER): cos(k sqrt(u)) on the cosine bump's axis
                    elif op in ("asin", "acos"):
                        dm = 1.0 / np.sqrt(1.0 - a * a)
                    elif op == "atan":
                        dm = 1.0 / (1.0 + a * a)
                    elif op == "asinh":
                        dm = 1.0 / np.sqrt(1.0 + a * a)
                    elif op == "acosh":
                        dm = 1.0 / np.sqrt(a * a - 1.0)
                    elif op == "atanh":
                        dm = 1.0 / np.abs(1.0 - a * a)
                    elif op == "abs":
                        M[n] = M[args[0]]
                    elif op == "sgn":
                        M[n] = np.abs(r)
            V[n] = r
            if magnitude and dm is not None:
                # An argument without error propagates none, even where f'
                # is infinite (sqrt at 0): inf * 0 would make it NaN.
                mu = M[args[0]]
                prop = dm * mu
                if op in _HOLDER:
                    # At the end of the domain f' is infinite but f moves
                    # by at most sqrt(2 d) when u moves by d (sqrt at 0,
                    # asin at 1, acosh at 1): an error eps mu in u gives
                    # at most sqrt(2 mu / eps) ulps (not inf: sqrt(1 - x)
                    # at x = 1 would be "zero" whatever its value).
                    prop = np.fmin(prop, np.sqrt(2.0 * mu / _EPS))
                M[n] = np.abs(r) + np.where(mu == 0, 0.0, prop)
            for b in args:
                if last.get(b) == n and b not in keep:
                    V.pop(b, None)
                    M.pop(b, None)
    values = [V[o] for o in outputs]
    if magnitude:
        return values, [M[o] for o in outputs]
    return values
