"""SingSurf definition files: read_definitions, `singmesh defs`, `singmesh mesh --defs`.

The files are written here, in SingSurf's own (not quite XML) style: open
``<parameter>`` tags, stray characters in tags, HTML in comments, nested
groups, definitions in x, y, z.
"""

import subprocess
import sys

import numpy as np
import pytest
import sympy

import singmesh
from singmesh import SurfaceError, find_definition, read_definitions
from singmesh.defs import parse_definitions

x, y, z = sympy.symbols("x y z", real=True)

DEFS = """\
<group name="Simple">
<definition name="Sphere" type="asurf">
// A sphere of radius r
x^2 + y^2 + z^2 - r^2;
<parameter name="r" value="0.75" />
<variable name="x" min="-1.14" max="1.03">
<variable name="y" min="-1.13" max="1.04">
<variable name="z" min="-1.12" max="1.05"}, >
</definition>

<definition name="Off-centre sphere" type="asurf">
(x-x0)^2 + (y-y0)^2 + (z-z0)^2 - r^2;
<variable name="x" min="-1" max="1">
<variable name="y" min="-1" max="1">
<variable name="z" min="-1" max="1">
<parameter name="r" value="1" />
</definition>
</group>

<group name="Cubics">
<group name="Class II: one A1 singularity">
<definition name="CayleyII" type="asurf">
//<h3>Class II: 1 A<sub>1</sub> singularity</h3>
//<p>In Cayley's notation: II = 12 - C2;
W (a X^2 + b Y^2 + c Z^2 + f X Y+ g X Z+h Y Z)+2 k X Y Z;
X = x + y + z + w;
Y = -x - y + z + w;
Z = x -y -z + w;
W = -x + y - z + w;
w = 1;
<parameter name="a" value="0.9">
<parameter name="b" value="-0.3">
<parameter name="c" value="0.8" />
<parameter name="f" value="-0.2" />
<parameter name="g" value="1.0" />
<parameter name="h" value="0.8" />
<parameter name="k" value="0.4" />
<variable name="x" min="-3.14" max="3.03">
<variable name="y" min="-3.13" max="3.04">
<variable name="z" min="-3.12" max="3.05">
</definition>
</group>
<definition name="Cayley's Cubic" type="asurf">
//# A cubic surface with 4 nodes
4 (x^2+y^2+z^2)
  + 16 x y z \u2212 1;
<option name="colour" value="red" />
</definition>
</group>

<definition name="Broken" type="asurf">
// the error is on the second line of the equation
x^2 + y^2
   + (z^2 - 1;
<variable name="x" min="-1" max="1">
</definition>

<definition name="A parametric one" type="psurf">
[cos(u), sin(u), v];
</definition>
"""


@pytest.fixture()
def defs_file(tmp_path):
    path = tmp_path / "test.defs"
    path.write_text(DEFS, encoding="utf-8")
    return path


def test_entries_groups_boxes_parameters(defs_file):
    ds = read_definitions(defs_file)
    assert [d.name for d in ds] == ["Sphere", "Off-centre sphere", "CayleyII", "Cayley's Cubic",
                                    "Broken", "A parametric one"]
    assert [d.group for d in ds] == [("Simple",), ("Simple",), ("Cubics", "Class II: one A1 singularity"),
                                     ("Cubics",), (), ()]
    sphere, _, cayley2, cayley, broken, param = ds
    assert sphere.box == ((-1.14, 1.03), (-1.13, 1.04), (-1.12, 1.05))
    assert sphere.parameters == {"r": "0.75"}
    assert sphere.line == 2 and sphere.first_line == 3
    assert sphere.description == "A sphere of radius r"
    assert cayley2.parameters == dict(a="0.9", b="-0.3", c="0.8", f="-0.2", g="1.0", h="0.8", k="0.4")
    assert cayley2.description.startswith("Class II: 1 A 1 singularity")
    assert cayley.box is None and cayley.options == {"colour": {"name": "colour", "value": "red"}}
    assert broken.box is None   # only x has a range
    assert param.type == "psurf"


def test_equations_read_as_written_by_hand(defs_file):
    ds = {d.name: d for d in read_definitions(defs_file)}
    same = lambda a, b: sympy.expand(a - b) == 0  # noqa: E731
    assert same(ds["Sphere"].surface().expr, x**2 + y**2 + z**2 - sympy.Rational(9, 16))
    assert same(ds["Cayley's Cubic"].surface().expr, 4 * (x**2 + y**2 + z**2) + 16 * x * y * z - 1)
    a, b, c, f, g, h, k = (sympy.Rational(v) for v in ("0.9", "-0.3", "0.8", "-0.2", "1.0", "0.8", "0.4"))
    X, Y, Z, W = x + y + z + 1, -x - y + z + 1, x - y - z + 1, -x + y - z + 1
    assert same(ds["CayleyII"].surface().expr,
                W * (a*X**2 + b*Y**2 + c*Z**2 + f*X*Y + g*X*Z + h*Y*Z) + 2*k*X*Y*Z)
    # Keyword values override the file's.
    assert same(ds["Sphere"].surface(r=2).expr, x**2 + y**2 + z**2 - 4)


