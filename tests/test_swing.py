"""skeleton.swing (issue #11): batched Newton loops stop once their whole live set
alternates between two values, with the values the remaining iterations would leave.
Meshes come out to the bit as with every iteration run."""

from __future__ import annotations

import numpy as np
import pytest

import singmesh
from singmesh.skeleton import swing as swing_mod
from singmesh.skeleton.swing import Swing

from test_rounded import float_rotated

BARTH = ("4*(((1+sqrt(5))/2)**2*x**2-y**2)*(((1+sqrt(5))/2)**2*y**2-z**2)*(((1+sqrt(5))/2)**2*z**2-x**2)"
         "-(1+2*((1+sqrt(5))/2))*(x**2+y**2+z**2-1)**2")


def _loop(x0, iterations, use_swing):
    """A toy batched loop: point k swings between two floats from iteration k on
    (a step of -+1 ulp), points stop when their counter runs out."""
    x = np.array(x0, float)
    live = np.arange(len(x))
    swing = Swing(iterations)
    for it in range(iterations):
        if len(live) == 0:
            break
        if use_swing:
            last = swing.cycle(live, x[live])
            if last is not None:
                x[live] = last
                break
        y = x[live]
        toward = np.where(live <= it, np.where(np.arange(len(y)) % 2 == 0, 1.0, -1.0), 0.0)
        step = np.where(y.view(np.int64) % 2 == 0, 1, -1) * toward
        x[live] = np.nextafter(y, y + step)
        if it == 3:
            live = live[:-1]  # one point leaves the batch
    return x


@pytest.mark.parametrize("iterations", [5, 6, 19, 20])
def test_two_cycle_gives_what_every_iteration_gives(iterations):
    x0 = np.array([0.3, 1.7, -2.25, 1e-300, 5.0])
    assert np.array_equal(_loop(x0, iterations, True).view(np.int64), _loop(x0, iterations, False).view(np.int64))


def _mesh_bits(text, box, monkeypatch, enabled):
    calls = []
    original = Swing.cycle

    def cycle(self, live, values):
        out = original(self, live, values) if enabled else None
        calls.append(out is not None)
        return out

    monkeypatch.setattr(swing_mod.Swing, "cycle", cycle)
    m = singmesh.mesh(text, box=box)
    monkeypatch.undo()
    return m.vertices.tobytes() + m.faces.tobytes(), sum(calls)


@pytest.mark.parametrize("text, box, swings", [
    (BARTH, ((-2.0, 2.0),) * 3, True),                           # 50 nodes, skeleton traces swing
    (float_rotated("x^2 + y^2 - z^2 + 0.3 x y z", 7)[0], ((-1.0, 1.0),) * 3, False),
])
def test_meshes_as_with_every_iteration(text, box, swings, monkeypatch):
    full, _ = _mesh_bits(text, box, monkeypatch, False)
    cut, stopped = _mesh_bits(text, box, monkeypatch, True)
    assert cut == full
    if swings:
        assert stopped > 0  # the loop was stopped early somewhere: the test compares something
