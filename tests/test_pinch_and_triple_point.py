"""A pinch point and a triple point on one double line.

F = (u^2 - v^2 w) * P: a Whitney umbrella (double line u = v = 0, w > 0,
pinch point at the origin, isolated real line w < 0) times a plane P that
crosses the double line at w = 0.5, a triple point, float-rotated with
17-digit coefficients and shifted.  The rails of the umbrella's sheets turn
back along the line round the pinch point; a rail that did so and also went
out past the triple point along another branch and back kept that excursion
(fuzz s4-850): its edges had six triangles.  Every edge of the mesh lies on
at most two sheets here (the third sheet meets the line at one vertex).

Checked from the faces: no edge of more than four triangles, none of an odd
number above two, edges of four on the double line or on umbrella = P = 0
(from the formulas, not the mesher), no open edge inside the box, no close
vertex pairs.
"""
from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import singmesh

import meshcheck as mc

BOX = ((-1.0, 1.0),) * 3
FINE = 64
CELL = 2.0 / FINE
TRIPLE = 0.5


def _case(seed: int):
    """The text of F, the rotation q and the shift o (u = q (x - o))."""
    rng = np.random.default_rng(seed)
    q = Rotation.random(random_state=seed).as_matrix()
    o = rng.uniform(-0.2, 0.2, 3)
    u = ["(" + " + ".join(f"{float(q[i, j])!r}*({'xyz'[j]} - {float(o[j])!r})" for j in range(3)) + ")"
         for i in range(3)]
    n = rng.normal(size=3)
    n /= np.linalg.norm(n)
    if abs(n[2]) < 0.4:  # crossing the double line, not nearly along it
        n[2] = 0.4 * np.sign(n[2] or 1.0)
        n /= np.linalg.norm(n)
    plane = " + ".join(f"{float(n[j])!r}*{u[j]}" for j in range(3)) + f" - {float(n[2] * TRIPLE)!r}"
    return f"({u[0]}^2 - {u[1]}^2*{u[2]})*({plane})", q, o, n


OPEN = {
    2: "the branches of umbrella = P = 0 run 4 cells from the double line between the pinch and the triple "
       "point: 88 edges of 6 and 8 triangles where their tubes meet (not fixed)",
    3: "two branches of umbrella = P = 0 are not traced (the mesher says so): 5 edges of 6 triangles there",
}


@pytest.mark.parametrize("seed", [pytest.param(s, marks=pytest.mark.xfail(strict=True, reason=OPEN[s]))
                                  if s in OPEN else s for s in range(1, 9)])
def test_pinch_and_triple_point_on_one_double_line(seed):
    text, q, o, n = _case(seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = singmesh.mesh(text, box=BOX, coarse=8, fine=FINE)
    v = np.asarray(m.vertices)
    counts = mc.edge_counts(m.faces)
    many = [k for k in counts.values() if k > 4]
    assert not many, f"{len(many)} edges of more than four triangles ({sorted(set(many))})"
    odd = [k for k in counts.values() if k > 2 and k % 2]
    assert not odd, f"{len(odd)} edges of an odd number of triangles"
    four = np.array([e for e, k in counts.items() if k == 4]).reshape(-1, 2)
    mid = (v[four[:, 0]] + v[four[:, 1]]) / 2
    u = (mid - o) @ q.T
    on_line = np.hypot(u[:, 0], u[:, 1]) <= 0.25 * CELL
    umb = u[:, 0] ** 2 - u[:, 1] ** 2 * u[:, 2]
    grad = np.stack([2 * u[:, 0], -2 * u[:, 1] * u[:, 2], -u[:, 1] ** 2], axis=1)
    on_cut = (np.abs(umb) <= 0.25 * CELL * np.linalg.norm(grad, axis=1)) & (np.abs(u @ n - n[2] * TRIPLE) <= 0.25 * CELL)
    assert (on_line | on_cut).all(), f"{int((~(on_line | on_cut)).sum())} edges of four triangles off the double curves"
    open_ = mc.boundary_edges_off_box(v, m.faces, BOX)
    assert not open_, f"{len(open_)} open edges inside the box"
    assert mc.close_vertex_pairs(v[np.unique(np.asarray(m.faces))], BOX) == 0
