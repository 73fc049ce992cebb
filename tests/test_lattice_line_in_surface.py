"""A surface holding a lattice line, with a degenerate singular point on it.

F = a x y^5 + c x^6 + b z^5 + d x^4 y (fuzz s6-601, float coefficients)
holds the y-axis, a lattice line of every symmetric box, and is singular
only at the origin (its 4-jet is 0).  At each lattice point of the axis
F = 0 is an event on the x-line and on the z-line through it, each put in
a cell beside the point, and the face square holding both joins them with
a link of length zero.  Where that square faces a cell pruned for having
no zero inside (F < 0 in x < 0, z > 0 below the star), the star's cycle
broke there: on main the point had no vertex and no triangle, and the
star's faces were open.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import singmesh
from singmesh.facets.cycles import find_cycles

import meshcheck as mc


def _cycle_links():
    """One box's links: 0 -> 1 -> 2, then 3 -> 4 -> 0; events 2 and 3 at one lattice point."""
    src = np.array([0, 1, 3, 4])
    dst = np.array([1, 2, 4, 0])
    return np.zeros(4, np.int64), src, dst, np.array([10, 11, 12, 13])


def test_a_cycle_broken_at_a_lattice_point_is_joined_there():
    box, src, dst, square = _cycle_links()
    key = np.array([100, 101, 7, 7, 104])
    broken = find_cycles(box, src, dst, square, n_events=5)
    assert list(broken.broken_boxes) == [0] and len(broken) == 0
    joined = find_cycles(box, src, dst, square, n_events=5, key=key)
    assert len(joined.broken_boxes) == 0 and len(joined) == 1
    ev = list(joined.events)
    i = ev.index(0)
    assert ev[i:] + ev[:i] == [0, 1, 2, 3, 4]
    # The link 2 -> 3 lies in the square of the link arriving at 2.
    assert joined.squares[ev.index(2)] == 11


def test_a_cycle_is_not_joined_at_two_vertices():
    box, src, dst, square = _cycle_links()
    cycles = find_cycles(box, src, dst, square, n_events=5, key=np.array([100, 101, 7, 8, 104]))
    assert list(cycles.broken_boxes) == [0]


def test_a_cycle_is_not_joined_where_the_vertex_does_not_say_how():
    """Two cycles broken at one vertex (two sheets through it): which loose
    end goes with which is not known; the box stays broken (said, not guessed)."""
    box = np.zeros(8, np.int64)
    src = np.array([0, 1, 3, 4, 5, 6, 8, 9])
    dst = np.array([1, 2, 4, 0, 6, 7, 9, 5])
    key = np.array([100, 101, 7, 7, 104, 105, 106, 7, 7, 109])
    cycles = find_cycles(box, src, dst, np.arange(8), n_events=10, key=key)
    assert list(cycles.broken_boxes) == [0]


#: s6-601's polynomial and two of the family with 15-digit coefficients (on main
#: each point had no vertex, with 70, 181 and 184 open edges inside the box).
FAMILY = [
    "-0.775974137592386*x*y^5 + 0.121225544438783*x^6 - 1.33566962761821*z^5 + 2.14603450024772*x^4*y",
    "-1.6345987066878*x*y^5 + 1.49597498122393*x^6 + 1.9048924341648*z^5 - 2.35715933233309*x^4*y",
    "-0.959366159182247*x*y^5 + 0.362303276520019*x^6 + 1.22991188663485*z^5 + 0.573423208299041*x^4*y",
]


@pytest.mark.parametrize("text", FAMILY)
def test_the_point_on_the_lattice_line_is_a_vertex_with_triangles(text):
    box = np.array([(-2.0, 2.0), (-0.5, 0.5), (-0.5, 0.5)])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = singmesh.mesh(text, box, coarse=8, fine=64)
    # The origin is singular (every term has degree 5 or more).
    i = int(np.argmin(np.abs(m.vertices).max(axis=1)))
    assert np.abs(m.vertices[i]).max() <= 1e-12
    assert mc.fans_at(m.faces, i) >= 1 and mc.fans_are_closed(m.faces, i)
    # Its star's faces (0.125 from it) are closed: no open edge that near.
    open_ = np.array(mc.boundary_edges_off_box(m.vertices, m.faces, box), np.int64).reshape(-1, 2)
    assert (np.abs(m.vertices[open_]).max(axis=2) > 0.15).all()
