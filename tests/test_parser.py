"""Surface parsing: accepted syntaxes and the errors that name the problem."""

import numpy as np
import pytest
import sympy

from singmesh import Surface, SurfaceError

x, y, z = sympy.symbols("x y z")


@pytest.mark.parametrize("text, expected", [
    ("4(x^2+y^2+z^2) + 16 x y z - 1", 4 * (x**2 + y**2 + z**2) + 16 * x * y * z - 1),
    ("2 x y", 2 * x * y),
    ("x(y+1)", x * y + x),
    ("x^2 = y^2 + z", x**2 - y**2 - z),
    ("a x + b y - 1; a = 2; b = 3;", 2 * x + 3 * y - 1),
    ("x**2 + y**2 - z**2", x**2 + y**2 - z**2),
    ("(x+y)^3", (x + y) ** 3),
])
def test_accepts(text, expected):
    s = Surface.parse(text)
    assert sympy.expand(s.expr - expected.subs({x: sympy.Symbol("x", real=True),
                                                 y: sympy.Symbol("y", real=True),
                                                 z: sympy.Symbol("z", real=True)})) == 0


def test_constants_are_numbers():
    s = Surface.parse("sqrt(5) x + pi y + cos(2 pi/5) z")
    assert s.degree == 1
    assert s.coeffs[1, 0, 0] == pytest.approx(5 ** 0.5)
    assert s.coeffs[0, 1, 0] == pytest.approx(np.pi)
    assert s.coeffs[0, 0, 1] == pytest.approx(np.cos(2 * np.pi / 5))


def test_keyword_parameters_override_definitions():
    s = Surface.parse("a x - 1; a = 2;", a=5)
    assert s.coeffs[1, 0, 0] == 5


def test_barth_parameter_chain():
    s = Surface.parse("4(t^2 x^2-y^2)(t^2 y^2-z^2)(t^2 z^2-x^2) - (1+2t)(x^2+y^2+z^2-1)^2;"
                      " t = (1+sqrt(5))/2;")
    assert s.degree == 6
    t = (1 + 5 ** 0.5) / 2
    p = np.array([0.3, -0.7, 0.2])
    direct = 4 * (t**2 * p[0]**2 - p[1]**2) * (t**2 * p[1]**2 - p[2]**2) * (t**2 * p[2]**2 - p[0]**2) \
        - (1 + 2 * t) * (p @ p - 1) ** 2
    assert s(p) == pytest.approx(direct, rel=1e-12)


def test_sympy_expression_input():
    assert Surface.parse(x**2 + y**2 - z**2).degree == 2


def test_derivatives():
    s = Surface.parse("x^3 y + z^2 x")
    p = np.array([[0.5, -1.5, 2.0]])
    assert np.allclose(s.gradient(p), [[3 * 0.25 * -1.5 + 4.0, 0.125, 2 * 2.0 * 0.5]])
    h = s.hessian(p)[0]
    assert np.allclose(h, [[6 * 0.5 * -1.5, 3 * 0.25, 2 * 2.0], [3 * 0.25, 0, 0], [4.0, 0, 2 * 0.5]])


@pytest.mark.parametrize("text, words", [
    ("gamma(x) + y", "unknown function gamma"),
    ("x + w", "unknown symbol w"),
    ("x + beta", "unknown symbol beta"),
    ("x + (y", "syntax error"),
    ("x ++* y", "syntax error: unexpected '\\*' at column 5"),
    ("0 * x", "identically zero"),
    ("x^40", "degree 40"),
    ("x + nan", "NaN"),
    ("x + 1/0", "division by zero at column 6"),
    ("x + oo", "infinite"),
    ("", "empty"),
    ("x; a 2", "name = value"),
    ("x = y = z", "more than one"),
    ("3", "constant"),
    ("sqrt(-1) x", "not real"),
])
def test_errors_name_the_problem(text, words):
    with pytest.raises(SurfaceError, match=words):
        Surface.parse(text)


@pytest.mark.parametrize("text, f", [
    ("sin(x) + y", lambda x, y, z: np.sin(x) + y),
    ("x / (1 + sin(y)^2)", lambda x, y, z: x / (1 + np.sin(y) ** 2)),
    ("sqrt(x^2 + y^2) - z", lambda x, y, z: np.sqrt(x * x + y * y) - z),
])
def test_non_polynomials_are_read_as_functions(text, f):
    # Not refused any more (issue #10): an interval-bounded surface whose
    # values are the function's.
    s = Surface.parse(text)
    assert not s.is_polynomial
    p = np.random.default_rng(1).uniform(-1, 1, (20, 3))
    assert np.allclose(s(p), f(*p.T), rtol=1e-14, atol=1e-14)


@pytest.mark.parametrize("text", ["x / (1 + y^2)", "1/x + 1/y - 3", "(x^2 - y^2) / (x - y) + 1/z", "2.5/(x - 0.1) - z"])
def test_rational_functions_are_read_as_numerator_over_denominator(text):
    # F = N / D has the zero set N = 0 (off D = 0): the polynomial N, with D kept
    # for the report; checked by sympy: N / D - F simplifies to 0, D not constant.
    import sympy

    s = Surface.parse(text)
    assert s.is_polynomial and s.denominator
    f = sympy.sympify(text.replace("^", "**"))
    assert sympy.simplify(sympy.sympify(str(s.expr)) / sympy.sympify(s.denominator) - f) == 0
    assert sympy.sympify(s.denominator).free_symbols


def test_not_text():
    with pytest.raises(SurfaceError, match="text or a sympy expression"):
        Surface.parse(3.5)
