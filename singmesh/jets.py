"""Taylor jets of an expression graph at points: truncated power series.

A jet of order n at a point p is the truncated multivariate power series
of F(p + (u, v, w)) in the three offsets, total degree <= n, stored as
the coefficients of the monomials of degree <= n (graded order, see
:class:`JetSpace`), vectorised over P points: arrays (P, M).  The series
is computed over the expression graph of :mod:`singmesh.boxes.intervals`:
sums termwise, products by convolution (truncated), and each elementary
function f composed as sum_k f^(k)(a0)/k! h^k, with a0 the series'
constant term and h the series minus it (the inverse functions' f^(k)
from their derivatives, powers of quadratics).

At a kink (Abs of 0, Min/Max with tied arguments) the series of one
piece is taken: Abs's positive one, the first of the tied arguments.
Where a function is undefined (sqrt, log, non-integer power of a
negative number, or of 0 with a derivative that is infinite there;
asin, acos, acosh, atanh outside their domains or at its ends; division
by 0) the coefficients are NaN.
"""

from __future__ import annotations

from functools import lru_cache
from math import factorial

import numpy as np

from singmesh.boxes.intervals import Graph


class JetSpace:
    """Monomials u^i v^j w^k of total degree <= n and their products.

    Attributes
    ----------
    order : int
    exponents : (M, 3) int   graded (degree, then lexicographic descending)
    index : dict (i, j, k) -> column
    """

    def __init__(self, order: int):
        self.order = order
        exps = [(i, j, d - i - j) for d in range(order + 1)
                for i in range(d, -1, -1) for j in range(d - i, -1, -1)]
        self.exponents = np.array(exps, dtype=np.int64).reshape(-1, 3)
        self.index = {e: m for m, e in enumerate(exps)}
        deg = self.exponents.sum(axis=1)
        i, j = np.nonzero(deg[:, None] + deg[None, :] <= order)
        k = np.array([self.index[tuple(e)] for e in (self.exponents[i] + self.exponents[j])], np.int64)
        srt = np.argsort(k, kind="stable")
        self._i, self._j, self._k = i[srt], j[srt], k[srt]
        self._starts = np.searchsorted(self._k, np.arange(len(exps)))
        self.size = len(exps)

    def mul(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Truncated product of stacked series (P, M)."""
        prod = a[:, self._i] * b[:, self._j]
        return np.add.reduceat(prod, self._starts, axis=1)

    def constant(self, c: np.ndarray) -> np.ndarray:
        out = np.zeros((len(c), self.size))
        out[:, 0] = c
        return out

    def compose(self, coeffs: np.ndarray, a: np.ndarray) -> np.ndarray:
        """sum_k coeffs[:, k] h^k with h = a minus its constant term (Horner)."""
        h = a.copy()
        h[:, 0] = 0.0
        r = self.constant(coeffs[:, self.order])
        for k in range(self.order - 1, -1, -1):
            r = self.mul(r, h)
            r[:, 0] += coeffs[:, k]
        return r

    def tensor(self, series: np.ndarray) -> np.ndarray:
        """One series (M,) as the (n+1, n+1, n+1) tensor T[i, j, k]."""
        n = self.order
        t = np.zeros((n + 1, n + 1, n + 1))
        e = self.exponents
        t[e[:, 0], e[:, 1], e[:, 2]] = series
        return t


@lru_cache(maxsize=None)
def jet_space(order: int) -> JetSpace:
    return JetSpace(order)


@lru_cache(maxsize=None)
def _tan_polys(order: int, sign: int) -> list[np.ndarray]:
    """P_k with d^k/dx^k tan(x) = P_k(tan x) (sign +1), tanh (sign -1)."""
    polys = [np.array([0.0, 1.0])]  # P_0(t) = t
    for _ in range(order):
        p = polys[-1]
        dp = np.polynomial.polynomial.polyder(p)
        polys.append(np.polynomial.polynomial.polymul(dp, [1.0, 0.0, float(sign)]))
    return polys


def _univariate(op: str, a0: np.ndarray, n: int, param=None) -> np.ndarray:
    """Taylor coefficients f^(k)(a0)/k!, k = 0..n, of a univariate function: (P, n+1)."""
    k = np.arange(n + 1)
    fact = np.array([float(factorial(i)) for i in range(n + 1)])
    with np.errstate(all="ignore"):
        if op == "exp":
            return np.exp(a0)[:, None] / fact
        if op == "log":
            c = np.empty((len(a0), n + 1))
            c[:, 0] = np.log(a0)
            c[:, 1:] = (-1.0) ** (k[1:] + 1) / k[1:] / a0[:, None] ** k[1:]
            return np.where(a0[:, None] > 0, c, np.nan)
        if op in ("sin", "cos", "sinh", "cosh"):
            if op in ("sin", "cos"):
                s, c = np.sin(a0), np.cos(a0)
                cycle = [s, c, -s, -c] if op == "sin" else [c, -s, -c, s]
            else:
                s, c = np.sinh(a0), np.cosh(a0)
                cycle = [s, c] * 2 if op == "sinh" else [c, s] * 2
            return np.stack([cycle[i % 4] for i in range(n + 1)], axis=1) / fact
        if op in ("tan", "tanh"):
            t = np.tan(a0) if op == "tan" else np.tanh(a0)
            polys = _tan_polys(n, 1 if op == "tan" else -1)
            return np.stack([np.polynomial.polynomial.polyval(t, p) for p in polys], axis=1) / fact
        if op in ("powr", "sqrt", "recip"):
            r = {"sqrt": 0.5, "recip": -1.0}.get(op, param)
            binom = np.ones(n + 1)
            for i in range(1, n + 1):
                binom[i] = binom[i - 1] * (r - i + 1) / i
            c = np.power(a0, r)[:, None] * binom / a0[:, None] ** k
            # Defined for a0 > 0 (a0 < 0 too for -1); sqrt and powers of 0 have no series.
            ok = (a0 > 0) if op != "recip" else (a0 != 0)
            return np.where(ok[:, None], c, np.nan)
        if op in _INVERSE:
            return _inverse_coefficients(op, a0, n)
    raise AssertionError(op)  # pragma: no cover


#: The inverse functions by their derivatives sign * q(a)^r, with q a
#: quadratic (coefficients of 1, a, a^2): asin' = (1 - a^2)^(-1/2), ...
_INVERSE = {"asin": (1.0, (1.0, 0.0, -1.0), -0.5, np.arcsin), "acos": (-1.0, (1.0, 0.0, -1.0), -0.5, np.arccos),
            "atan": (1.0, (1.0, 0.0, 1.0), -1.0, np.arctan), "asinh": (1.0, (1.0, 0.0, 1.0), -0.5, np.arcsinh),
            "acosh": (1.0, (-1.0, 0.0, 1.0), -0.5, np.arccosh), "atanh": (1.0, (1.0, 0.0, -1.0), -1.0, np.arctanh)}


def _inverse_coefficients(op: str, a0: np.ndarray, n: int) -> np.ndarray:
    """Taylor coefficients of asin, acos, atan, asinh, acosh, atanh at a0: (P, n+1).

    The derivative sign * q(a0 + t)^r is a power of a quadratic in t, whose
    series follows from J.C.P. Miller's recurrence (b = q^r:
    k q_0 b_k = sum_j ((r + 1) j - k) q_j b_(k-j)); the function's are its
    integral.  NaN where q(a0) <= 0: outside the domain or at its ends,
    where the derivative is infinite (asin at 1, like sqrt at 0).
    """
    sign, (c0, _, c2), r, fn = _INVERSE[op]
    q = np.zeros((len(a0), 3))
    q[:, 0] = c0 + c2 * a0 * a0
    q[:, 1] = 2.0 * c2 * a0
    q[:, 2] = c2
    out = np.empty((len(a0), n + 1))
    with np.errstate(all="ignore"):
        out[:, 0] = fn(a0)
        b = np.zeros((len(a0), max(n, 1)))
        b[:, 0] = np.power(q[:, 0], r)
        for k in range(1, n):
            acc = np.zeros(len(a0))
            for j in (1, 2):
                if j <= k:
                    acc += ((r + 1.0) * j - k) * q[:, j] * b[:, k - j]
            b[:, k] = acc / (k * q[:, 0])
        out[:, 1:] = sign * b[:, :n] / np.arange(1, n + 1)
    return np.where((q[:, 0] > 0)[:, None], out, np.nan)


def graph_jets(graph: Graph, output: int, points: np.ndarray, order: int) -> np.ndarray:
    """Series of node ``output`` at points (P, 3) to total degree ``order``: (P, M)."""
    sp = jet_space(order)
    points = np.asarray(points, float).reshape(-1, 3)
    P = len(points)
    S: dict = {}
    for n in graph.plan([output]):
        op, args, p = graph.ops[n], graph.args[n], graph.params[n]
        if op == "var":
            s = sp.constant(points[:, p])
            if order >= 1:
                s[:, sp.index[tuple(int(i == p) for i in range(3))]] = 1.0
        elif op == "const":
            s = sp.constant(np.full(P, p[0]))
        elif op == "add":
            s = S[args[0]] + S[args[1]]
        elif op == "neg":
            s = -S[args[0]]
        elif op == "mul":
            s = sp.mul(S[args[0]], S[args[1]])
        elif op == "powi":
            base = S[args[0]]
            e = abs(p)
            s, sq = None, base
            while e:
                if e & 1:
                    s = sq if s is None else sp.mul(s, sq)
                e >>= 1
                if e:
                    sq = sp.mul(sq, sq)
            if p < 0:
                s = sp.compose(_univariate("recip", s[:, 0], order), s)
        elif op in ("max", "min"):
            vals = np.stack([S[b][:, 0] for b in args])
            pick = np.argmax(vals, axis=0) if op == "max" else np.argmin(vals, axis=0)
            stack = np.stack([S[b] for b in args])
            s = np.take_along_axis(stack, pick[None, :, None], 0)[0]
            s = np.where(np.isnan(vals).any(axis=0)[:, None], np.nan, s)
        elif op == "rfun":
            s = S[args[0]] + S[args[1]] + p * S[args[2]]
        elif op == "abs":
            a = S[args[0]]
            s = np.where((a[:, 0] < 0)[:, None], -a, a)
        elif op in ("sgn", "maxd", "mind", "unit"):  # pragma: no cover - only in derivative graphs
            raise ValueError("jets are taken of F's graph, not of its derivatives")
        else:
            a = S[args[0]]
            s = sp.compose(_univariate(op, a[:, 0], order, p), a)
            if op in ("cos", "cosh"):
                s = _even_of_sqrt(graph, sp, S, op, args[0], s)
        S[n] = s
    return S[output]


def _even_of_sqrt(graph: Graph, sp: JetSpace, S: dict, op: str, arg: int, s: np.ndarray) -> np.ndarray:
    """cos(c sqrt(u)) and cosh(c sqrt(u)) where u = 0: the series in u.

    They are analytic in u (sum (-+c^2 u)^j / (2j)!) although sqrt(u) is
    not at u = 0: seed 000's cosine bump cos(k sqrt((y-py)^2 + (z-pz)^2))
    on its axis, where it attaches a singular point.  The argument may
    reach the sqrt through constant factors and Min/Max nodes (the bump
    cut at its rim, cos(k Min(sqrt(u), pi/k))): at the points where the
    Min/Max picks the sqrt it is the same series.
    """
    c = 1.0
    node = arg
    picked = np.ones(len(s), bool)
    while True:
        op_n = graph.ops[node]
        if op_n == "mul":
            a, b = graph.args[node]
            if not any(graph.depends(a, v) for v in range(3)):
                c, node = c * float(S[a][0, 0]), b
            elif not any(graph.depends(b, v) for v in range(3)):
                c, node = c * float(S[b][0, 0]), a
            else:
                return s
        elif op_n in ("max", "min"):
            args = graph.args[node]
            roots = [b for b in args if graph.ops[b] == "sqrt"]
            if len(roots) != 1:
                return s
            vals = np.stack([S[b][:, 0] for b in args])
            pick = np.argmax(vals, axis=0) if op_n == "max" else np.argmin(vals, axis=0)
            picked &= pick == args.index(roots[0])
            node = roots[0]
        else:
            break
    if graph.ops[node] != "sqrt":
        return s
    u = S[graph.args[node][0]]
    at = (u[:, 0] == 0) & picked
    if not at.any():
        return s
    n = sp.order
    sign = -1.0 if op == "cos" else 1.0
    coeffs = np.array([(sign * c * c) ** j / factorial(2 * j) for j in range(n + 1)])
    s = s.copy()
    s[at] = sp.compose(np.broadcast_to(coeffs, (int(at.sum()), n + 1)), u[at])
    return s
