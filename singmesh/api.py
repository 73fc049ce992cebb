"""``singmesh.mesh``: the pipeline from a surface to a :class:`Mesh`."""

from __future__ import annotations

import time
import warnings
from dataclasses import replace

import numpy as np

from singmesh.boxes.edges import compute_events
from singmesh.boxes.faces import face_links
from singmesh.boxes.octree import refine_stars, subdivide
from singmesh.facets.assemble import assemble
from singmesh.facets.cycles import box_links, find_cycles
from singmesh.facets.fans import insert_link_nodes, sector_polygons
from singmesh.facets.stars import group_stars, shrink_cubes, star_cubes, stray_cycles
from singmesh.skeleton.curves import skeleton_links
from singmesh.skeleton.directions import skeleton_directions
from singmesh.skeleton.singular import singular_points, skeleton_nodes

from . import tolerances as tol
from .errors import SurfaceError
from .mesh import Mesh, SingularPointWarning
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

    t_sing = time.perf_counter()
    # A curve of singular points (the classifier finds an infinite Milnor
    # number on it) is not meshed as points: ``overflow``.
    points, overflow = singular_points(surf, b, level=min(fine_level, tol.SINGULAR_LEVEL))
    kinds = [sp.classification for sp in points]
    t_sing = time.perf_counter() - t_sing
    cell = (b[:, 1] - b[:, 0]) / (1 << fine_level)
    # First pass: the boxes at each singular point go to the fine level.
    cubes = np.array([[sp.point - cell, sp.point + cell] for sp in points]).reshape(-1, 2, 3)
    tree = subdivide(surf.coeffs, b, coarse_level, fine_level, keep_splitting=None if overflow else cubes)
    events = compute_events(surf, tree)
    links = face_links(tree, events)
    centres = np.array([sp.point for sp in points]).reshape(-1, 3)
    expected = [getattr(sp.classification, "branches", None) for sp in points]
    cubes = star_cubes(tree, links, centres) if len(points) and not overflow else None
    first = tree
    for attempt in range(tol.STAR_RETRIES + 1):
        if cubes is not None:
            # Second pass: each star becomes a cube around its point, large
            # enough to hold the boxes that failed the simplicity test
            # there; the leaves meeting its boundary go to the fine level.
            tree = refine_stars(first, cubes)
            events = compute_events(surf, tree)
            links = face_links(tree, events)
        group, stars, clashes = group_stars(tree, cubes, centres)
        cycles = find_cycles(*box_links(links, group), n_events=len(events.key))
        # A star too large for the cone over its boundary to be the surface
        # in it joins branches: fewer link cycles than the classifier's
        # branches.  Those stars shrink by half and are meshed again.
        few = _short_stars(cycles, stars, expected)
        if not few or attempt == tol.STAR_RETRIES:
            break
        cubes = shrink_cubes(first, cubes, centres, few)

    offsets, keys, pts, apex, branches = _polygons(surf, tree, events, links, cycles, stars, points)
    vertices, faces, vkeys = assemble(offsets, keys, pts, surf.gradient,
                                      project=lambda q: project_to_surface(surf, q), apex=apex)
    # Where two axis skeletons meet (normal along an axis), for reference.
    nodes, node_axes = skeleton_nodes(surf, b, level=min(fine_level, tol.SKELETON_NODE_LEVEL))
    singular = []
    for i, sp in enumerate(points):
        where = np.nonzero(vkeys == _point_key(i))[0]
        singular.append(replace(sp, vertex=int(where[0]) if len(where) else None,
                                branches=branches.get(i, 0), classification=kinds[i]))
    stats = {
        "leaves": len(tree.level),
        "non_simple_leaves": int((~tree.simple).sum()),
        "levels": np.bincount(tree.level).tolist() if len(tree.level) else [],
        "events": len(events.key),
        "cycles": len(cycles),
        "broken_boxes": len(cycles.broken_boxes),
        "ambiguous_squares": int(links.ambiguous.sum()),
        "inconsistent_squares": int(links.inconsistent.sum()),
        "singular_search_time": t_sing,
        "singular_locus_not_isolated": bool(overflow),
        "overlapping_stars": len(clashes),
        "time": time.perf_counter() - t0,
    }
    m = Mesh(vertices=vertices, faces=faces, surface=surf, box=b, singularities=singular, stats=stats,
             skeleton_nodes=nodes, skeleton_node_axes=node_axes)
    # Nothing is dropped silently: a point with branches that is not a
    # vertex, or whose fans differ from its branches, is said aloud.
    for note in m.singular_point_warnings():
        warnings.warn(note, SingularPointWarning, stacklevel=2)
    return m


