"""Per-vertex curvatures (singmesh.curvature, Mesh arrays, file point data) against closed forms.

Every check is at the mesh's own vertices: the expected values come from
the closed forms of the sphere, cylinder, torus, saddle and ellipsoid, not
from singmesh.  Sign convention: n = grad F / |grad F|, the mean curvature
is -div(n) / 2 (a sphere |p|^2 - r^2 has -1/r).
"""

from __future__ import annotations

import warnings

import meshio
import numpy as np
import pytest
import sympy as sp

import singmesh
from singmesh.cli import main
from singmesh.curvature import curvatures

X, Y, Z = sp.symbols("x y z")


def _mesh(text, box, coarse=8, fine=16):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return singmesh.mesh(text, box, coarse=coarse, fine=fine)


def _normal_curvature(m, d):
    """II(d, d) = -d^T H d / |g| at the vertices: the normal curvature along unit tangents d."""
    _, g, h = m.surface.jet(m.vertices)
    return -np.einsum("ni,nij,nj->n", d, h, d) / np.linalg.norm(g, axis=1)


def test_sphere_translated():
    c, r = np.array([0.1234, -0.2, 0.05]), 0.7
    m = _mesh(f"(x - {c[0]})^2 + (y + 0.2)^2 + (z - 0.05)^2 - {r}^2", ((-1, 1),) * 3)
    assert len(m.vertices) > 100
    assert np.allclose(m.gaussian_curvature, 1 / r**2, rtol=1e-9)
    assert np.allclose(m.mean_curvature, -1 / r, rtol=1e-9)
    assert np.allclose(m.principal_curvatures, -1 / r, rtol=1e-6)
    # Inward normal (F negated): the mean curvature changes sign, K does not.
    m = _mesh(f"{r}^2 - (x - {c[0]})^2 - (y + 0.2)^2 - (z - 0.05)^2", ((-1, 1),) * 3)
    assert np.allclose(m.mean_curvature, 1 / r, rtol=1e-9)
    assert np.allclose(m.gaussian_curvature, 1 / r**2, rtol=1e-9)


def test_cylinder_and_its_directions():
    r = 0.6
    m = _mesh(f"x^2 + y^2 - {r}^2", ((-1, 1), (-1, 1), (-0.77, 0.9)))
    assert np.allclose(m.gaussian_curvature, 0, atol=1e-9)
    assert np.allclose(m.mean_curvature, -1 / (2 * r), rtol=1e-9)
    k = m.principal_curvatures
    assert np.allclose(k[:, 0], 0, atol=1e-9) and np.allclose(k[:, 1], -1 / r, rtol=1e-9)
    d = m.principal_directions
    # k1 = 0 along the axis; k2 around it (tangent to the circle).
    assert np.allclose(np.abs(d[:, 0, 2]), 1, atol=1e-9)
    around = np.stack([-m.vertices[:, 1], m.vertices[:, 0], 0 * m.vertices[:, 0]], 1) / r
    assert np.allclose(np.abs(np.einsum("ni,ni->n", d[:, 1], around)), 1, atol=1e-6)


def test_torus_general_position():
    R, r = 1.0, 0.35
    c = np.array([0.013, -0.021, 0.037])
    text = f"((x-{c[0]})^2+(y+{-c[1]})^2+(z-{c[2]})^2+{R}^2-{r}^2)^2 - 4 {R}^2 ((x-{c[0]})^2+(y+{-c[1]})^2)"
    m = _mesh(text, ((-1.5, 1.5), (-1.5, 1.5), (-0.5, 0.5)), coarse=16, fine=16)
    p = m.vertices - c
    cos_v = (np.hypot(p[:, 0], p[:, 1]) - R) / r
    assert len(m.vertices) > 300 and cos_v.min() < -0.9 and cos_v.max() > 0.9
    assert np.allclose(m.gaussian_curvature, cos_v / (r * (R + r * cos_v)), rtol=1e-7, atol=1e-7)
    # Outward normal: k = -1/r around the tube, -cos v / (R + r cos v) around the axis.
    k_tube, k_axis = -1 / r, -cos_v / (R + r * cos_v)
    assert np.allclose(m.mean_curvature, (k_tube + k_axis) / 2, rtol=1e-7, atol=1e-7)
    k = m.principal_curvatures
    assert np.allclose(k[:, 0], np.maximum(k_tube, k_axis), atol=1e-6)
    assert np.allclose(k[:, 1], np.minimum(k_tube, k_axis), atol=1e-6)
    # The directions: tangent, orthonormal, and the normal curvature along
    # each is its principal curvature.
    d = m.principal_directions
    assert np.allclose(np.einsum("nci,ni->nc", d, m.normals), 0, atol=1e-9)
    assert np.allclose(np.einsum("nci,ndi->ncd", d, d), np.eye(2), atol=1e-9)
    for i in range(2):
        assert np.allclose(_normal_curvature(m, d[:, i]), k[:, i], atol=1e-6)


