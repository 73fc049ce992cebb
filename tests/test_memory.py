"""The memory budget (issue #13): a request over the limit is refused in one line, before it is made."""

from __future__ import annotations

import resource
import subprocess
import sys

import pytest

import singmesh
from singmesh import memory
from singmesh.cli import main

BARTH = ("4(t^2 x^2-y^2)(t^2 y^2-z^2)(t^2 z^2-x^2) - (1+2t)(x^2+y^2+z^2-1)^2; t = (1+sqrt(5))/2",
         ((-2.0, 2.0),) * 3)


def test_request_over_max_memory_is_refused_before_the_boxes_are_made():
    # Barth at coarse 512 would hold millions of boxes of 2.7 kB of Bernstein
    # coefficients each: refused at the first levels, in one line, without
    # numpy's allocator being asked (no MemoryError), and fast.
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    with pytest.raises(memory.MemoryBudgetError) as info:
        singmesh.mesh(*BARTH, coarse=512, fine=1024, max_memory="1G")
    message = str(info.value)
    assert "\n" not in message
    assert "coarse 512, fine 1024 would need about" in message and "over max_memory (1 GB)" in message
    assert isinstance(info.value, singmesh.SurfaceError)
    grown = (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before) * 1024
    assert grown < 200 << 20  # the peak did not move by more than the imports of a first mesh


def test_machine_limit_refuses_what_it_cannot_hold():
    # No max_memory: the machine's available memory is the limit.  Coarse
    # 16384 (2^42 boxes at the uniform level) cannot fit anywhere.
    avail = memory.available_bytes()
    if avail is None:
        pytest.skip("no MemAvailable on this system")
    with pytest.raises(memory.MemoryBudgetError, match="over the memory available"):
        singmesh.mesh("x^2 + y^2 + z^2 - 1", ((-1.2, 1.2),) * 3, coarse=16384, fine=16384)


def test_request_under_the_limit_is_meshed_and_estimated():
    m = singmesh.mesh("x^2 + y^2 + z^2 - 1", ((-1.2, 1.2),) * 3, coarse=16, fine=64, max_memory="4G")
    assert len(m.faces) > 500
    est = m.stats["memory_estimate"]
    assert memory.resident_bytes() * 0.5 < est < 4 << 30


@pytest.mark.parametrize("text, size", [("512M", 512 << 20), ("2G", 2 << 30), ("1.5 GB", 1.5 * (1 << 30)),
                                        ("100k", 102400), (1e9, 1e9), ("3e9", 3e9)])
def test_sizes_read(text, size):
    assert memory.parse_size(text) == size


@pytest.mark.parametrize("text", ["", "lots", "-1G", "0", float("nan"), "2X", True])
def test_bad_sizes_refused(text):
    with pytest.raises(singmesh.SurfaceError, match="max_memory"):
        memory.parse_size(text)
    with pytest.raises(singmesh.SurfaceError, match="max_memory"):
        singmesh.mesh("x^2 + y^2 + z^2 - 1", coarse=8, fine=16, max_memory=text)


def test_cli_max_memory(tmp_path, capsys):
    out = tmp_path / "b.ply"
    status = main(["mesh", BARTH[0], "--coarse", "512", "--fine", "1024", "--max-memory", "1G", "-o", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 2 and len(err) == 1
    assert err[0].startswith("singmesh: error: meshing at coarse 512, fine 1024 would need about")
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_cli_refusal_in_a_fresh_process(tmp_path):
    # As a user sees it: status 2, one line, no traceback, in well under the
    # time the mesh would take.
    r = subprocess.run([sys.executable, "-m", "singmesh.cli", "mesh", "x^2+y^2+z^2-1", "--coarse", "4096",
                        "--fine", "4096", "--max-memory", "300M", "-o", str(tmp_path / "s.ply")],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 2
    assert "Traceback" not in r.stderr and len(r.stderr.strip().splitlines()) == 1
    assert "over max_memory (300 MB)" in r.stderr
