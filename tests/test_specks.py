"""Closed specks between two sheets closer than a cell, and tiny real pieces.

Where two sheets pass within a cell of each other, a lattice point between
them with all its neighbours outside used to come out as a closed speck of
8 triangles: a piece the surface does not have.  The checks here count the
pieces of the mesh themselves (vertex-connected triangles) and place the
real ones from the equation, not from the mesher.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

import meshcheck as mc
import singmesh
from test_curves import float_rotated

BOX1 = ((-1.0, 1.0),) * 3


def pieces(vertices: np.ndarray, faces: np.ndarray) -> list[np.ndarray]:
    """The triangles of each vertex-connected piece of the mesh."""
    n = len(vertices)
    a, b = faces.ravel(), np.roll(faces, -1, axis=1).ravel()
    k, label = connected_components(coo_matrix((np.ones(len(a)), (a, b)), shape=(n, n)), directed=False)
    lab = label[faces[:, 0]]
    return [np.nonzero(lab == c)[0] for c in np.unique(lab)]


def mesh_quiet(text, box):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return singmesh.mesh(text, box)


@pytest.mark.parametrize("seed", [3, 5])
@pytest.mark.parametrize("gap", ["0.503", "0.5021"])
def test_no_specks_between_a_sphere_and_a_plane_closer_than_a_cell(seed, gap):
    # The plane z = gap passes 0.003 and 0.0021 above the sphere of radius
    # 1/2 (the cell is 1/128): between them F = S P < 0, above and below
    # F > 0.  Float-rotated, 52 to 62 closed specks of 8 triangles came
    # out round lattice points in that slab.
    text = float_rotated(f"(x^2 + y^2 + z^2 - 0.25) (z - {gap})", seed)
    m = mesh_quiet(text, BOX1)
    V, T = m.vertices, m.faces
    assert mc.boundary_edges_off_box(V, T, np.array(BOX1)) == []
    small_closed = [p for p in pieces(V, T) if len(p) < 200 and not mc.boundary_edges(T[p])]
    assert small_closed == [], f"{len(small_closed)} closed specks"


@pytest.mark.parametrize("scale", [(1, 1, 1), (4, 1, 9)])
def test_a_tiny_closed_piece_of_the_surface_stays(scale):
    # A sphere (an ellipsoid) 1.5 cells across next to a large sphere: a
    # real piece of F = 0, with a minimum of F inside; it must not be
    # taken for a speck.
    c = np.array([0.704125, 0.1008625, -0.046375])
    a, b, d = scale
    text = (f"(x^2 + y^2 + z^2 - 0.25)((x - {c[0]})^2/{a} + (y - {c[1]})^2/{b} + (z - {c[2]})^2/{d} - 0.000036)")
    m = mesh_quiet(text, BOX1)
    parts = pieces(m.vertices, m.faces)
    assert len(parts) == 2
    small = min(parts, key=len)
    p = m.vertices[np.unique(m.faces[small])]
    q = ((p - c) ** 2 / np.array([a, b, d], float)).sum(axis=1)
    assert np.allclose(q, 0.000036, rtol=1e-6)