def test_saddle():
    m = _mesh("x y - z", ((-1.1, 0.9), (-0.95, 1.05), (-1.2, 1.2)))
    x, y = m.vertices[:, 0], m.vertices[:, 1]
    w = 1 + x**2 + y**2
    assert np.allclose(m.gaussian_curvature, -1 / w**2, rtol=1e-9)
    # n = (y, x, -1) / sqrt(w): -div(n) / 2 = x y / w^(3/2).
    assert np.allclose(m.mean_curvature, x * y / w**1.5, atol=1e-9)


def test_rotated_translated_ellipsoid_15_digits():
    rng = np.random.default_rng(12)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    t = np.array([0.0731, -0.1187, 0.0459])
    a, b, c = 0.9, 0.6, 0.35
    # u = q^T (p - t): the unrotated coordinates; F written out with 15-digit floats.
    u = [sum(q[i, j] * ((X, Y, Z)[i] - t[i]) for i in range(3)) for j in range(3)]
    expr = sp.expand(u[0] ** 2 / a**2 + u[1] ** 2 / b**2 + u[2] ** 2 / c**2 - 1)
    text = str(expr.xreplace({f: sp.Float(f"{float(f):.15g}") for f in expr.atoms(sp.Float)}))
    m = _mesh(text, ((-1.2, 1.2),) * 3, coarse=16, fine=16)
    assert len(m.vertices) > 300
    p = (m.vertices - t) @ q  # the mapped points, unrotated
    s = p[:, 0] ** 2 / a**4 + p[:, 1] ** 2 / b**4 + p[:, 2] ** 2 / c**4
    K = 1 / (a * b * c) ** 2 / s**2
    M = -(a**2 + b**2 + c**2 - (p**2).sum(1)) / (2 * (a * b * c) ** 2 * s**1.5)
    assert np.allclose(m.gaussian_curvature, K, rtol=1e-7)
    assert np.allclose(m.mean_curvature, M, rtol=1e-7)
    k = m.principal_curvatures
    assert np.allclose(k[:, 0] * k[:, 1], K, rtol=1e-6) and np.allclose(k.mean(1), M, rtol=1e-7)


@pytest.mark.parametrize("text, K, M", [
    ("sqrt(x^2 + y^2) - 0.8", 0.0, -1 / 1.6),
    ("exp(x^2 + y^2 + z^2) - exp(0.49)", 1 / 0.49, -1 / 0.7),
])
def test_non_polynomial(text, K, M):
    m = _mesh(text, ((-1, 1.1), (-1.05, 1), (-1, 1)))
    assert len(m.vertices) > 100
    assert np.allclose(m.gaussian_curvature, K, atol=1e-8)
    assert np.allclose(m.mean_curvature, M, rtol=1e-8)


