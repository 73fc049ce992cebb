"""Bad input, every kind of it (issue #13): one line naming the problem.

Each case goes through the Python API (``singmesh.mesh`` raises a
``SurfaceError``, a ``ValueError``, whose message is one line with the
words expected) and through the command line (``singmesh mesh ...``: exit
status 2, one line on stderr, no traceback, no output file left behind).
The command line runs in-process through ``main()`` (a traceback there is an
exception the test sees); a few cases run as real subprocesses too.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import singmesh
from singmesh import SurfaceError
from singmesh.cli import main

SPHERE = "x^2 + y^2 + z^2 - 1"
B = ((-1.5, 1.5),) * 3
SMALL = {"coarse": 8, "fine": 16}
SMALL_CLI = ["--coarse", "8", "--fine", "16"]

DEFS = """\
<definition name="Sphere" type="asurf">
x^2 + y^2 + z^2 - r^2;
<parameter name="r" value="0.75" />
</definition>
<definition name="Broken" type="asurf">
x^2 + y^2 - ;
</definition>
"""
OPEN_DEFS = DEFS + """<definition name="Open" type="asurf">
x^2 + y^2 - z^2;
"""


def _box(*numbers) -> list[str]:
    return ["--box", *map(str, numbers)]


# (id, API call (surface, box, keyword arguments) or None, command-line
# arguments after "mesh" (the output file is added) or None, words of the message)
CASES = [
    # --- syntax errors, at every position
    ("leading operator", ("* x + y", B, {}), ["* x + y"], r"unexpected '\*' at column 1"),
    ("trailing operator", ("x + y -", B, {}), ["x + y -"], "unexpected end of the expression at column 8"),
    ("unclosed bracket", ("(x + y", B, {}), ["(x + y"], r"expected '\)'"),
    ("unopened bracket", ("x + y)", B, {}), ["x + y)"], r"unexpected '\)' at column 6"),
    ("empty string", ("", B, {}), [""], "the equation is empty"),
    ("only spaces", ("   \t ", B, {}), ["   \t "], "the equation is empty"),
    ("power without exponent", ("x^", B, {}), ["x^"], "unexpected end of the expression at column 3"),
    ("** without exponent", ("2**", B, {}), ["2**"], "unexpected end of the expression"),
    ("two powers in a row", ("x y ^ ^ z", B, {}), ["x y ^ ^ z"], r"unexpected '\^' at column 7"),
    ("stray comma", ("x, y", B, {}), ["x, y"], "unexpected ',' at column 2"),
    ("empty brackets", ("x + ()", B, {}), ["x + ()"], "empty parentheses"),
    ("two equals signs", ("x = y = z", B, {}), ["x = y = z"], "more than one '='"),
    ("comparison", ("x > y", B, {}), ["x > y"], "unexpected character '>'"),
    # --- names
    ("unknown symbol", ("x + q y", B, {}), ["x + q y"], "unknown symbol q"),
    ("undefined parameter", ("x^2 + y^2 - a z", B, {}), ["x^2 + y^2 - a z"], "unknown symbol a"),
    ("unknown function", ("gamma(x) + y", B, {}), ["gamma(x) + y"], "unknown function gamma"),
    ("function with two arguments", ("sin(x, y) + z", B, {}), ["sin(x, y) + z"], "cannot apply sin"),
    ("definitions in a cycle", ("a x + y; a = b; b = a", B, {}), ["a x + y; a = b; b = a"], "in a cycle"),
    ("variable given a value", (SPHERE, B, {"x": 1}), [SPHERE, "x=1"], "x is a variable"),
    # --- F undefined on the whole box
    ("sqrt undefined on the box", ("sqrt(-1 - x^2) + y", B, {}), ["sqrt(-1 - x^2) + y"],
     "undefined everywhere in the box"),
    ("log undefined on the box", ("log(-x^2 - 1) + z", B, {}), ["log(-x^2 - 1) + z"],
     "undefined everywhere in the box"),
    # --- polynomials with no surface
    ("zero polynomial", ("0", B, {}), ["0"], "identically zero"),
    ("cancels to zero", ("(x+y)^2 - x^2 - 2 x y - y^2", B, {}), ["(x+y)^2 - x^2 - 2 x y - y^2"],
     "identically zero"),
    ("cancels to a constant", ("(x+1)^2 - x^2 - 2 x", B, {}), ["(x+1)^2 - x^2 - 2 x"], "nonzero constant"),
    # --- NaN and infinity
    ("nan in the equation", ("x + nan", B, {}), ["x + nan"], "NaN or infinite"),
    ("infinity in the equation", ("x^2 + oo y", B, {}), ["x^2 + oo y"], "NaN or infinite"),
    ("coefficient over doubles", ("x^2 - 1e400", B, {}), ["x^2 - 1e400"], "out of the range of double"),
    ("number power over doubles", ("x^2 - 10^100000", B, {}), ["x^2 - 10^100000"], "out of the range of double"),
    # 1e-400 read as 0 left x^2: no sign change, a silent empty mesh.
    ("coefficient under doubles", ("x^2 - 1e-400", B, {}), ["x^2 - 1e-400"],
     "coefficient of x.0 y.0 z.0 is below the range of double precision"),
    ("number power under doubles", ("y + x^2 10^-400", B, {}), ["y + x^2 10^-400"],
     "coefficient of x.2 y.0 z.0 is below the range of double precision"),
    ("nan parameter", ("x^2 + y^2 - a", B, {"a": float("nan")}), ["x^2 + y^2 - a", "a=nan"],
     "not a finite real number"),
    ("nan in the box", (SPHERE, ((np.nan, 1), (-1, 1), (-1, 1)), {}), [SPHERE, *_box("nan", 1, -1, 1, -1, 1)],
     "non-finite bound"),
    ("infinity in the box", (SPHERE, ((-np.inf, 1), (-1, 1), (-1, 1)), {}),
     [SPHERE, *_box("-inf", 1, -1, 1, -1, 1)], "non-finite bound"),
    # --- degree
    ("degree over the limit", ("x^19 + y - 1", B, {}), ["x^19 + y - 1"], "degree 19 is over the limit of 18"),
    ("expanded degree over the limit", ("(x + y + z + 1)^19", B, {}), ["(x + y + z + 1)^19"],
     "degree 19 is over the limit"),
    ("huge power", ("(x + y + z)^1000 - 1", B, {}), ["(x + y + z)^1000 - 1"], "over the degree limit"),
    ("huge power of a definition", ("X^1000 - 1; X = x + y + z", B, {}), ["X^1000 - 1; X = x + y + z"],
     "degree up to 1000 is over the limit"),
    # --- boxes
    ("inverted box", (SPHERE, ((1, -1), (-1, 1), (-1, 1)), {}), [SPHERE, *_box(1, -1, -1, 1, -1, 1)],
     "inverted in x"),
    ("box of zero width", (SPHERE, ((-1, 1), (0.5, 0.5), (-1, 1)), {}), [SPHERE, *_box(-1, 1, 0.5, 0.5, -1, 1)],
     "empty in y"),
    ("too few box numbers", (SPHERE, ((-1, 1), (-1, 1), (-1,)), {}), [SPHERE, *_box(-1, 1, -1, 1, -1)],
     "(three .lo, hi. pairs|six numbers)"),
    ("too many box numbers", (SPHERE, [-1, 1] * 4, {}), [SPHERE, "--box", *["-1", "1"] * 3, "7"],
     "(three .lo, hi. pairs|a seventh)"),
    ("non-numeric box", (SPHERE, (("a", 1), (-1, 1), (-1, 1)), {}), [SPHERE, *_box("a", 1, -1, 1, -1, 1)],
     "(three .lo, hi. pairs|six numbers)"),
    ("huge box", (SPHERE, ((-1e300, 1e300),) * 3, {}), [SPHERE, *_box(*[-1e300, 1e300] * 3)],
     "over the limit of 1e\\+06"),
    ("tiny box", (SPHERE, ((-1e-300, 1e-300),) * 3, {}), [SPHERE, *_box(*[-1e-300, 1e-300] * 3)],
     "under the limit of 1e-12"),
    ("narrow box far out", (SPHERE, ((1e5, 1e5 + 1e-3), (-1, 1), (-1, 1)), {}),
     [SPHERE, *_box(1e5, 1e5 + 1e-3, -1, 1, -1, 1)], "too narrow for its distance"),
    # --- resolution
    ("coarse not a power of two", (SPHERE, B, {"coarse": 30}), [SPHERE, "--coarse", "30"],
     "coarse must be a power of two"),
    ("fine not a power of two", (SPHERE, B, {"fine": 100}), [SPHERE, "--fine", "100"],
     "fine must be a power of two"),
    ("coarse zero", (SPHERE, B, {"coarse": 0}), [SPHERE, "--coarse", "0"], "coarse must be a power of two"),
    ("coarse negative", (SPHERE, B, {"coarse": -8}), [SPHERE, "--coarse", "-8"], "coarse must be a power of two"),
    ("coarse not an integer", (SPHERE, B, {"coarse": 8.5}), [SPHERE, "--coarse", "8.5"],
     "(power of two|invalid int value)"),
    ("coarse a boolean", (SPHERE, B, {"coarse": True}), None, "coarse must be a power of two"),
    ("fine over the limit", (SPHERE, B, {"fine": 1 << 20}), [SPHERE, "--fine", str(1 << 20)],
     "over the limit of 16384"),
    ("fine below coarse", (SPHERE, B, {"coarse": 32, "fine": 16}), [SPHERE, "--coarse", "32", "--fine", "16"],
     r"fine \(16\) must be at least coarse \(32\)"),
    ("unknown size", (SPHERE, B, {"size": "small"}), [SPHERE, "--size", "small"], "(size must be|invalid choice)"),
    ("negative chord", (SPHERE, B, {"size": "curvature", "chord": -1.0}),
     [SPHERE, "--size", "curvature", "--chord", "-1"], "chord is a fraction"),
    # --- very long input
    ("very long input, unclosed", ("(" + " + ".join(["x y z"] * 12500), B, {}),
     ["(" + " + ".join(["x y z"] * 12500)], r"expected '\)'"),
    ("deep brackets", ("(" * 20000 + "x" + ")" * 20000, B, {}), ["(" * 20000 + "x" + ")" * 20000],
     "nests brackets, signs or powers more than"),
    ("power tower", ("x" + "^2" * 5000, B, {}), ["x" + "^2" * 5000], "nests brackets, signs or powers"),
    ("many signs", ("-" * 50000 + "x", B, {}), ["-" * 50000 + "x"], "nests brackets, signs or powers"),
    # --- characters
    ("control character", ("x\x01 + y", B, {}), ["x\x01 + y"], r"unexpected character \(U\+0001\)"),
    ("NUL character", ("x^2\x00 + y", B, {}), ["x^2\x00 + y"], r"unexpected character \(U\+0000\)"),
    ("undecodable byte", ("x + y\udcff", B, {}), ["x + y\udcff"], r"unexpected character \(U\+DCFF\)"),
    ("not text", (b"x^2 + y^2 - 1", B, {}), None, "given as text or a sympy expression, not bytes"),
    # --- parameters on the command line
    ("parameter twice", None, ["x^2 + y^2 - a", "a=1", "a=2"], "parameter a is given twice"),
    ("parameter without value", ("x^2 + y^2 - a", B, {"a": ""}), ["x^2 + y^2 - a", "a="], "it is empty"),
    ("parameter without name", None, ["x^2 + y^2 - a", "=1"], "is not a parameter name"),
    ("parameter not name=value", None, [SPHERE, "a"], "name=value"),
    ("non-numeric parameter", ("x^2 + y^2 - a", B, {"a": object()}), ["x^2 + y^2 - a", "a=1+"],
     "(is not a number|syntax error)"),
    ("unknown option", None, [SPHERE, "--frobnicate"], "unrecognized arguments: --frobnicate"),
    ("long unknown option", None, [SPHERE, "--" + "x" * 100000], "unrecognized arguments: --xxx"),
    # --- definition files
    ("defs file missing", None, ["--defs", "{tmp}/missing.defs", "--name", "Sphere"], "cannot read"),
    ("defs file a folder", None, ["--defs", "{tmp}", "--name", "Sphere"], "cannot read"),
    ("defs unknown name", None, ["--defs", "{defs}", "--name", "Spheer"], "no definition named 'Spheer'.*'Sphere'"),
    ("defs malformed equation", None, ["--defs", "{defs}", "--name", "Broken"], "line 6.*syntax error"),
    ("defs definition not closed", None, ["--defs", "{open}", "--name", "Open"], "not closed"),
    ("defs without name", None, ["--defs", "{defs}"], "--defs needs --name"),
    ("defs parameter twice", None, ["--defs", "{defs}", "--name", "Sphere", "s=1", "s=2"], "given twice"),
    # A value given for nothing (a misspelt name, the wrong equation) was
    # ignored without a word.
    ("unused parameter", (SPHERE, B, {"b": 1}), [SPHERE, "b=1"], r"parameter b is not used by the equation \(it has none\)"),
    ("misspelt parameter", ("x^2 + y^2 - a z", B, {"a": 1, "aa": 2}), ["x^2 + y^2 - a z", "a=1", "aa=2"],
     r"parameter aa is not used by the equation \(its parameters are a\)"),
    ("defs parameter unused", None, ["--defs", "{defs}", "--name", "Sphere", "s=1"], "parameter s is not used"),
]


def _cli(args: list[str], tmp_path: Path, output: str = "out.ply") -> tuple[list[str], Path]:
    defs = tmp_path / "s.defs"
    defs.write_text(DEFS)
    (tmp_path / "open.defs").write_text(OPEN_DEFS)
    args = [a.replace("{tmp}", str(tmp_path)).replace("{defs}", str(defs)).replace("{open}", str(tmp_path / "open.defs"))
            for a in args]
    out = tmp_path / output
    return args, out


def _one_line(text: str) -> str:
    lines = text.strip().splitlines()
    assert len(lines) == 1, lines[:5]
    return lines[0]


def test_at_least_thirty_kinds():
    assert len(CASES) >= 30
    assert len({c[0] for c in CASES}) == len(CASES)


@pytest.mark.parametrize("name, api, cli, words", [c for c in CASES if c[1] is not None],
                         ids=[c[0] for c in CASES if c[1] is not None])
def test_api_refuses_in_one_line(name, api, cli, words):
    surface, box, kwargs = api
    with pytest.raises(SurfaceError) as info:
        singmesh.mesh(surface, box, **{**SMALL, **kwargs})
    assert isinstance(info.value, ValueError)
    message = _one_line(str(info.value))
    assert __import__("re").search(words, message), message
    assert len(message) < 400, message


@pytest.mark.parametrize("name, api, cli, words", [c for c in CASES if c[2] is not None],
                         ids=[c[0] for c in CASES if c[2] is not None])
def test_cli_refuses_in_one_line(name, api, cli, words, tmp_path, capsys):
    args, out = _cli(cli, tmp_path)
    extra = [] if "--coarse" in args or "--fine" in args else SMALL_CLI
    status = main(["mesh", *args, *extra, "-o", str(out)])
    captured = capsys.readouterr()
    assert status == 2
    line = _one_line(captured.err)
    assert line.startswith("singmesh: error: "), line
    assert __import__("re").search(words, line), line
    assert len(line) < 400, line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["open.defs", "s.defs"]  # no file, no partial file


@pytest.mark.parametrize("output, words", [
    ("missing/out.ply", "no folder"),
    ("out.xyz", "unknown mesh format '.xyz'"),
    ("out", "unknown mesh format ''"),
    (".", "unknown mesh format|is a folder"),
])
def test_cli_refuses_bad_output_before_meshing(output, words, tmp_path, capsys):
    status = main(["mesh", SPHERE, *SMALL_CLI, "-o", str(tmp_path / output)])
    captured = capsys.readouterr()
    assert status == 2
    assert words.split("|")[0] in _one_line(captured.err) or words.split("|")[-1] in captured.err
    assert "vertices" not in captured.out  # refused before meshing: no report
    assert list(tmp_path.iterdir()) == []


@pytest.mark.skipif(os.name != "posix" or not Path("/proc/self").exists(), reason="needs Linux /proc")
def test_cli_unwritable_output(capsys):
    # /proc takes no new files, even from root (who may write anywhere else).
    status = main(["mesh", SPHERE, *SMALL_CLI, "-o", "/proc/singmesh-test.ply"])
    assert status == 2
    assert "cannot write /proc/singmesh-test.ply" in _one_line(capsys.readouterr().err)


def test_failing_writer_leaves_no_partial_file(tmp_path, monkeypatch):
    # The writer fails half-way (a full disk): the file is not left behind,
    # and neither is the temporary one.
    import meshio

    m = singmesh.mesh(SPHERE, B, **SMALL)
    out = tmp_path / "s.vtu"
    out.write_bytes(b"the previous file")

    def broken(self, path, *args, **kwargs):
        Path(path).write_bytes(b"half a mesh")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(meshio.Mesh, "write", broken)
    with pytest.raises(OSError):
        m.write(out)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.vtu"]
    assert out.read_bytes() == b"the previous file"


def test_msh_with_line_cells(tmp_path):
    # The Whitney umbrella's handle is an isolated line: line cells beside
    # the triangles, which meshio writes to Gmsh only with node entities.
    import meshio

    m = singmesh.mesh("x^2 - y^2 z", ((-1, 1),) * 3, coarse=8, fine=32)
    points, lines = m.curve_lines()
    assert len(lines)
    out = tmp_path / "u.msh"
    m.write(out)
    back = meshio.read(out)
    tri = [c.data for c in back.cells if c.type == "triangle"][0]
    seg = [c.data for c in back.cells if c.type == "line"][0]
    # Gmsh orders the nodes by entity: compare the cells' coordinates.
    key = lambda a: np.sort(np.round(a, 12).reshape(len(a), -1), axis=0)  # noqa: E731
    np.testing.assert_array_equal(key(back.points[tri].reshape(len(tri), -1)),
                                  key(points[m.faces].reshape(len(m.faces), -1)))
    assert len(seg) == len(lines)
    np.testing.assert_allclose(np.sort(back.points[seg].reshape(-1, 3), axis=0),
                               np.sort(points[lines].reshape(-1, 3), axis=0))


@pytest.mark.parametrize("args, words", [
    (["x^2 + y^2 - a", "a=1", "a=2"], "given twice"),
    (["gamma(x) + y"], "unknown function gamma"),
    ([SPHERE, "--box", "-1e300", "1e300", "-1", "1", "-1", "1"], "over the limit"),
])
def test_cli_subprocess_one_line_no_traceback(args, words, tmp_path):
    out = tmp_path / "o.ply"
    r = subprocess.run([sys.executable, "-m", "singmesh.cli", "mesh", *args, *SMALL_CLI, "-o", str(out)],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 2
    assert "Traceback" not in r.stderr
    assert words in _one_line(r.stderr)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("args", [["-x^2-y^2+z^2+1"], ["--coarse", "8", "-x^2-y^2+z^2+a", "a=1"]])
def test_cli_equation_with_a_leading_minus_is_not_an_option(args, tmp_path, capsys):
    # argparse takes any word starting with '-' for an option: the equation
    # "-x^2-y^2+z^2+1" (a hyperboloid of one sheet) is meshed, not refused.
    out = tmp_path / "h.ply"
    status = main(["mesh", *args, *([] if "--coarse" in args else ["--coarse", "8"]), "--fine", "16",
                   "-o" + str(out)])
    captured = capsys.readouterr()
    assert status == 0, captured.err
    assert "-x**2 - y**2 + z**2 + 1" in captured.out
    assert out.stat().st_size > 1000


def test_unused_parameters_of_a_definition_file_are_no_error(tmp_path):
    # A SingSurf file may declare parameters its equation does not use: only
    # the caller's own unused values are refused.
    from singmesh.defs import find_definition, read_definitions

    path = tmp_path / "p.defs"
    path.write_text('<definition name="Plane" type="asurf">\nx + a*y - 0.25;\n'
                    '<parameter name="a" value="0.5" />\n<parameter name="b" value="2" />\n</definition>\n')
    d = find_definition(read_definitions(path), "Plane")
    assert float(d.surface()(np.array([0.25, 0.0, 0.0]))) == 0.0
    assert float(d.surface(a=1)(np.array([0.0, 0.25, 0.0]))) == 0.0
    assert float(d.surface(a=1, b=3)(np.array([0.0, 0.25, 0.0]))) == 0.0  # b: declared by the file
    with pytest.raises(SurfaceError, match="parameter c is not used"):
        d.surface(c=1)


def test_unused_parameter_with_a_sympy_expression():
    import sympy as sp

    x, y, z, a = sp.symbols("x y z a")
    with pytest.raises(SurfaceError, match=r"parameter b is not used by the equation \(its parameters are a\)"):
        singmesh.Surface.parse(x**2 + y**2 - a * z, a=1, b=2)
    s = singmesh.Surface.parse(x**2 + y**2 - a * z, a=0.5)
    assert float(s(np.array([1.0, 0.0, 2.0]))) == 0.0


def test_cli_output_closed_early_is_no_traceback(tmp_path):
    # singmesh mesh ... | head: the reader has gone before the report is
    # printed; the mesh file is still written and no traceback follows.
    out = tmp_path / "s.ply"
    p = subprocess.Popen([sys.executable, "-m", "singmesh.cli", "mesh", SPHERE, *SMALL_CLI, "-o", str(out)],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    p.stdout.close()
    err = p.stderr.read().decode()
    assert p.wait(timeout=120) == 0, err
    assert "Traceback" not in err and "Error" not in err, err
    assert out.stat().st_size > 1000


#: F nearly a square, G^2 - e (a near-double component): (text, e, the
#: sheets' distance apart or None where e is below the rounding of F's
#: terms).  Rotated and shifted planes with 15-digit coefficients, a
#: sphere and a cone, exact and decimal e.
NEAR_DOUBLE = [
    ("x^2 - 1e-20", 1e-20, 2e-10),                                              # planes x = +-1e-10
    ("x^2*y^2 - 1/10^20", 1e-20, 1e-10),                                        # xy = +-1e-10
    ("(x^2 + y^2 + z^2 - 1)^2 - 1/10^16", 1e-16, None),                         # 1e-16 below F's rounding
    ("(x^2 + y^2 + z^2 - 1)^2 - 1e-10", 1e-10, 1e-5),
    ("0.36*x^2 + 0.48*x*y + 0.16*y^2 - 1e-22", 1e-22, None),                    # 0.6 x + 0.4 y = +-1e-11
    ("(0.612372435695795*x - 0.353553390593274*y + 0.707106781186548*z - 0.123456789012345)^2 - 1e-20",
     1e-20, None),
    ("(x^2 + y^2 + z^2 - 1)^2 + 1e-16", 1e-16, None),                           # its constant rounds to 1
    ("(x^2 + y^2 - z^2)^2 - 1e-20", 1e-20, None),
]


@pytest.mark.parametrize("text, e, apart", NEAR_DOUBLE, ids=[c[0] for c in NEAR_DOUBLE])
def test_nearly_a_square_is_said(text, e, apart, tmp_path, capsys):
    """F = G^2 - e with e tiny: its two sheets are closer than any lattice
    parts (or rounding cannot tell them from none).  The CLI at its
    defaults says so in one line, naming a near-double component and what
    to do, with exit status 2 and no file; the distance it gives is
    2 sqrt(e) / |grad G| (to 10%).  On main ``x^2 - 1e-20`` at the defaults
    answered "out of memory" (63 GB for the distances between the ends of
    130,000 candidate boxes), the sphere's square minus 1e-16 ran for
    minutes; at fine 32 some gave an empty mesh and a warning."""
    import re
    import time

    out = tmp_path / "out.ply"
    t0 = time.process_time()  # CPU: the machine is shared
    status = main(["mesh", text, "-o", str(out)])
    captured = capsys.readouterr()
    assert status == 2
    line = _one_line(captured.err)
    assert line.startswith("singmesh: error: F is nearly a square near ("), line
    assert "near-double component" in line and "mesh G alone" in line, line
    assert "out of memory" not in line
    if apart is not None:
        said = float(re.search(r"two sheets (\S+) apart", line).group(1))
        assert abs(said - apart) <= 0.1 * apart, line
    else:
        assert "rounding cannot tell" in line, line
    assert not out.exists()
    assert time.process_time() - t0 < 30


@pytest.mark.parametrize("square, e", [("x^2", "1e-20"), ("(x^2 + y^2 + z^2 - 1)^2", "1/10^12"),
                                       ("(0.6*x + 0.8*z - 0.1)^2", "1e-9")])
def test_nearly_a_square_without_zeros_is_empty(square, e):
    """G^2 + e, e > 0 above the rounding of F's terms: no zero (F >= e),
    an empty mesh, quickly, and no refusal.  On main ``x^2 + 1e-20`` ran
    for minutes (the sheet of near-singular points traced as curves)."""
    import time
    import warnings

    import sympy as sp

    g2 = sp.sympify(square.replace("^", "**"), rational=True)
    assert sp.sqf_list(g2)[1][0][1] == 2 and sp.sympify(e.replace("^", "**"), rational=True) > 0  # F >= e > 0
    t0 = time.process_time()  # CPU: the machine is shared
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = singmesh.mesh(f"{square} + {e}", ((-1.0, 1.0),) * 3)
    assert len(m.faces) == 0
    assert time.process_time() - t0 < 30


@pytest.mark.parametrize("text, shown", [
    ("x^2 + y^2 + z^2 - 1e300", "1.0e+300"),            # read exactly: an integer of 301 digits
    ("x^2 + y^2 + z^2 + 10^40", "1.0e+40"),
    ("x^2 + y^2 + z^2 - 1 - 1e-300", "- 1.0"),          # 1 + 1e-300: a decimal of 301 digits
])
def test_huge_numbers_are_shown_short(text, shown):
    # The warning and the report printed every digit of the exact number.
    import warnings

    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        m = singmesh.mesh(text, ((-2.0, 2.0),) * 3, coarse=8, fine=32)
    lines = [str(w.message) for w in rec] + m.report_text().splitlines()
    shown_in = [t for t in lines if "x**2" in t]
    assert shown_in and all(shown in t and len(t) < 160 for t in shown_in), shown_in
    # The exact number is what was meshed: the unit sphere for the last case.
    if "1e-300" in text:
        assert len(m.faces) > 0 and np.abs(np.linalg.norm(m.vertices, axis=1) - 1).max() < 1e-12


#: Two sheets closer than a fine cell, parted by far more than rounding
#: (G^2 - e with e well above F's rounding): (text, the box, fine, a point
#: between the sheets).  Slabs between lattice planes, off-lattice float
#: positions with 15 digits.
THIN_SLABS = [
    ("(x - 0.0131234567891234)^2 - 1.23456789012345e-6", ((-1.0, 1.0),) * 3, 32, (0.0131234567891234, 0.2, 0.3)),
    ("(y + 0.371234567890123)^2 - 2.5e-7", ((-1.0, 1.0),) * 3, 32, (0.1, -0.371234567890123, -0.4)),
    ("(x - 0.0131234567891234)^2 - 1.23456789012345e-6", ((-1.0, 1.0),) * 3, 64, (0.0131234567891234, 0.2, 0.3)),
]


@pytest.mark.parametrize("text, box, fine, inside", THIN_SLABS, ids=[f"{c[0]}-{c[2]}" for c in THIN_SLABS])
def test_sheets_closer_than_a_cell_are_refused_not_empty(text, box, fine, inside):
    """F > 0 at every lattice point but < 0 in a slab thinner than a fine
    cell between two of its planes: the surface is there, and no lattice
    edge meets it.  Not an empty mesh that says F "only touches 0" (what
    main said of ``(x - 0.013)^2 - 1e-6`` at fine 32; at the defaults main
    ran out of memory after a minute: 16 GiB of distances between the
    65,536 Newton ends along the slab), but one line naming a point where
    F has the other sign and what to change."""
    import re

    import sympy as sp

    x, y, z = sp.symbols("x y z")
    f = sp.lambdify((x, y, z), sp.sympify(text.replace("^", "**")))
    assert f(*inside) < 0  # the slab is real
    with pytest.raises(singmesh.SurfaceError) as err:
        singmesh.mesh(text, box, coarse=8, fine=fine)
    line = str(err.value)
    assert "\n" not in line and "only touches" not in line
    assert "changes sign near (" in line and "thinner than a fine cell" in line and "raise fine" in line, line
    named = [float(v) for v in re.search(r"changes sign near \(([^)]*)\)", line).group(1).split(",")]
    assert f(*named) < 0, line  # the point named is in the slab
    assert abs(named[0] - inside[0]) < 0.01 or abs(named[1] - inside[1]) < 0.01, line


def test_cli_sheets_closer_than_a_cell(tmp_path, capsys):
    """The CLI says the same in one line, status 2, no file."""
    out = tmp_path / "out.ply"
    status = main(["mesh", THIN_SLABS[0][0], "--box", "-1", "1", "-1", "1", "-1", "1", "--fine", "32", "--coarse", "8",
                   "-o", str(out)])
    line = _one_line(capsys.readouterr().err)
    assert status == 2 and "thinner than a fine cell" in line, line
    assert not out.exists()
