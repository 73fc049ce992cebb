"""Newton from beside a traced curve ending on an arc of the locus that was not traced.

F = g1 * g2 (a cubic times a quadric cone through the origin, fuzz s1-494)
has a double curve along g1 = g2 = 0 of degree 6: arcs that come into the
box [-2, 2] x [-1, 1] x [-0.5, 0.5] through its bottom or top face and turn
back within half its height, a few fine cells from the arc through the
origin.  Those short arcs are not traced (the box is four times wider than
tall, and the trace's least extent is a number of the largest cells), and
the mesher says so.  The point search runs Newton from the boxes within
CURVE_AVOID cells of the traced arc (for isolated points beside it), and
some starts there end on an untraced arc: every one of those ends was
reported as an isolated non-simple point (33 to 49 of them, a few cells
apart, each with a star: close vertex pairs and open edges).  The straight
curve test (singular points 4 and 8 cells along the kernel) misses an arc
that turns within 8 cells; tracing it (as for high A_k) follows it.

Checked without the mesher: a reported point where both factors vanish is
on the double curve (not isolated); close vertex pairs and the edges of
more than two triangles from the faces.  Float rotations by 1 and 3 degrees
with 17-digit coefficients and a small shift, as users give them.
"""
from __future__ import annotations

import functools
import warnings

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import singmesh

import meshcheck as mc

BOX = ((-2.0, 2.0), (-1.0, 1.0), (-0.5, 0.5))
G1 = "8*X^3 + 1/2*X^2*Y - 6/7*X - 2/7*Z^2"
G2 = "-1/2*X*Y + 3*X*Z - 9*Y^2 - 1/8*Y"


def _case(seed: int, degrees: float) -> tuple[str, list[str]]:
    """F = g1 * g2 in coordinates rotated by ``degrees`` about a random axis and shifted."""
    rng = np.random.default_rng(seed)
    axis = Rotation.random(random_state=seed).as_rotvec()
    q = Rotation.from_rotvec(np.radians(degrees) * axis / np.linalg.norm(axis)).as_matrix()
    o = rng.uniform(-0.01, 0.01, 3) if degrees else np.zeros(3)
    u = {"XYZ"[i]: "(" + " + ".join(f"{float(q[i, j])!r}*({'xyz'[j]} - {float(o[j])!r})" for j in range(3)) + ")"
         for i in range(3)}
    g = [s.replace("X", u["X"]).replace("Y", u["Y"]).replace("Z", u["Z"]) for s in (G1, G2)]
    return f"({g[0]})*({g[1]})", g


def _value(expr: str, p: np.ndarray) -> np.ndarray:
    x, y, z = np.asarray(p, float).reshape(-1, 3).T
    return eval(expr.replace("^", "**"), {"x": x, "y": y, "z": z})  # noqa: S307 - our own polynomial text


def _distance(expr: str, p: np.ndarray, h: float = 1e-7) -> np.ndarray:
    """|g| / |grad g| by central differences: the distance to g = 0 near it."""
    p = np.asarray(p, float).reshape(-1, 3)
    grad = np.stack([(_value(expr, p + h * e) - _value(expr, p - h * e)) / (2 * h) for e in np.eye(3)], axis=1)
    return np.abs(_value(expr, p)) / np.maximum(np.linalg.norm(grad, axis=1), 1e-300)


CASES = [(0, 0.0), (1, 1.0), (4, 1.0), (5, 1.0), (8, 1.0), (1, 3.0), (5, 3.0)]


@functools.lru_cache(maxsize=None)
def _mesh(seed: int, degrees: float):
    text, g = _case(seed, degrees)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return singmesh.mesh(text, box=BOX, coarse=8, fine=64), g


@pytest.mark.parametrize("seed, degrees", CASES, ids=[f"s{s}-{d:g}deg" for s, d in CASES])
def test_no_points_on_an_untraced_arc_of_the_double_curve(seed, degrees):
    m, g = _mesh(seed, degrees)
    at = np.array([s.point for s in m.singularities]).reshape(-1, 3)
    on = (_distance(g[0], at) < 1e-6) & (_distance(g[1], at) < 1e-6)
    assert not on.any(), f"{int(on.sum())} points reported on the double curve g1 = g2 = 0, first {at[on][0].tolist()}"
    used = np.unique(np.asarray(m.faces))
    assert mc.close_vertex_pairs(np.asarray(m.vertices)[used], BOX) == 0


ODD = {(1, 1.0): "the arc x ~ 0.33 (z > 0) is traced here, and 25 edges along it have 3 triangles: "
                 "its tube, not a point (found with this test, not fixed)"}


@pytest.mark.parametrize("seed, degrees", [pytest.param(s, d, marks=pytest.mark.xfail(strict=True, reason=ODD[s, d]))
                                           if (s, d) in ODD else (s, d) for s, d in CASES],
                         ids=[f"s{s}-{d:g}deg" for s, d in CASES])
def test_edges_on_the_double_curve_have_an_even_count(seed, degrees):
    m, _ = _mesh(seed, degrees)
    odd = [k for k in mc.edge_counts(m.faces).values() if k > 2 and k % 2]
    assert not odd, f"{len(odd)} edges of an odd number (> 2) of triangles"