def test_undefined_where_grad_vanishes():
    # The cone's apex (a singular vertex): NaN there, finite elsewhere.
    m = _mesh("x^2 + y^2 - z^2", ((-1, 1),) * 3)
    apex = np.nonzero(np.linalg.norm(m.vertices, axis=1) < 1e-12)[0]
    assert len(apex) == 1
    assert np.isnan(m.gaussian_curvature[apex]).all() and np.isnan(m.principal_curvatures[apex]).all()
    rest = np.ones(len(m.vertices), bool)
    rest[apex] = False
    assert np.isfinite(m.gaussian_curvature[rest]).all()
    # Away from the apex K = 0 (a cone is developable), M = -1 / (2 sqrt(2) rho) ... rho = sqrt(x^2+y^2):
    rho = np.hypot(m.vertices[rest, 0], m.vertices[rest, 1])
    assert np.allclose(m.gaussian_curvature[rest], 0, atol=1e-6 / rho.min() ** 2)
    assert np.allclose(np.abs(m.mean_curvature[rest]), 1 / (2 * np.sqrt(2) * rho), rtol=1e-7)
    # Points given directly: the apex (grad F = 0 exactly) is NaN.
    c = curvatures(m.surface, [[0.0, 0.0, 0.0], [0.6, 0.0, 0.6]])
    assert np.isnan(c.gaussian[0]) and np.isnan(c.mean[0]) and np.isfinite(c.mean[1])


def test_singular_curve_vertices_are_nan():
    # Whitney umbrella: the handle x = y = 0 is a curve of singular points.
    m = _mesh("x^2 - y^2 z", ((-1, 1),) * 3, fine=32)
    on_curve = np.hypot(m.vertices[:, 0], m.vertices[:, 1]) < 1e-12
    assert on_curve.sum() >= 5
    assert np.isnan(m.mean_curvature[on_curve]).all()
    assert np.isfinite(m.mean_curvature[~on_curve]).all()


@pytest.mark.parametrize("suffix", [".ply", ".vtk", ".vtu"])
def test_files_hold_curvature(tmp_path, suffix):
    m = _mesh("x^2 - y^2 z", ((-1, 1),) * 3, fine=32)
    back = meshio.read(m.write(tmp_path / f"umbrella{suffix}"))
    n = len(m.vertices)
    assert np.allclose(back.points[:n], m.vertices)
    for name, want in [("gaussian_curvature", m.gaussian_curvature), ("mean_curvature", m.mean_curvature),
                       ("k1", m.principal_curvatures[:, 0]), ("k2", m.principal_curvatures[:, 1])]:
        got = np.asarray(back.point_data[name])
        assert got.shape[0] == len(back.points)
        assert np.array_equal(got[:n], want, equal_nan=True)
        assert np.isnan(got[n:]).all()  # extra points of line cells: undefined
    # Without curvature: the arrays are left out.
    back = meshio.read(m.write(tmp_path / f"bare{suffix}", curvature=False))
    assert "k1" not in back.point_data


def test_obj_and_stl_take_none_and_still_read(tmp_path):
    m = _mesh("x^2 + y^2 + z^2 - 1", ((-1.5, 1.5),) * 3)
    for suffix in (".obj", ".stl"):
        back = meshio.read(m.write(tmp_path / f"s{suffix}"))
        assert len(back.points) >= len(m.vertices) and "k1" not in back.point_data


def test_cli_writes_curvature_by_default(tmp_path, capsys):
    out = tmp_path / "s.vtu"
    assert main(["mesh", "x^2 + y^2 + z^2 - 1", "-o", str(out), "--coarse", "8", "--fine", "8"]) == 0
    got = meshio.read(out).point_data
    assert np.allclose(got["gaussian_curvature"], 1.0, rtol=1e-9)
    out2 = tmp_path / "t.vtu"
    assert main(["mesh", "x^2 + y^2 + z^2 - 1", "-o", str(out2), "--coarse", "8", "--fine", "8",
                 "--no-curvature"]) == 0
    assert "gaussian_curvature" not in meshio.read(out2).point_data


def test_to_meshio_has_curvature():
    m = _mesh("x^2 - y^2 z", ((-1, 1),) * 3, fine=32)
    mm = m.to_meshio()
    n = len(m.vertices)
    assert len(mm.points) > n  # the handle's extra points
    assert np.array_equal(mm.point_data["k2"][:n], m.principal_curvatures[:, 1], equal_nan=True)
    assert np.isnan(mm.point_data["mean_curvature"][n:]).all()
