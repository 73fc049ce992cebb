"""SingSurf's equation language: lines, comments, definitions, typography, errors.

Every expected polynomial is written by hand in sympy, never taken from the
parser's output.
"""

import numpy as np
import pytest
import sympy

from singmesh import Surface, SurfaceError

x, y, z = sympy.symbols("x y z", real=True)


def same(text, expected, **params):
    got = Surface.parse(text, **params).expr
    assert sympy.expand(got - expected) == 0, (text, got)


# ------------------------------------------------------------------ lines and comments
@pytest.mark.parametrize("text, expected", [
    ("x^2+y^2\n+z^2-1", x**2 + y**2 + z**2 - 1),
    ("x^2+y^2\n-z^2\n\n-1\n", x**2 + y**2 - z**2 - 1),
    ("(x+1)\n(x-1)", (x + 1) * (x - 1)),          # juxtaposition across a line break
    ("2\nx y", 2 * x * y),
    ("(x+1)*\n(y+1)", (x + 1) * (y + 1)),
    ("x^\n2 - y", x**2 - y),
    ("  \n\t x + y \r\n - z", x + y - z),
])
def test_statements_run_over_lines(text, expected):
    same(text, expected)


@pytest.mark.parametrize("text, expected", [
    ("x^2+y^2+z^2-1 // comment", x**2 + y**2 + z**2 - 1),
    ("// a sphere\n// (of radius 1)\nx^2+y^2+z^2-1;", x**2 + y**2 + z**2 - 1),
    ("x^2 // first; = part\n + y^2 // second ( unbalanced\n - 1", x**2 + y**2 - 1),
    ("//<h3>Class II: 1 A<sub>1</sub></h3>\nx y + x z + y z + x y z;", x*y + x*z + y*z + x*y*z),
    ("a x - 1; // a comment between statements\n a = 3; // and after", 3 * x - 1),
    ("x/2 - y // comment with a division / and a 2", x / 2 - y),
])
def test_comments_run_to_the_end_of_the_line(text, expected):
    same(text, expected)


# ------------------------------------------------------------------ definitions
def test_cayley_classification_definitions_in_x_y_z():
    # Cayley's notation as SingSurf writes it: the surface in X, Y, Z, W, which
    # are defined below it in terms of x, y, z and w.
    text = """// Class II
W (a X^2 + b Y^2 + c Z^2 + f X Y+ g X Z+h Y Z)+2 k X Y Z;
X = x + y + z + w;
Y = -x - y + z + w;
Z = x -y -z + w;
W = -x + y - z + w;
w = 1;
"""
    params = dict(a="0.9", b="-0.3", c="0.8", f="-0.2", g="1.0", h="0.8", k="0.4")
    a, b, c, f, g, h, k = (sympy.Rational(params[n]) for n in "abcfghk")
    w = 1
    X, Y, Z, W = x + y + z + w, -x - y + z + w, x - y - z + w, -x + y - z + w
    expected = W * (a*X**2 + b*Y**2 + c*Z**2 + f*X*Y + g*X*Z + h*Y*Z) + 2*k*X*Y*Z
    same(text, expected, **params)


def test_definitions_in_any_order_and_in_terms_of_each_other():
    # Sarti-style: the surface uses names defined after it, which use later ones.
    text = "S6 + lambda*Q6;\nQ6 = P^3;\nS6 = P x y z;\nP = x^2 + y^2 + z^2 - r;\nr = 1/2; lambda = -3;"
    P = x**2 + y**2 + z**2 - sympy.Rational(1, 2)
    same(text, P * x * y * z - 3 * P**3)


def test_constant_definitions_are_reported_as_parameters():
    s = Surface.parse("a x + b; b = 2 a; a = 1.5")
    assert s.params == {"a": 1.5, "b": 3.0}


def test_keyword_parameters_override_the_text():
    same("a x + X; X = y + c; a = 2; c = 1", 5 * x + y + 1, a=5)
    same("a x + X; X = y + c; a = 2; c = 1", 2 * x + z + 1, X="z + c")   # a name in x, y, z too
    same("t x - 1; t = 1", (1 + sympy.sqrt(5)) / 2 * x - 1, t="(1+sqrt(5))/2")
    same("a x + 1", sympy.Rational(1, 10) * x + 1, a=0.1)   # a float is the decimal typed


def test_parameter_given_only_by_keyword():
    same("x^2 + y^2 - r^2", x**2 + y**2 - 4, r=2)


@pytest.mark.parametrize("text, words, line, column", [
    ("X + 1;\nX = Y;\nY = Z + x;\nZ = X;", r"cycle: X -> Y -> Z -> X", 2, 1),
    ("a x;\na = a + 1;", r"cycle: a -> a", 2, 1),
    ("x + q", r"unknown symbol q", 1, 5),
    ("X;\nX = x + q2;", r"unknown symbol q2", 2, 9),
    ("x;\n  a = 1;\n  a = 2;", r"a is defined twice \(first on line 2\)", 3, 3),
    ("x^2 + y^2\n + z^2 - 1;\n z = 2;", r"z is a variable", 3, 2),
    ("x;\n3 = a", r"must read 'name = value'", 2, 1),
    ("x;\na =", r"the definition of a has no value", 2, 3),
])
def test_definition_errors_name_the_name_and_its_place(text, words, line, column):
    with pytest.raises(SurfaceError, match=words) as info:
        Surface.parse(text)
    assert (info.value.line, info.value.column) == (line, column)
    assert f"column {column}" in str(info.value)


