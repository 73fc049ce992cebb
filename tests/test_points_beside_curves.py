"""Isolated singular points a few cells from a curve of singular points.

A product g * h has a double curve along g = h = 0, and a singular point
wherever g has one (F = g h, grad F = h grad g there).  A node or an A2
point of g a cell or two from the plane h = 0 is such a point beside the
curve (fuzz s2-66: an A2 of a cubic 1.1 fine cells from the crossing of a
plane).  The point search used to leave every box within three cells of a
traced curve alone, and those points were dropped without a word.  Each
must be reported, and be a vertex of the mesh or named in a
SingularPointWarning.

The point is known by construction (g's singular point, rotated by a float
rotation with 17-digit coefficients), not from the mesher.
"""
from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import singmesh
from singmesh import SingularPointWarning

BOX = ((-1.0, 1.0),) * 3
FINE = 64
CELL = 2.0 / FINE


def _case(seed: int, cells: float, kind: str) -> tuple[str, np.ndarray]:
    """F = g * h: g has a node or A2 point at p (float-rotated), h a plane ``cells`` fine cells from p."""
    rng = np.random.default_rng(seed)
    q = Rotation.random(random_state=seed).as_matrix()
    p = rng.uniform(-0.5, 0.5, 3)
    u = ["(" + " + ".join(f"{float(q[i, j])!r}*({'xyz'[j]} - {float(p[j])!r})" for j in range(3)) + ")"
         for i in range(3)]
    g = {"node": f"{u[0]}^2 + {u[1]}^2 - {u[2]}^2 + 0.7*{u[0]}^3",
         "A2": f"{u[0]}^2 - {u[1]}^2 + {u[2]}^3"}[kind]
    n = rng.normal(size=3)
    n /= np.linalg.norm(n)
    h = " + ".join(f"{float(n[j])!r}*({'xyz'[j]} - {float(p[j])!r})" for j in range(3)) + f" - {cells * CELL!r}"
    return f"({g})*({h})", p


CASES = [(kind, cells, seed) for kind in ("node", "A2") for cells in (0.3, 0.6, 1.3, 2.5, 4.0) for seed in (1, 2)]


@pytest.mark.parametrize("kind, cells, seed", CASES, ids=[f"{k}-{c}-s{s}" for k, c, s in CASES])
def test_point_beside_a_curve_is_not_dropped(kind, cells, seed):
    text, p = _case(seed, cells, kind)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        m = singmesh.mesh(text, box=BOX, coarse=8, fine=FINE)
    assert len(m.singular_curves), "the double curve g = h = 0 is traced"
    at = [s for s in m.singularities if np.linalg.norm(np.asarray(s.point) - p) < 1e-7]
    assert at, f"{kind} point at {p.tolist()} ({cells} cells from the curve) not reported"
    assert str(at[0].classification).startswith("A1" if kind == "node" else "A2")
    named = [w for w in caught if issubclass(w.category, SingularPointWarning)
             and "not mesh vertices" in str(w.message)]
    if at[0].vertex is None:
        assert named, "a point that is not a mesh vertex is said in a SingularPointWarning"
    else:
        assert np.linalg.norm(m.vertices[at[0].vertex] - p) < 1e-7