def _short_stars(cycles, stars: dict, expected: list) -> list[int]:
    """Points whose star has fewer link cycles than the branches they have."""
    counts = dict(zip(*np.unique(cycles.box, return_counts=True))) if len(cycles) else {}
    return [i for box, i in stars.items() if expected[i] is not None and counts.get(box, 0) < expected[i]]


def _point_key(i: int) -> int:
    """Vertex key of singular point i: below all event keys (which are >= 0)."""
    return -1 - i


def _square_bounds(tree, square):
    """(axis, lo, hi) in space of a contact square row (n, plane, u0, v0, size)."""
    n, plane, u0, v0, size = (int(c) for c in square)
    lo = np.zeros(3, np.int64)
    lo[n], lo[(n + 1) % 3], lo[(n + 2) % 3] = plane, u0, v0
    hi = lo.copy()
    hi[(n + 1) % 3] += size
    hi[(n + 2) % 3] += size
    return n, tree.lattice_to_space(lo), tree.lattice_to_space(hi)


def _polygons(surf, tree, events, links, cycles, stars, points):
    """Facet polygons (offsets, keys, points, apex flags) and branch counts.

    Plain boxes give one polygon per cycle; the star of a singular point
    gives sectors fanning into it (:mod:`singmesh.facets.fans`).
    """
    sizes = np.diff(cycles.offsets)
    plain = ~np.isin(cycles.box, list(stars))
    plain |= stray_cycles(cycles, events, stars, [getattr(sp.classification, "branches", None) for sp in points])
    ev = cycles.events
    owner = np.repeat(np.arange(len(cycles)), sizes)
    keep = plain[owner]
    parts_keys = [events.key[ev[keep]]]
    parts_pts = [events.point[ev[keep]]]
    parts_sq = [cycles.squares[keep]]
    parts_sizes = [sizes[plain]]
    apex = [np.zeros(plain.sum(), bool)]
    branches = {}
    splits = {}
    next_key = int(events.key.max()) + 1 if len(events.key) else 0
    for c in np.nonzero(~plain)[0]:
        i = stars[cycles.box[c]]
        p = points[i].point
        span = slice(cycles.offsets[c], cycles.offsets[c + 1])
        cyc = ev[span]
        cyc_keys, cyc_pts = events.key[cyc], events.point[cyc]
        squares = [_square_bounds(tree, links.square[q]) for q in cycles.squares[span]]
        spokes = skeleton_links(surf, p, cyc_pts, squares, skeleton_directions(surf.hessian(p)))
        polys, split, next_key = sector_polygons(_point_key(i), p, cyc_keys, cyc_pts, spokes, next_key,
                                                 cycle_squares=cycles.squares[span])
        splits.update(split)
        for k, q in polys:
            parts_sq.append(np.full(len(k), -1, np.int64))
            parts_keys.append(k)
            parts_pts.append(q)
            parts_sizes.append([len(k)])
            apex.append([True])  # large ones fan from their first vertex, p or a traced point
        branches[i] = branches.get(i, 0) + 1
    sizes = np.concatenate([np.asarray(s, np.int64) for s in parts_sizes])
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    offsets, keys, pts = insert_link_nodes(offsets, np.concatenate(parts_keys), np.concatenate(parts_pts),
                                           np.concatenate(parts_sq), splits)
    return offsets, keys, pts, np.concatenate([np.asarray(a, bool) for a in apex]), branches


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