def test_undefined_parameter_stays_an_error():
    # SingSurf's files name parameters they never define (a sphere of centre
    # x0, y0, z0 with only r given): a clear error, not a silent zero.
    with pytest.raises(SurfaceError, match="unknown symbol x0"):
        Surface.parse("(x-x0)^2 + (y-y0)^2 + (z-z0)^2 - r^2;", r=1)


# ------------------------------------------------------------------ typography and numbers
@pytest.mark.parametrize("text, expected", [
    ("x\u00b2 + y\u00b2 \u2212 z\u00b3", x**2 + y**2 - z**3),        # superscripts, minus sign
    ("x \u2013 y \u2014 z", x - y - z),                                 # en and em dash
    ("2\u00d7x\u00b7y \u22c5 z", 2 * x * y * z),                       # times, middle dots
    ("x \u00f7 4 + y", x / 4 + y),
    ("(x+y)\u00b9\u2070", (x + y)**10),                                 # a two-digit superscript
    ("x\u00b2y\u00b3", x**2 * y**3),
    ("x\u00a0+\u2009y", x + y),                                         # non-breaking and thin spaces
])
def test_typographic_signs(text, expected):
    same(text, expected)


@pytest.mark.parametrize("text, expected", [
    ("16xyz", 16 * x * y * z),
    ("2 a x; a = 3", 6 * x),
    ("tx - 1; t = 2", 2 * x - 1),
    ("1/3 a x; a = 3", x),                        # juxtaposition has the precedence of *
    ("-x^2", -x**2),                              # powers bind tighter than the minus
    ("2^3^2 x", 2**9 * x),                        # and to the right
    ("x^-1 x^2", x),
    ("2pi x", 2 * sympy.pi * x),
    ("e x", sympy.E * x),
    ("e x; e = 2", 2 * x),                        # a definition wins over the constant
    ("x**2 - y**2", x**2 - y**2),                 # sympy's syntax too
    ("2.5e-1 x + .5 y + 3. z", x / 4 + y / 2 + 3 * z),
])
def test_products_powers_and_numbers(text, expected):
    same(text, expected)


def test_decimals_are_exact():
    s = Surface.parse("(0.1 + 0.2 - 0.3) x + y")
    assert s.expr == y and s.coeffs.shape[0] == 1   # x would keep 5.6e-17 in floating point
    digits = "0.12345678901234567890123"
    assert sympy.Poly(Surface.parse(f"{digits} x").expr, x).coeffs()[0] == sympy.Rational(digits)


# ------------------------------------------------------------------ errors, located
@pytest.mark.parametrize("text, words, line, column", [
    ("x^2 + y^2\n + (z^2 - 1", r"expected '\)'", 2, 12),
    ("x^2 + y^2\n + z^2 - 1)", r"unexpected '\)'", 2, 11),
    ("x +\n  * y", r"unexpected '\*'", 2, 3),
    ("x + y\n+ foo(z)", r"unknown function foo", 2, 3),
    ("x + y $ z", r"unexpected character '\$'", 1, 7),
    ("x\n + sin z", r"sin must be followed by '\('", 2, 4),
    ("x = y = z", r"more than one '='", 1, 7),
    ("\n\n   = y", r"one side of '=' is empty", 3, 4),
    ("x/(y - y)", r"division by zero", 1, 2),
    ("x + ()", r"empty parentheses", 1, 6),
    ("x\u207b", r"superscript", 1, 2),
])
def test_syntax_errors_give_line_and_column(text, words, line, column):
    with pytest.raises(SurfaceError, match=words) as info:
        Surface.parse(text)
    assert (info.value.line, info.value.column) == (line, column)
    where = f"line {line}, column {column}" if "\n" in text.strip() else f"column {column}"
    assert where in str(info.value)
    assert "\n" not in str(info.value)   # one line


@pytest.mark.parametrize("text, f", [
    ("max(x, y) - 1", lambda x, y, z: np.maximum(x, y) - 1),
    ("Min(x, y^2)", lambda x, y, z: np.minimum(x, y * y)),
    ("abs(x) - y", lambda x, y, z: np.abs(x) - y),
    ("x^2 + y^2 = exp(-z)", lambda x, y, z: x * x + y * y - np.exp(-z)),
])
def test_min_max_abs_are_read_in_both_spellings(text, f):
    s = Surface.parse(text)
    assert not s.is_polynomial
    p = np.random.default_rng(2).uniform(-1, 1, (20, 3))
    assert np.allclose(s(p), f(*p.T), rtol=1e-14, atol=1e-14)


@pytest.mark.parametrize("text, words", [
    ("x; a = sqrt(-1)", r"a is not a finite real number"),
    ("", r"empty"),
    ("// only a comment\n", r"empty"),
    (";;", r"empty"),
])
def test_other_errors_are_one_clear_line(text, words):
    with pytest.raises(SurfaceError, match=words) as info:
        Surface.parse(text)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("params, words", [
    ({"a": "1 +"}, r"parameter a = '1 \+'"),
    ({"a": ""}, r"parameter a = ''"),
    ({"a": None}, r"not a number"),
    ({"a": "b"}, r"unknown symbol b"),
    ({"x": 1}, r"x is a variable"),
])
def test_bad_parameters(params, words):
    with pytest.raises(SurfaceError, match=words):
        Surface.parse("a x + y", **params)


def test_long_input_is_fast_enough_and_exact():
    # 600 terms: sums are built in one go (adding term by term is quadratic in sympy).
    terms = " + ".join(f"{k}.5 x^{k % 7} y^{k % 5} z^{k % 3}" for k in range(600))
    s = Surface.parse(terms)
    expected = sum(sympy.Rational(2 * k + 1, 2) * x**(k % 7) * y**(k % 5) * z**(k % 3) for k in range(600))
    assert sympy.expand(s.expr - expected) == 0