def test_errors_are_placed_in_the_file(defs_file):
    ds = {d.name: d for d in read_definitions(defs_file)}
    with pytest.raises(SurfaceError) as info:
        ds["Broken"].surface()
    msg = str(info.value)
    # The missing ')' is found at the ';' of "   + (z^2 - 1;" (column 14).
    lines = DEFS.splitlines()
    row = next(i for i, t in enumerate(lines, 1) if "(z^2 - 1;" in t)
    assert f"test.defs, line {row}, column 14" in msg and "expected ')'" in msg and "Broken" in msg
    with pytest.raises(SurfaceError, match=r"line 12, column 4 \('Off-centre sphere'\): unknown symbol x0"):
        ds["Off-centre sphere"].surface()
    with pytest.raises(SurfaceError, match="'psurf' definition, not an implicit surface"):
        ds["A parametric one"].surface()


def test_find_definition(defs_file):
    ds = read_definitions(defs_file)
    assert find_definition(ds, "cayleyii").name == "CayleyII"
    with pytest.raises(SurfaceError, match="did you mean 'Sphere'"):
        find_definition(ds, "Spere")


@pytest.mark.parametrize("text, words", [
    ('<definition name="a" type="asurf">\nx;\n', "not closed"),
    ('<definition name="a" type="asurf">\nx;\n<definition name="b" type="asurf">\n', "missing </definition>"),
    ("</definition>\n", "without a <definition>"),
])
def test_malformed_files(text, words):
    with pytest.raises(SurfaceError, match=words):
        parse_definitions(text, "bad.defs")


def test_unreadable_file(tmp_path):
    with pytest.raises(SurfaceError, match="cannot read"):
        read_definitions(tmp_path / "missing.defs")


def test_tags_on_equation_lines_and_urls_in_comments():
    text = ('<definition name="u" type="asurf">// see http://example.org/<b>x</b>\n'
            'x^2 - y <parameter name="s" value="2"/> + s z;  </definition>\n')
    (d,) = parse_definitions(text)
    assert d.parameters == {"s": "2"}
    assert sympy.expand(d.surface().expr - (x**2 - y + 2 * z)) == 0


def test_mesh_of_a_definition_on_its_box(defs_file):
    d = find_definition(read_definitions(defs_file), "Sphere")
    m = d.mesh(coarse=8, fine=16)
    assert np.allclose(m.box, d.box)
    r = np.linalg.norm(m.vertices, axis=1)
    assert len(m.faces) and np.allclose(r, 0.75, atol=1e-12)


# ------------------------------------------------------------------ command line
def run(*args):
    return subprocess.run([sys.executable, "-m", "singmesh.cli", *args], capture_output=True, text=True)


def test_cli_lists_and_checks(defs_file):
    r = run("defs", str(defs_file), "--check")
    assert r.returncode == 0, r.stderr
    assert "Cubics / Class II: one A1 singularity" in r.stdout
    assert "reads: degree 3" in r.stdout
    assert "does not read" in r.stdout and "expected ')'" in r.stdout
    assert "6 definitions; of the implicit surfaces 3 read, 2 do not" in r.stdout


def test_cli_shows_one(defs_file):
    r = run("defs", str(defs_file), "--name", "CayleyII")
    assert r.returncode == 0, r.stderr
    assert "parameter   k = 0.4" in r.stdout and "X = x + y + z + w;" in r.stdout


def test_cli_meshes_a_definition_with_overrides(defs_file, tmp_path):
    out = tmp_path / "s.ply"
    r = run("mesh", "--defs", str(defs_file), "--name", "Sphere", "r=0.5", "--coarse", "8", "--fine", "16",
            "-o", str(out))
    assert r.returncode == 0, r.stderr
    assert "[-1.14, 1.03] x [-1.13, 1.04] x [-1.12, 1.05]" in r.stdout
    import meshio

    v = meshio.read(out).points
    assert np.allclose(np.linalg.norm(v, axis=1), 0.5, atol=1e-6)


@pytest.mark.parametrize("args, words", [
    (["--name", "Sphere"], "--name goes with --defs"),
    (["--defs", "DEFS"], "--defs needs --name"),
    (["--defs", "DEFS", "--name", "Broken"], "line 54, column 14"),
    (["--defs", "DEFS", "--name", "Nope"], "no definition named 'Nope'"),
    (["x^2 - 1", "1a=2"], "not a parameter name"),
])
def test_cli_errors_are_one_line(defs_file, args, words):
    r = run("mesh", *[str(defs_file) if a == "DEFS" else a for a in args])
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and words in lines[0], r.stderr


def test_cli_multiline_equation_and_parameters(tmp_path):
    r = run("mesh", "x^2 + y^2 // a comment\n + z^2 - R^2;\n R = 1;", "R=0.5", "--coarse", "8", "--fine", "16",
            "--box", "-1", "1", "-1", "1", "-1", "1")
    assert r.returncode == 0, r.stderr
    assert "Euler characteristic 2" in r.stdout


def test_api_exports():
    assert singmesh.read_definitions is read_definitions
