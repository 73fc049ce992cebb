"""``singmesh.mesh``: the pipeline from a surface to a :class:`Mesh`."""

from __future__ import annotations

import time

import numpy as np

from singmesh.boxes.edges import compute_events
from singmesh.boxes.faces import face_links
from singmesh.boxes.octree import subdivide
from singmesh.facets.assemble import assemble
from singmesh.facets.cycles import box_links, find_cycles

from . import tolerances as tol
from .errors import SurfaceError
from .mesh import Mesh
from .surface import Surface

DEFAULT_BOX = ((-2.0, 2.0), (-2.0, 2.0), (-2.0, 2.0))


def _level(cells: int, what: str) -> int:
    if not isinstance(cells, (int, np.integer)) or cells < 1 or cells & (cells - 1):
        raise SurfaceError(f"{what} must be a power of two (boxes per axis), not {cells!r}")
    level = int(cells).bit_length() - 1
    if level > tol.MAX_LEVEL:
        raise SurfaceError(f"{what} = {cells} is over the limit of {1 << tol.MAX_LEVEL} boxes per axis")
    return level


def check_box(box) -> np.ndarray:
    """The box as a (3, 2) float array, or SurfaceError naming what is wrong."""
    try:
        b = np.array(box, dtype=float)
    except (TypeError, ValueError):
        raise SurfaceError(f"a box is three (lo, hi) pairs, not {box!r}") from None
    if b.shape == (6,):
        b = b.reshape(3, 2)
    if b.shape != (3, 2):
        raise SurfaceError(f"a box is three (lo, hi) pairs, not an array of shape {b.shape}")
    if not np.isfinite(b).all():
        raise SurfaceError("the box has a non-finite bound")
    for axis, (lo, hi) in zip("xyz", b):
        if hi < lo:
            raise SurfaceError(f"the box is inverted in {axis}: {lo:g} > {hi:g}")
        if hi == lo:
            raise SurfaceError(f"the box is empty in {axis}: {lo:g} = {hi:g}")
    return b


def mesh(surface, box=DEFAULT_BOX, *, coarse: int = 32, fine: int = 256, **params) -> Mesh:
    """Mesh the real surface F = 0 inside ``box``.

    Parameters
    ----------
    surface : str, sympy expression or Surface
        The equation, e.g. ``"4(x^2+y^2+z^2) + 16 x y z - 1"``.
    box : three (lo, hi) pairs
        The region meshed; the mesh is cut at its faces.
    coarse : int, power of two
        Boxes per axis of the uniform subdivision every box goes through:
        it sets the size of the largest triangles (about box / coarse).
    fine : int, power of two, >= coarse
        Boxes per axis at the deepest refinement, used only where a box
        is not simple (near singular points, tangencies, thin features).
    **params
        Values of named parameters of the equation.

    Returns
    -------
    Mesh

    Raises
    ------
    SurfaceError
        Bad equation, box or resolution.
    """
    t0 = time.perf_counter()
    surf = Surface.parse(surface, **params)
    b = check_box(box)
    coarse_level = _level(coarse, "coarse")
    fine_level = _level(fine, "fine")
    if fine_level < coarse_level:
        raise SurfaceError(f"fine ({fine}) must be at least coarse ({coarse})")

    tree = subdivide(surf.coeffs, b, coarse_level, fine_level)
    events = compute_events(surf, tree)
    links = face_links(tree, events)
    bl = box_links(links)
    cycles = find_cycles(*bl, n_events=len(events.key))
    vertices, faces, _ = assemble(cycles.offsets, cycles.events, events.key, events.point,
                                  surf.gradient, project=lambda p: project_to_surface(surf, p))
    stats = {
        "leaves": len(tree.level),
        "non_simple_leaves": int((~tree.simple).sum()),
        "levels": np.bincount(tree.level).tolist() if len(tree.level) else [],
        "events": len(events.key),
        "cycles": len(cycles),
        "broken_boxes": len(cycles.broken_boxes),
        "ambiguous_squares": int(links.ambiguous.sum()),
        "inconsistent_squares": int(links.inconsistent.sum()),
        "time": time.perf_counter() - t0,
    }
    return Mesh(vertices=vertices, faces=faces, surface=surf, box=b, stats=stats)


def project_to_surface(surface: Surface, points: np.ndarray, iterations: int = 8) -> np.ndarray:
    """Newton steps along grad F from points near the surface onto it."""
    p = np.array(points, dtype=float)
    for _ in range(iterations):
        f = surface(p)
        g = surface.gradient(p)
        gg = np.einsum("ij,ij->i", g, g)
        step = np.where(gg > 0, f / np.where(gg > 0, gg, 1), 0.0)
        p = p - step[:, None] * g
    return p
