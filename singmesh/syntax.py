"""SingSurf's equation language, read into sympy expressions.

An equation text is a sequence of statements separated by ``;``::

    W (a X^2 + b Y^2 + c Z^2) + 2 k X Y Z;   // the surface (lhs = rhs allowed)
    X = x + y + z + w;                      // a definition: NAME = EXPR
    Y = -x - y + z + w; ...
    w = 1;

* Statements may run over any number of lines; a line break is a space.
* ``//`` starts a comment that runs to the end of its line.
* The first statement is the surface; every later one defines a name, which
  may use x, y, z, parameters and other names, in any order.
* ``^`` and ``**`` are powers (right-associative, above unary minus:
  ``-x^2`` is ``-(x^2)``); juxtaposition is multiplication, with the
  precedence of ``*`` (``2 x y``, ``x(y+1)``, ``1/3 a x`` = ``(1/3) a x``);
  a name made of known names is their product (``16xyz``, ``tx``).
* Typographic signs are read as what they mean: ``− – —`` as ``-``,
  ``× · ⋅`` as ``*``, ``÷`` as ``/``, superscripts ``x²``, ``x⁻¹`` as powers.
* Decimal numbers are exact (``0.1`` is 1/10): the polynomial is expanded
  exactly and rounded to double precision once.
* Functions: ``sqrt exp log ln sin cos tan asin acos atan sinh cosh tanh
  abs min max`` and their sympy spellings; constants ``pi`` and ``e`` (as
  in SingSurf; a definition of ``e`` takes precedence).
* ``|u|`` is ``abs(u)``, as in SingSurf and the common notation.  A ``|``
  where an operand is expected opens a group; inside one, a ``|`` after
  an operand closes the innermost group, so ``|x - |y||`` is
  ``abs(x - abs(y))`` and ``|x||y|`` is ``abs(x) abs(y)``; outside any
  group a ``|`` after an operand opens one (``2|x|``).

Errors raise :class:`singmesh.SurfaceError` with the line and column of
the offending character in the text as given (``line`` and ``column``
attributes as well as in the message).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np
import sympy

from .errors import SurfaceError
from .tolerances import MAX_DEGREE, MAX_NESTING, MAX_NUMBER_EXPONENT, MAX_POWER, SOURCE_QUOTE

X, Y, Z = sympy.symbols("x y z", real=True)
VARIABLES = (X, Y, Z)

# ---------------------------------------------------------------- characters
#: Typographic signs pasted from papers, and what they stand for.
_SIGNS = {
    "\u2212": "-", "\u2013": "-", "\u2014": "-", "\u2010": "-", "\u2011": "-", "\u2012": "-",
    "\ufe63": "-", "\uff0d": "-",
    "\u00d7": "*", "\u00b7": "*", "\u22c5": "*", "\u2217": "*", "\u2219": "*",
    "\u00f7": "/", "\u2215": "/", "\uff0b": "+",
}
_SUPERSCRIPT_DIGITS = {c: str(i) for i, c in enumerate("\u2070\u00b9\u00b2\u00b3\u2074\u2075\u2076\u2077\u2078\u2079")}
_SUPERSCRIPT_SIGNS = {"\u207b": "-", "\u207a": "+"}
_SUPERSCRIPT_CHARS = set(_SUPERSCRIPT_DIGITS) | set(_SUPERSCRIPT_SIGNS)
_SUPERSCRIPT = re.compile("([%s]?)([%s]+)" % ("".join(_SUPERSCRIPT_SIGNS), "".join(_SUPERSCRIPT_DIGITS)))

_NUMBER = re.compile(r"(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?")
_NAME = re.compile(r"[A-Za-z_][A-Za-z_0-9]*")
_OPERATORS = ("**", "^", "+", "-", "*", "/", "(", ")", ",", ";", "=", "|")

#: Functions a text may call, by the names it may use.
FUNCTIONS = {
    "sqrt": sympy.sqrt, "cbrt": sympy.cbrt, "root": sympy.root, "exp": sympy.exp,
    "log": sympy.log, "ln": sympy.log, "sin": sympy.sin, "cos": sympy.cos, "tan": sympy.tan,
    "asin": sympy.asin, "acos": sympy.acos, "atan": sympy.atan, "atan2": sympy.atan2,
    "sinh": sympy.sinh, "cosh": sympy.cosh, "tanh": sympy.tanh, "asinh": sympy.asinh,
    "acosh": sympy.acosh, "atanh": sympy.atanh,
    "abs": sympy.Abs, "Abs": sympy.Abs, "min": sympy.Min, "Min": sympy.Min,
    "max": sympy.Max, "Max": sympy.Max, "Rational": sympy.Rational, "Integer": sympy.Integer,
    "binomial": sympy.binomial, "factorial": sympy.factorial, "pow": sympy.Pow,
}
#: Decimals with at most this many significant digits are exact (``0.9``);
#: longer ones are rounded reals (see :func:`literal_rounding`).
EXACT_DIGITS = 6

#: Named constants; a definition or parameter of the same name wins.
CONSTANTS = {"pi": sympy.pi, "e": sympy.E, "E": sympy.E,
             "nan": sympy.nan, "inf": sympy.oo, "oo": sympy.oo}


@dataclass(frozen=True)
class Token:
    kind: str  # "number", "name", "op", "end"
    text: str
    pos: int  # offset of the first character in the text as given


def _location(text: str, pos: int) -> tuple[int, int]:
    """1-based (line, column) of offset ``pos`` in ``text``."""
    line = text.count("\n", 0, pos) + 1
    column = pos - (text.rfind("\n", 0, pos) + 1) + 1
    return line, column


def syntax_error(text: str, pos: int, message: str) -> SurfaceError:
    """A SurfaceError for ``message`` at offset ``pos`` of ``text``, located by line and column."""
    line, column = _location(text, pos)
    where = f"line {line}, column {column}" if "\n" in text.strip() else f"column {column}"
    start = text.rfind("\n", 0, pos) + 1
    end = text.find("\n", pos)
    source = text[start:end if end >= 0 else len(text)].rstrip()
    # One readable line however long the input: the line quoted around
    # the place, at most SOURCE_QUOTE characters of it.
    shown = source
    if len(source) > SOURCE_QUOTE:
        lo = max(0, min(column - 1 - SOURCE_QUOTE // 2, len(source) - SOURCE_QUOTE))
        shown = ("..." if lo else "") + source[lo:lo + SOURCE_QUOTE] + ("..." if lo + SOURCE_QUOTE < len(source) else "")
    err = SurfaceError(f"{message} at {where} in {shown!r}" if source.strip() else f"{message} at {where}")
    err.reason, err.line, err.column, err.source = message, line, column, source
    return err


def tokenize(text: str) -> list[Token]:
    """Tokens of ``text`` (comments dropped), ending with an ``end`` token."""
    out: list[Token] = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if c.isspace():
            i += 1
        elif text.startswith("//", i):
            j = text.find("\n", i)
            i = n if j < 0 else j
        elif c in "0123456789" or (c == "." and i + 1 < n and text[i + 1] in "0123456789"):
            m = _NUMBER.match(text, i)
            out.append(Token("number", m.group(0), i))
            i = m.end()
        elif c.isascii() and (c.isalpha() or c == "_"):
            m = _NAME.match(text, i)
            out.append(Token("name", m.group(0), i))
            i = m.end()
        elif c in _SUPERSCRIPT_CHARS:
            # x² is x^2, x⁻¹ is x^-1: one power operator for the whole run.
            m = _SUPERSCRIPT.match(text, i)
            if m is None or m.end() < len(text) and text[m.end()] in _SUPERSCRIPT_CHARS:
                raise syntax_error(text, i, "syntax error: a superscript must be an integer power such as ² or ⁻¹")
            out.append(Token("op", "^", i))
            if m.group(1):
                out.append(Token("op", _SUPERSCRIPT_SIGNS[m.group(1)], i))
            out.append(Token("number", "".join(_SUPERSCRIPT_DIGITS[d] for d in m.group(2)), i))
            i = m.end()
        else:
            op = next((o for o in _OPERATORS if text.startswith(o, i)), None)
            if op is not None:
                out.append(Token("op", op, i))
                i += len(op)
            elif c in _SIGNS:
                out.append(Token("op", _SIGNS[c], i))
                i += 1
            else:
                what = f"character {c!r}" if c.isprintable() else "character"
                raise syntax_error(text, i, f"syntax error: unexpected {what} (U+{ord(c):04X})")
    out.append(Token("end", "", n))
    return out


# ---------------------------------------------------------------- statements
@dataclass
class Statement:
    """One ``;``-separated statement: the surface or a definition."""

    tokens: list[Token]
    name: str | None = None  # the defined name (None for the surface)
    name_pos: int = 0


def split_statements(text: str, tokens: list[Token]) -> tuple[Statement, list[Statement]]:
    """The surface statement and the definitions, in order of the text."""
    groups: list[list[Token]] = [[]]
    for t in tokens[:-1]:
        if t.kind == "op" and t.text == ";":
            groups.append([])
        else:
            groups[-1].append(t)
    groups = [g for g in groups if g]
    if not groups:
        raise SurfaceError("the equation is empty")
    end = tokens[-1]
    surface = Statement(groups[0] + [Token("end", "", _end_of(groups[0], end))])
    definitions = []
    for g in groups[1:]:
        stop = Token("end", "", _end_of(g, end))
        if len(g) < 2 or g[0].kind != "name" or g[1].text != "=":
            raise syntax_error(text, g[0].pos, "syntax error: a statement after ';' must read 'name = value'")
        if len(g) == 2:
            raise syntax_error(text, g[1].pos, f"syntax error: the definition of {g[0].text} has no value")
        if g[0].text in ("x", "y", "z"):
            raise syntax_error(text, g[0].pos, f"{g[0].text} is a variable and cannot be given a value")
        definitions.append(Statement(g[2:] + [stop], g[0].text, g[0].pos))
    return surface, definitions


def _end_of(group: list[Token], end: Token) -> int:
    """Offset just after the last token of a statement."""
    last = group[-1]
    return last.pos + len(last.text) if last.kind != "end" else end.pos


# ---------------------------------------------------------------- expressions
@dataclass
class Parser:
    """Precedence-climbing parser of one statement's tokens into sympy.

    ``names`` are the names the statement may use besides x, y, z (the
    definitions and parameters); each becomes a real Symbol.  ``uses``
    collects the names used, with the offset of their first use.
    """

    text: str
    tokens: list[Token]
    names: frozenset
    i: int = 0
    uses: dict = field(default_factory=dict)
    depth: int = 0
    bars: int = 0  # |...| groups open

    # -- helpers
    def peek(self) -> Token:
        return self.tokens[self.i]

    def take(self) -> Token:
        t = self.tokens[self.i]
        self.i += 1
        return t

    def error(self, token: Token, message: str) -> SurfaceError:
        return syntax_error(self.text, token.pos, message)

    def expect(self, op: str) -> Token:
        t = self.peek()
        if t.kind != "op" or t.text != op:
            raise self.error(t, f"syntax error: expected {op!r}, found {_describe(t)}")
        return self.take()

    # -- grammar
    def statement(self) -> sympy.Expr:
        """The whole token list as one expression."""
        e = self.sum()
        t = self.peek()
        if t.kind != "end":
            if t.text == "=":
                raise self.error(t, "syntax error: more than one '=' in the equation")
            raise self.error(t, f"syntax error: unexpected {_describe(t)}")
        return e

    def sum(self) -> sympy.Expr:
        terms = [self.product()]
        while self.peek().kind == "op" and self.peek().text in "+-":
            op = self.take()
            rhs = self.product()
            terms.append(rhs if op.text == "+" else -rhs)
        # One Add of all terms: adding one at a time is quadratic in sympy.
        return sympy.Add(*terms) if len(terms) > 1 else terms[0]

    def product(self) -> sympy.Expr:
        factors = [self.unary()]
        while True:
            t = self.peek()
            if t.kind == "op" and t.text in ("*", "/"):
                self.take()
                rhs = self.unary()
                if t.text == "/" and rhs == 0:
                    raise self.error(t, "division by zero")
                factors.append(rhs if t.text == "*" else 1 / rhs)
            elif (t.kind in ("number", "name") or (t.kind == "op" and t.text == "(")
                  or (t.kind == "op" and t.text == "|" and not self.bars)):
                # juxtaposition: 2 x y, x(y+1), (a)(b), 2|x| (inside |...|
                # a bar after an operand closes the group instead)
                factors.append(self.unary())
            else:
                return sympy.Mul(*factors) if len(factors) > 1 else factors[0]

    def unary(self) -> sympy.Expr:
        # Every nesting (brackets, signs, exponents) passes here: deeper
        # than MAX_NESTING is refused before Python's or sympy's recursion
        # limit is met (a RecursionError is no message for a user).
        t = self.peek()
        if self.depth >= MAX_NESTING:
            raise self.error(t, f"the expression nests brackets, signs or powers more than {MAX_NESTING} deep")
        self.depth += 1
        try:
            if t.kind == "op" and t.text in "+-":
                self.take()
                e = self.unary()
                return -e if t.text == "-" else e
            return self.power()
        finally:
            self.depth -= 1

    def power(self) -> sympy.Expr:
        base = self.primary()
        t = self.peek()
        if t.kind == "op" and t.text in ("^", "**"):
            self.take()
            exponent = self.unary()  # right-associative, x^-1 allowed
            if base == 0 and exponent.is_negative:
                raise self.error(t, "division by zero")
            problem = _power_problem(base, exponent)
            if problem:
                raise self.error(t, problem)
            return base ** exponent
        return base

    def primary(self) -> sympy.Expr:
        t = self.take()
        if t.kind == "number":
            return _number(t.text)
        if t.kind == "name":
            return self.name(t)
        if t.kind == "op" and t.text == "(":
            if self.peek().kind == "op" and self.peek().text == ")":
                raise self.error(self.peek(), "syntax error: empty parentheses")
            e = self.sum()
            self.expect(")")
            return e
        if t.kind == "op" and t.text == "|":
            return self.bar_group(t)
        if t.kind == "end":
            raise self.error(t, "syntax error: unexpected end of the expression")
        raise self.error(t, f"syntax error: unexpected {_describe(t)}")

    def bar_group(self, t: Token) -> sympy.Expr:
        """``|u|`` after its opening bar ``t``: abs(u)."""
        # (A bar right after an opening one opens a group inside it:
        # ||x| - y| is abs(abs(x) - y).)
        if self.peek().kind == "end":
            raise self.error(t, "syntax error: this '|' is not closed (nothing follows it)")
        self.bars += 1
        e = self.sum()
        self.bars -= 1
        close = self.peek()
        if close.kind != "op" or close.text != "|":
            raise self.error(t, f"syntax error: this '|' is not closed (found {_describe(close)} where "
                                "the closing '|' of |...| should be)")
        self.take()
        return sympy.Abs(e)

    def name(self, t: Token) -> sympy.Expr:
        name = t.text
        calls = self.peek().kind == "op" and self.peek().text == "("
        if name in ("x", "y", "z"):
            return VARIABLES["xyz".index(name)]
        if name in self.names:
            self.uses.setdefault(name, t.pos)
            return sympy.Symbol(name, real=True)
        if name in FUNCTIONS and calls:
            return self.call(t, FUNCTIONS[name])
        if name in FUNCTIONS:
            raise self.error(t, f"syntax error: the function {name} must be followed by '(' and its argument")
        if name in CONSTANTS:
            return CONSTANTS[name]
        parts = _segment(name, ["x", "y", "z", *self.names])
        if parts:
            # SingSurf's 16xyz: a name made of known names is their product.
            e = sympy.Integer(1)
            for p in parts:
                if p not in "xyz":
                    self.uses.setdefault(p, t.pos)
                e = e * (VARIABLES["xyz".index(p)] if p in ("x", "y", "z") else sympy.Symbol(p, real=True))
            return e
        if calls:
            raise self.error(t, f"unknown function {name}")
        err = self.error(t, f"unknown symbol {name}: only x, y, z are variables; give parameters as "
                            f"keyword arguments, name=value, or a definition such as '; {name} = 1;'")
        err.symbol = name
        raise err

    def call(self, t: Token, func) -> sympy.Expr:
        self.expect("(")
        args = [self.sum()]
        while self.peek().kind == "op" and self.peek().text == ",":
            self.take()
            args.append(self.sum())
        self.expect(")")
        try:
            return func(*args)
        except (TypeError, ValueError) as exc:
            raise self.error(t, f"cannot apply {t.text} to {len(args)} argument(s): {exc}") from None


def _describe(t: Token) -> str:
    if t.kind == "end":
        return "the end of the expression"
    return f"{t.kind} {t.text!r}" if t.kind != "op" else repr(t.text)


def _power_problem(base: sympy.Expr, exponent: sympy.Expr) -> str | None:
    """Why ``base ** exponent`` is refused, or None.

    A power of two numbers is computed exactly by sympy (``9^9^9`` has 370
    million digits), and one of a polynomial in x, y, z is expanded: both
    are refused before they are computed when they are out of reach.
    """
    if not (exponent.is_number and exponent.is_real):
        return None
    e = abs(float(exponent))
    if base.is_number:
        b = abs(complex(sympy.N(base, 15)))
        digits = float(exponent) * np.log10(b) if b not in (0.0, 1.0) and np.isfinite(b) else 0.0
        if abs(digits) > MAX_NUMBER_EXPONENT:
            return f"the number {base}^{exponent} is out of the range of double precision (about 10^{digits:.0f})"
    elif base.free_symbols & set(VARIABLES) and e > MAX_POWER:
        return f"the power {exponent} of {base} is over the degree limit of {MAX_DEGREE}"
    return None


def _number(text: str) -> sympy.Expr:
    """Exact value of a number literal: ``0.1`` is 1/10, ``1e-3`` is 1/1000."""
    return sympy.Rational(text) if any(c in text for c in ".eE") else sympy.Integer(text)


def _segment(name: str, known: list[str]) -> list[str] | None:
    """Split ``name`` into a sequence of ``known`` names (longest match first), or None."""
    best: dict[int, list[str]] = {0: []}
    ordered = sorted(set(known), key=len, reverse=True)
    for i in range(1, len(name) + 1):
        for k in ordered:
            j = i - len(k)
            if j >= 0 and j in best and name[j:i] == k:
                best[i] = best[j] + [k]
                break
    parts = best.get(len(name))
    return parts if parts and len(parts) > 1 else None


def parse_expression(text: str, tokens: list[Token], names) -> tuple[sympy.Expr, dict]:
    """Parse ``tokens`` (ending in an ``end`` token) of ``text``.

    Returns
    -------
    expr : sympy.Expr
    uses : dict
        Names of ``names`` used, with the offset of their first use.
    """
    p = Parser(text, tokens, frozenset(names))
    return p.statement(), p.uses


def parse_equation(text: str, tokens: list[Token], names) -> tuple[sympy.Expr, dict]:
    """The surface statement: ``expr`` or ``lhs = rhs`` read as ``lhs - rhs``."""
    sides: list[list[Token]] = [[]]
    for t in tokens[:-1]:
        if t.kind == "op" and t.text == "=":
            if len(sides) == 2:
                raise syntax_error(text, t.pos, "syntax error: more than one '=' in the equation")
            sides.append([])
        else:
            sides[-1].append(t)
    uses: dict = {}
    parts = []
    for k, side in enumerate(sides):
        if not side:
            where = tokens[-1].pos if k else (tokens[0].pos if tokens[:-1] else 0)
            raise syntax_error(text, where, "syntax error: one side of '=' is empty")
        end = Token("end", "", _end_of(side, tokens[-1]))
        e, u = parse_expression(text, side + [end], names)
        parts.append(e)
        for n, pos in u.items():
            uses.setdefault(n, pos)
    return (parts[0] - parts[1] if len(parts) == 2 else parts[0]), uses


# ---------------------------------------------------------------- definitions
@dataclass(frozen=True)
class Equation:
    """An equation text read: the surface in x, y, z and what it was built from.

    Attributes
    ----------
    expr : sympy.Expr
        The surface, every definition and parameter substituted.
    values : dict
        The definitions (and parameters) that are constants, by name.
    definitions : dict
        Every definition as written, by name (sympy, in terms of other names).
    rounding : float
        Relative precision of the numbers as typed (:func:`literal_rounding`):
        0 when every number is exact.
    """

    expr: sympy.Expr
    values: dict
    definitions: dict
    rounding: float = 0.0


def _name_statements(text: str, definitions: list[Statement]) -> dict[str, Statement]:
    by_name: dict[str, Statement] = {}
    for d in definitions:
        if d.name in by_name:
            first, _ = _location(text, by_name[d.name].name_pos)
            raise syntax_error(text, d.name_pos, f"{d.name} is defined twice (first on line {first})")
        by_name[d.name] = d
    return by_name


def read_equation(text: str, params: dict | None = None, optional=frozenset()) -> Equation:
    """Read an equation text with its definitions; ``params`` override them.

    Parameters
    ----------
    text : str
        The statements (see the module docstring).
    params : dict, optional
        Values by name (numbers, sympy expressions, or text in the same
        language, which may use other names).  They replace definitions
        of the same name, or give names the text uses without defining.
    optional : set of str
        Names of ``params`` the equation need not use (a definition
        file's own parameters); any other parameter it does not use is
        refused.

    Raises
    ------
    SurfaceError
        Syntax errors, unknown symbols, definitions in a cycle, parameters
        that are not finite real numbers, parameters the equation does not
        use; located by line and column.
    """
    params = dict(params or {})
    if not text.strip():
        raise SurfaceError("the equation is empty")
    tokens = tokenize(text)
    surface, statements = split_statements(text, tokens)
    by_name = _name_statements(text, statements)
    for name in params:
        if name in ("x", "y", "z"):
            raise SurfaceError(f"{name} is a variable and cannot be given a value")
    names = frozenset(by_name) | frozenset(params)

    # name -> (expression in names, names used, where it is defined)
    defined: dict[str, tuple[sympy.Expr, dict, str, int | None]] = {}
    for name, value in params.items():
        expr, uses = _parameter_value(name, value, names)
        defined[name] = (expr, uses, f"parameter {name}", None)
    for name, st in by_name.items():
        if name in params:
            continue  # the caller's value wins over the text's
        expr, uses = parse_expression(text, st.tokens, names)
        defined[name] = (expr, uses, f"{name}", st.name_pos)
    expr, uses = parse_equation(text, surface.tokens, names)
    _check_used(params, uses, defined, optional)

    order = _dependency_order(text, defined)
    resolved: dict[str, sympy.Expr] = {}
    for name in order:
        e, u, what, pos = defined[name]
        e = e.xreplace({sympy.Symbol(m, real=True): resolved[m] for m in u})
        if not e.free_symbols:
            value = complex(sympy.N(e, 30)) if not e.has(sympy.nan, sympy.zoo, sympy.oo, -sympy.oo) else complex("nan")
            if value.imag != 0 or not _finite(value.real):
                msg = f"{what} is not a finite real number (its value is {e})"
                raise syntax_error(text, pos, msg) if pos is not None else SurfaceError(msg)
        resolved[name] = e
    expr = expr.xreplace({sympy.Symbol(m, real=True): resolved[m] for m in uses})
    if expr.has(sympy.nan, sympy.zoo, sympy.oo, -sympy.oo):
        raise SurfaceError("the equation has a NaN or infinite coefficient")
    values = {n: e for n, e in resolved.items() if not e.free_symbols}
    rounding = max([literal_rounding(tokens)] + [_value_rounding(v) for v in params.values()])
    return Equation(expr=expr, values=values, definitions={n: d[0] for n, d in defined.items()},
                    rounding=rounding)


def _check_used(params: dict, uses, defined: dict, optional) -> None:
    """Refuse a parameter that neither the equation nor a definition it uses needs.

    A value given for nothing is most likely a misspelt name or the wrong
    equation: said, not silently ignored.
    """
    reached, todo = set(), list(uses)
    while todo:
        name = todo.pop()
        if name not in reached:
            reached.add(name)
            todo.extend(defined[name][1] if name in defined else ())
    unused = sorted(n for n in params if n not in reached and n not in optional)
    if unused:
        used = sorted(n for n in reached if n in defined)
        raise SurfaceError(unused_message(unused, used))


def unused_message(unused: list[str], used: list[str]) -> str:
    """The one line refusing the parameters ``unused``; ``used`` are those the equation has."""
    has = f"its parameters are {', '.join(used)}" if used else "it has none"
    return (f"parameter{'s' if len(unused) > 1 else ''} {', '.join(unused)} "
            f"{'are' if len(unused) > 1 else 'is'} not used by the equation ({has})")


def literal_rounding(tokens: list[Token]) -> float:
    """Relative precision of the decimal numbers among ``tokens``.

    A decimal written with more than ``EXACT_DIGITS`` significant digits
    is a rounded real number (``1.61803398875``, a coefficient of a rotated
    polynomial): half a unit in its last digit, relative.  Shorter ones
    (``0.9``, ``2.5e-1``) and integers are taken as exact.  Returns the
    largest, 0 when all are exact.
    """
    worst = 0.0
    for t in tokens:
        if t.kind == "number":
            worst = max(worst, _digits_rounding(t.text))
    return worst


def _digits_rounding(text: str) -> float:
    mantissa = re.split("[eE]", text)[0]
    if "." not in mantissa:
        return 0.0
    digits = mantissa.replace(".", "").lstrip("0")
    if len(digits) <= EXACT_DIGITS:
        return 0.0
    return 0.5 * 10.0 ** (1 - len(digits))


def _value_rounding(value) -> float:
    """The rounding of a caller's parameter value (text, float or sympy)."""
    if isinstance(value, str):
        try:
            return literal_rounding(tokenize(value))
        except SurfaceError:
            return 0.0
    if isinstance(value, float):
        return _digits_rounding(repr(value))
    return 0.0


def _finite(v: float) -> bool:
    return v == v and abs(v) != float("inf")


def _parameter_value(name: str, value, names) -> tuple[sympy.Expr, dict]:
    """A caller's parameter value as an expression in the known names."""
    if isinstance(value, str):
        try:
            toks = tokenize(value)
            if len(toks) == 1:
                raise SurfaceError("it is empty")
            return parse_expression(value, toks, names)
        except SurfaceError as exc:
            raise SurfaceError(f"parameter {name} = {value!r}: {exc}") from None
    if isinstance(value, bool) or value is None:
        raise SurfaceError(f"parameter {name} = {value!r} is not a number")
    try:
        expr = sympy.sympify(value, rational=False)
    except (sympy.SympifyError, TypeError, ValueError):
        raise SurfaceError(f"parameter {name} = {value!r} is not a number") from None
    if not isinstance(expr, sympy.Expr):
        raise SurfaceError(f"parameter {name} = {value!r} is not a number")
    if isinstance(value, float) and _finite(value):
        # The shortest decimal that gives this float back: what was typed.
        expr = sympy.Rational(repr(value))
    known = {s.name: s for s in expr.free_symbols}
    bad = sorted(n for n in known if n not in names and n not in ("x", "y", "z"))
    if bad:
        raise SurfaceError(f"parameter {name} = {value!r} uses unknown symbol(s) {', '.join(bad)}")
    expr = expr.xreplace({s: (VARIABLES["xyz".index(s.name)] if s.name in ("x", "y", "z")
                              else sympy.Symbol(s.name, real=True)) for s in expr.free_symbols})
    return expr, {n: 0 for n in known if n in names}


def _dependency_order(text: str, defined: dict) -> list[str]:
    """Names in an order where each comes after the names it uses.

    Raises SurfaceError naming the cycle if definitions refer to each other.
    """
    order: list[str] = []
    state: dict[str, int] = {}  # 1: in progress, 2: done

    for root in sorted(defined):
        stack = [(root, iter(sorted(defined[root][1])))]
        if state.get(root) == 2:
            continue
        state[root] = 1
        while stack:
            name, deps = stack[-1]
            nxt = next(deps, None)
            if nxt is None:
                state[name] = 2
                order.append(name)
                stack.pop()
            elif state.get(nxt) == 1:
                path = [n for n, _ in stack]
                cycle = path[path.index(nxt):] + [nxt]
                msg = "definitions refer to each other in a cycle: " + " -> ".join(cycle)
                pos = defined[nxt][3]
                raise syntax_error(text, pos, msg) if pos is not None else SurfaceError(msg)
            elif state.get(nxt) != 2:
                state[nxt] = 1
                stack.append((nxt, iter(sorted(defined[nxt][1]))))
    return order
