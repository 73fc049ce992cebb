"""The command line: report, file, and one-line errors with status 2."""

import subprocess
import sys


def run(*args):
    return subprocess.run([sys.executable, "-m", "singmesh.cli", *args], capture_output=True, text=True)


def test_mesh_writes_and_reports(tmp_path):
    out = tmp_path / "s.ply"
    r = run("mesh", "x^2+y^2+z^2-r^2", "r=1", "-o", str(out), "--coarse", "8")
    assert r.returncode == 0, r.stderr
    assert "Euler characteristic 2" in r.stdout
    assert out.exists() and out.stat().st_size > 1000


def test_bad_equation_one_line_exit_2():
    r = run("mesh", "gamma(x) + y")
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "unknown function gamma" in lines[0]


def test_bad_box():
    r = run("mesh", "x^2+y^2+z^2-1", "--box", "1", "0", "0", "1", "0", "1")
    assert r.returncode == 2 and "inverted" in r.stderr


def test_unknown_command():
    assert run("frobnicate").returncode == 2
