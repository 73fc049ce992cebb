"""``singmesh.mesh``: the pipeline from a surface to a :class:`Mesh`."""

from __future__ import annotations

import time
import warnings
from dataclasses import replace
from functools import partial

import numpy as np
from scipy.spatial import cKDTree
from threadpoolctl import ThreadpoolController

from singmesh.boxes.edges import compute_events
from singmesh.boxes.faces import face_links, leaf_sides, rail_links
from singmesh.boxes.octree import Octree, refine_stars, subdivide
from singmesh.boxes.sizing import CurvatureSizing, sizing_levels
from singmesh.facets.assemble import assemble
from singmesh.facets.cycles import box_links, find_cycles, lens_leaves
from singmesh.facets.polygons import add_strips, curve_key0, facet_polygons, point_key
from singmesh.facets.records import curve_graph, curve_records
from singmesh.facets.stars import group_stars, part_branches, short_stars, shrink_cubes, star_cubes
from singmesh.facets.bubbles import lattice_specks, without_faces
from singmesh.facets.coarsen import coarsen_crease_mesh
from singmesh.facets.domain_edges import on_domain_end, reach_domain_edges
from singmesh.facets.tubes import curve_samples, faces_of, tube_leaves, tube_regions, untraced_points
from singmesh.facets.improve import improve_mesh
from singmesh.skeleton.creases import crease_curves, crease_gap, merge_curve_sets
from singmesh.skeleton.singular import singular_points, skeleton_nodes
from singmesh.skeleton.singular_curves import singular_curves
from singmesh.skeleton.tips import root_creases, tip_points

from . import tolerances as tol
from . import topology
from .errors import SurfaceError
from .memory import Budget, MemoryBudgetError, parse_size
from .mesh import UNRESOLVED_EMPTY, CreaseWarning, EmptyMeshWarning, Mesh, SingularPointWarning, cuspidal_crease_refusal
from .squarefree import squarefree
from .surface import CHILD_OFFSETS, Surface

DEFAULT_BOX = ((-2.0, 2.0), (-2.0, 2.0), (-2.0, 2.0))


def _level(cells: int, what: str) -> int:
    if (not isinstance(cells, (int, np.integer)) or isinstance(cells, (bool, np.bool_))
            or cells < 1 or cells & (cells - 1)):
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
    # Outside these scales the bounds and Newton steps, whose tolerances
    # are partly absolute, lose the surface (an empty mesh, not an error).
    size = float(np.abs(b).max())
    if size > tol.BOX_MAX_COORD:
        raise SurfaceError(f"the box reaches {size:g}, over the limit of {tol.BOX_MAX_COORD:g}: "
                           "scale the equation (x -> s x) to a smaller box")
    side = b[:, 1] - b[:, 0]
    for axis, w in zip("xyz", side):
        if w < tol.BOX_MIN_SIDE:
            raise SurfaceError(f"the box is {w:g} wide in {axis}, under the limit of {tol.BOX_MIN_SIDE:g}: "
                               "scale the equation (x -> s x) to a larger box")
        if w < tol.BOX_MIN_RELATIVE_SIDE * size:
            raise SurfaceError(f"the box is {w:g} wide in {axis}, too narrow for its distance {size:g} from 0 "
                               f"(at least {tol.BOX_MIN_RELATIVE_SIDE:g} of it): shift the equation to 0")
    return b


def check_defined(surf: Surface, box: np.ndarray) -> None:
    """SurfaceError if F is certainly undefined on the whole box (``sqrt(-1 - x^2)``),
    or 0 / 0 along the zeros of a divisor in it (``sin(x) / x``)."""
    if surf.undefined_everywhere(box):
        where = "[" + ", ".join(f"{lo:g}..{hi:g}" for lo, hi in box) + "]"
        raise SurfaceError(f"F = {surf} is undefined everywhere in the box {where} "
                           "(e.g. sqrt or log of a negative number)")
    removable = surf.removable_singularity(box)
    if removable is not None:
        # Its bounds are infinite on every box meeting the divisor's zeros:
        # they would all go to the fine level, with NaN lattice values, and
        # the mesh would have a gap along them (or worse, off the lattice).
        d, p = removable
        raise SurfaceError(f"F = {surf} is 0/0 where {d} = 0 in the box (e.g. at ({p[0]:.6g}, {p[1]:.6g}, "
                           f"{p[2]:.6g})): a removable singularity, F's value there is a limit, which singmesh "
                           "does not take; write F without that division, or use a box that does not meet "
                           f"{d} = 0")


def mesh(surface, box=DEFAULT_BOX, *, coarse: int = 32, fine: int = 256, improve: bool = True,
         size: str = "uniform",
         min_edge: float | None = None, max_edge: float | None = None, chord: float | None = None,
         max_memory=None, **params) -> Mesh:
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
        Where two isolated singular points are closer than
        ``STAR_MIN_GAP`` such boxes, it is doubled until they are not
        (each point needs a cube of its own), at most ``STAR_MAX_RAISE``
        times; where two creases (sharp edges) are closer than
        ``CREASE_MIN_GAP`` such boxes, the same, at most
        ``CREASE_MAX_RAISE`` times (``Mesh.stats["crease_gap"]``: their
        distance in boxes at the level used); where two singular curves
        are closer than that, once, if once parts them;
        ``Mesh.stats["fine"]`` is the value used.
    improve : bool
        Make the triangles well-shaped (:mod:`singmesh.facets.improve`):
        edge flips and vertices moved on the surface, keeping the singular
        points, the curves, the box's corners and the topology.  False
        gives the triangles as the boxes make them, vertices at the
        crossings with the lattice.
    size : {"uniform", "curvature"}
        ``"uniform"``: triangles about box / ``coarse`` wherever the surface
        is simple.  ``"curvature"``: triangles sized by the surface's
        curvature, edges about ``e = sqrt(8 chord / k)`` long where
        ``k = max(|k1|, |k2|)`` (an arc of curvature k is off its chord of
        length e by about k e^2 / 8), clamped to [min_edge, max_edge]:
        fewer triangles on flat parts, more on curved ones, for about the
        same maximal deviation from the surface.  ``coarse`` is then not
        used (``max_edge`` sets the largest boxes); singular points and
        curves keep their own refinement down to ``fine``.
    min_edge, max_edge : float, optional
        With ``size="curvature"``: the shortest and longest edges wanted,
        as fractions of the box's longest side (edges are about as long as
        the boxes holding them, which are halved level by level: the
        sizes used are the powers of two within the limits).  Defaults
        ``1 / fine`` and ``1 / 8``.
    chord : float, optional
        With ``size="curvature"``: the chord tolerance delta, a fraction of
        the box's longest side (default ``1e-3``).
    max_memory : float or str, optional
        Refuse (:class:`singmesh.memory.MemoryBudgetError`, a SurfaceError)
        a request whose estimated peak resident size is over this many
        bytes (or ``"512M"``, ``"2G"``); the machine's available memory is
        always a limit.  The estimate (:mod:`singmesh.memory`) is checked
        as the octree grows, level by level, before the boxes are made.
        ``Mesh.stats["memory_estimate"]``: the largest estimate seen.
    **params
        Values of named parameters of the equation; one it does not use
        is refused (SurfaceError), as a misspelt name would be.

    Returns
    -------
    Mesh

    Raises
    ------
    SurfaceError
        Bad equation, box or resolution.
    """
    # The matrix products here are many small ones (Bernstein tensors of a
    # few hundred coefficients, 4 x 3 Jacobians): BLAS threads only add
    # hand-offs, and on a machine shared with other work they compete for
    # the cores (Endrass octic: 32.9 s with two BLAS threads on two cores,
    # 29.9 s with one).
    # Non-polynomial F are NaN outside their domain and infinite at poles:
    # the stages handle such values, numpy need not warn of each.
    with _one_blas_thread(), np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        return _mesh(surface, box, coarse, fine, improve, params, (size, min_edge, max_edge, chord), max_memory)


_BLAS: list = []


def _one_blas_thread():
    """A context limiting the BLAS libraries to one thread.

    The libraries are found once per process (threadpoolctl's scan of the
    loaded libraries is about 1 ms, 4% of a sphere's mesh): numpy's and
    scipy's, which singmesh's imports have loaded before the first call.
    """
    if not _BLAS:
        _BLAS.append(ThreadpoolController())
    return _BLAS[0].limit(limits=1, user_api="blas")


def _mesh(surface, box, coarse: int, fine: int, improve: bool, params: dict,
          sizing=("uniform", None, None, None), max_memory=None, raises: int = 0,
          lenses: np.ndarray | None = None) -> Mesh:
    """:func:`mesh` itself (``raises``: the times ``fine`` was doubled for creases after a first try;
    ``lenses``: (k, 2, 3) regions split to the fine level, found by a first try)."""
    t0 = time.perf_counter()
    if max_memory is not None:
        parse_size(max_memory)  # a bad value is said before the work
    surf = Surface.parse(surface, **params)
    # F = G^2 H: G = 0 is no sign change; mesh G H and say so.
    surf, repeated = squarefree(surf)
    b = check_box(box)
    check_defined(surf, b)
    coarse_level = _level(coarse, "coarse")
    fine_level = _level(fine, "fine")
    if fine_level < coarse_level:
        raise SurfaceError(f"fine ({fine}) must be at least coarse ({coarse})")
    levels = sizing_levels(*sizing, fine_level)
    if levels is not None:
        coarse_level = levels[0]

    cell = (b[:, 1] - b[:, 0]) / (1 << fine_level)
    t_curves = time.perf_counter()
    curves = singular_curves(surf, b, step=float(cell.max()))
    locus_curves = bool(len(curves.points))
    # Creases (kinks of F on the surface) are meshed as the singular
    # curves are: tubes with two half-sheets along them.
    creases = crease_curves(surf, b, step=float(cell.max()))
    # Creases closer than a tube's width share one tube and lose the piece
    # of surface between them: the lattice is made finer until they do not.
    # The fine level asked for (before the retries of a failed crease mesh).
    asked = fine_level - raises
    gap = crease_gap(creases, b, fine_level)
    raised = _fine_for_creases(gap, fine_level)
    # Why fine was raised, for a refusal's message.
    raised_for = None
    if raised > fine_level:
        raised_for = f"creases {gap:.3g} fine cells apart at fine {1 << fine_level}"
        if gap < 1:
            raised_for += (" (two kinks along one curve, as coplanar faces of the arguments of a Min or Max, "
                           "are creases 0 apart)")
    # Two singular curves (or two stretches of one) closer than two tubes'
    # width share one tube, and the sheets between them have no rail there
    # (the two branches of a hyperbola 10 cells apart: fuzz s2-126): the
    # same, once.
    curve_gap = crease_gap(curves, b, fine_level)
    if _fine_for_curves(curve_gap, fine_level) > raised:
        raised = _fine_for_curves(curve_gap, fine_level)
        raised_for = f"singular curves {curve_gap:.3g} fine cells apart at fine {1 << fine_level}"
    # A small loop of a double curve whose sheets cross at a small angle
    # has no room for the wide tube those sheets need (it would hold the
    # lens between them whole): finer, its loop is more cells across while
    # the tube's reach in cells stays.
    if _fine_for_loops(curves.cramped, fine_level) > raised:
        raised = _fine_for_loops(curves.cramped, fine_level)
        raised_for = (f"a small loop of a double curve at fine {1 << fine_level} (its sheets cross at a small "
                      "angle and their tube would fill it)")
    if raised > fine_level:
        gap *= 1 << (raised - fine_level)
        fine_level = raised
        cell = (b[:, 1] - b[:, 0]) / (1 << fine_level)
        curves = singular_curves(surf, b, step=float(cell.max()))
        creases = crease_curves(surf, b, step=float(cell.max()))
    curves = merge_curve_sets(curves, creases)
    # A root of |u| along a curve of the surface (|x|^0.5 + ...) is a
    # cuspidal crease that is not traced: said below, and refused where
    # the mesh comes out open along it.
    unfollowed = [(name, p.tolist()) for name, p in root_creases(surf, b)]
    t_curves = time.perf_counter() - t_curves
    t_sing = time.perf_counter()
    # Points on the curves are their special points (pinch and triple
    # points): the point search leaves the curves alone.  A curve it sees
    # that was not traced (``overflow``) is reported, not meshed.
    avoid = curve_samples(curves.points, curves.edges, 0.25 * float(cell.max())) if len(curves.points) else None
    points, overflow = singular_points(surf, b, level=min(fine_level, tol.SINGULAR_LEVEL),
                                       avoid=avoid, avoid_radius=tol.CURVE_AVOID * float(cell.max()),
                                       on_radius=tol.CURVE_ON * float(cell.max()))
    # Where a root of a sum of squares in F vanishes on the surface (a
    # cone's apex written with sqrt), F is not differentiable: such points
    # are meshed as singular points, with a star.
    # (Such zeros along a curve, the edge of a half-plane where F touches
    # 0, are not points: said as a curve of singular points is.)
    tips, tip_curve = tip_points(surf, b, level=min(fine_level, tol.SINGULAR_LEVEL))
    overflow = overflow or tip_curve
    if tips and avoid is not None:
        d = cKDTree(avoid).query(np.array([t.point for t in tips]))[0]
        tips = [t for t, far in zip(tips, d > tol.CURVE_AVOID * float(cell.max())) if far]
    if tips:
        points = sorted(points + tips, key=lambda sp: tuple(sp.point))
    kinds = [sp.classification for sp in points]
    t_sing = time.perf_counter() - t_sing
    if not len(curves.points):
        # Each point needs a star cube of its own on the fine lattice:
        # points a cell or two apart would share one (and lose their
        # stars), so the lattice is made finer until they are not.
        fine_level = _fine_for_points(np.array([sp.point for sp in points]).reshape(-1, 3), b, fine_level)
        cell = (b[:, 1] - b[:, 0]) / (1 << fine_level)
    # First pass: the boxes at each singular point, and along each curve
    # of them, go to the fine level.
    cubes = np.array([[sp.point - cell, sp.point + cell] for sp in points]).reshape(-1, 2, 3)
    keep = np.concatenate([cubes, tube_regions(b, fine_level, curves)]) if len(curves.points) else cubes
    if lenses is not None:
        keep = np.concatenate([keep, lenses])
    refine = None
    if levels is not None:
        side = float((b[:, 1] - b[:, 0]).max())
        refine = CurvatureSizing(surf, b, fine_level, chord=levels[2] * side, min_level=levels[1])
    budget = Budget(surf.enclose(b).nbytes, coarse_level, fine_level, max_memory)
    try:
        tree = subdivide(surf, b, coarse_level, fine_level, keep_splitting=keep, refine=refine, budget=budget)
    except MemoryBudgetError as e:
        if fine_level <= asked:
            raise
        # The user's coarse and fine were not what asked for the memory.
        why = raised_for or "crease strips that failed on the coarser lattices"
        raise MemoryBudgetError(f"{e}; fine was raised from {1 << asked} to {1 << fine_level} for {why}") from None
    centres = np.array([sp.point for sp in points]).reshape(-1, 3)
    expected = [getattr(sp.classification, "branches", None) for sp in points]
    if len(points):
        # A point on a face of the box has only the branches inside it there
        # (one nappe of a cone whose axis crosses the face): no count to
        # shrink its star for.
        cut = topology.on_box_boundary(centres, b, tol.STAR_ON_BOX)
        expected = [None if c else e for c, e in zip(cut.tolist(), expected)]
        # The stars grow along the adjacency of the leaves that failed the
        # simplicity test alone: this tree's events and links would be
        # replaced by the refined tree's.
        cubes = star_cubes(tree, leaf_sides(tree, np.nonzero(~tree.simple)[0]), centres,
                           curves.points if len(curves.points) else None)
    else:
        cubes = None
        events = compute_events(surf, tree)
        links = face_links(surf, tree, events, tubes=bool(len(curves.points)))
    first = tree
    for attempt in range(tol.STAR_RETRIES + 1):
        if cubes is not None:
            # Second pass: each star becomes a cube around its point, large
            # enough to hold the boxes that failed the simplicity test
            # there; the leaves meeting its boundary go to the fine level.
            tree = refine_stars(surf, first, cubes)
            events = compute_events(surf, tree)
        group, stars, clashes = group_stars(tree, cubes, centres)
        if cubes is not None:
            # No links inside the stars (their cones replace the surface
            # there); the tubes are found from all links.
            links = face_links(surf, tree, events, group=None if len(curves.points) else group,
                               tubes=bool(len(curves.points)))
        tube_id = len(tree.level) + len(points)
        if len(curves.points):
            group[tube_leaves(tree, links, curves)] = tube_id
        grouped = box_links(links, group)
        cycles = find_cycles(*grouped, n_events=len(events.key), key=events.key)
        # A node just inside a face of the box: the links there may join its
        # two branches into one cycle.
        cycles = part_branches(cycles, events, links, tree, stars, points)
        # A star too large for the cone over its boundary to be the surface
        # in it joins branches: fewer link cycles than the classifier's
        # branches.  Those stars shrink by half and are meshed again.
        few = short_stars(cycles, stars, expected)
        if not few or attempt == tol.STAR_RETRIES:
            break
        cubes = shrink_cubes(first, cubes, centres, few)
    # A piece of surface cut off by the box's boundary in a coarse leaf
    # whose cycle's events all lie on one face of the leaf has no polygon
    # but a flat one: a sliver at an edge of the box (fuzz s4-26, 25 cells
    # long), a cap through a face of the box (s3-905, 6 cells across) is
    # dropped or cut short (facets/cycles.py lens_leaves).  Those leaves
    # are split to the fine level, once, where the piece meets more edges.
    lens = lens_leaves(cycles, tree.level, tree.corner, fine_level, events.lattice(),
                       topology.on_box_boundary(events.point, b, tol.STAR_ON_BOX), events.snapped)
    if len(lens) and lenses is None:
        lo = tree.lattice_to_space(tree.corner[lens])
        hi = tree.lattice_to_space(tree.corner[lens] + tree.size[lens, None])
        inset = tol.LENS_INSET * cell
        return _mesh(surface, box, coarse, fine, improve, params, sizing, max_memory, raises,
                     np.stack([lo + inset, hi - inset], axis=1))

    offsets, keys, pts, apex, branches, splits = facet_polygons(surf, tree, events, links, cycles, stars, points, tube_id,
                                                                 expected=expected)
    key0 = curve_key0(events)
    if len(curves.points):
        # The rails read the tube's squares on the box's faces paired by
        # following the surface's trace (two sheets less than a cell apart
        # there); the boxes' cycles keep their links.
        r_links = rail_links(surf, tree, events, links, group == tube_id,
                             untraced_points(curves, 0.25 * float(cell.max())),
                             tol.CURVE_TUBE_RADIUS * float(cell.max()))
        traced = None if r_links is links else (box_links(r_links, group), r_links)
        offsets, keys, pts, apex = add_strips(offsets, keys, pts, apex, grouped, links, events, curves,
                                              tube_id, key0, float(cell.max()), b,
                                              surf if len(creases.points) else None, traced, splits)
    fixed = np.arange(key0, key0 + len(curves.points))
    vertices, faces, vkeys, *grad = assemble(offsets, keys, pts, surf.gradient, project=surf.project,
                                             apex=apex, fixed_keys=fixed, return_gradient=improve)
    # Closed specks round single lattice points between two sheets closer
    # than a cell (no critical point of F in them) are not the surface.
    specks = lattice_specks(vertices, faces, float(cell.max()),
                            np.isin(vkeys, fixed) | np.isin(vkeys, point_key(np.arange(len(points)))),
                            surf.gradient, surf.hessian)
    if specks.any():
        vertices, faces, vkeys, *grad = without_faces(vertices, faces, specks, vkeys, *grad)
    if len(creases.points) and len(faces):
        # The fine triangles of the crease tubes merged up to the size of
        # the coarse lattice's.
        coarse_cell = float(np.max(b[:, 1] - b[:, 0])) / (1 << coarse_level)
        vertices, faces, vkeys, grad, curves = coarsen_crease_mesh(
            vertices, faces, vkeys, grad, curves, key0, point_key(np.arange(len(points))), b,
            tol.COARSEN_EDGE * coarse_cell, tol.COARSEN_REACH * coarse_cell)
        fixed = np.arange(key0, key0 + len(curves.points))
    strips = 0
    on_end = np.zeros(len(vertices), bool)
    if not surf.is_polynomial and len(faces):
        # Up to where the surface runs out of F's domain (sqrt(1 - x^2 - y^2)
        # at x^2 + y^2 = 1), from the open edges a cell short of it.
        n_old = len(vertices)
        vertices, faces, source, strips = reach_domain_edges(vertices, faces, surf, b, float(cell.max()))
        # (kept in place by improve, keyed below the singular points'; grad F is infinite on the
        # domain's end, the normal of the vertex each came from stands in for it there)
        vkeys = np.concatenate([vkeys, point_key(len(points) + np.arange(len(source)))])
        on_end = np.arange(len(vertices)) >= n_old
        if grad:
            grad[0] = np.concatenate([grad[0], grad[0][source]])
    t_improve = time.perf_counter()
    improved = {}
    if improve:
        # The singular points' vertices stay, as do the curve and crease
        # vertices (the keys fixed).
        singular_vertex = np.isin(vkeys, point_key(np.arange(len(points))))
        vertices, faces, improved = improve_mesh(vertices, faces, surf, b, singular_vertex,
                                                 np.isin(vkeys, fixed) | on_end,
                                                 gradient=grad[0])
    t_improve = time.perf_counter() - t_improve
    # Where two axis skeletons meet (normal along an axis), for reference:
    # the mesh does not use them, so they are found when first asked for.
    node_level = min(fine_level, tol.SKELETON_NODE_LEVEL)
    singular = []
    # Each point's first vertex, from one pass over the keys (not a pass per point).
    at = np.flatnonzero(np.isin(vkeys, point_key(np.arange(len(points)))))
    first: dict = {}
    for j, k in zip(at.tolist(), vkeys[at].tolist()):
        first.setdefault(k, j)
    for i, sp in enumerate(points):
        singular.append(replace(sp, vertex=first.get(point_key(i)),
                                branches=branches.get(i, 0), classification=kinds[i]))
    curve_list, special = curve_records(curves, vkeys, key0)
    stats = {
        "leaves": len(tree.level),
        "non_simple_leaves": int((~tree.simple).sum()),
        "levels": np.bincount(tree.level).tolist() if len(tree.level) else [],
        "events": len(events.key),
        "cycles": len(cycles),
        "broken_boxes": len(cycles.broken_boxes),
        "ambiguous_squares": int(links.ambiguous.sum()),
        "inconsistent_squares": int(links.inconsistent.sum()),
        "speck_triangles": int(specks.sum()),
        "singular_search_time": t_sing,
        "curve_time": t_curves,
        "singular_locus_not_isolated": bool(overflow or locus_curves),
        "creases": len(creases),
        "untraced_curve": bool(overflow),
        "repeated_factors": repeated,
        "unfollowed_creases": unfollowed,
        "overlapping_stars": len(clashes),
        "fine": 1 << fine_level,
        "size": sizing[0],
        # Distance (fine cells) of the two closest creases, where closer
        # than CREASE_MIN_GAP (then ``fine`` was raised for them), else None.
        "crease_gap": gap if np.isfinite(gap) else None,
        "domain_edge_triangles": strips,
        "improve": improved,
        "improve_time": t_improve,
        "memory_estimate": budget.largest,
        "time": time.perf_counter() - t0,
    }
    m = Mesh(vertices=vertices, faces=faces, surface=surf, box=b, singularities=singular, stats=stats,
             skeleton_source=_skeleton_source(surf, b, node_level), singular_curves=curve_list,
             special_points=special, curve_graph=curve_graph(curves, vkeys, key0))
    # Creases whose strips failed are meshed again on a finer lattice, as
    # creases too close together are: a face between creases a few cells
    # across is all tube, with no rail, and the edges round it lack a
    # triangle (a truncated cube's corner triangles at fine 64), or the
    # whole surface is tube and the mesh empty (an octahedron at fine 32).
    # What is still wrong at the last try is said below.
    if (len(creases.points) and not locus_curves and raises < tol.CREASE_RETRIES
            and fine_level < tol.MAX_LEVEL and _strips_failed(m)):
        try:
            return _mesh(surface, box, coarse, 1 << (fine_level + 1), improve, params, sizing, max_memory,
                         raises + 1, lenses)
        except MemoryBudgetError:
            pass
    # A surface thinner than a cell along a cuspidal edge (x^2 = z^3 - 5 z^4:
    # a lens 0.04 wide and 0.2 tall round the edge, fuzz s3-925) is all
    # tube, and its strips fail: the mesh is empty though F has both signs
    # at the leaves' corners, well above rounding.  The lattice is made
    # finer until the sheets are cells apart.  (Two planes 2e-10 apart,
    # x^2 - 1e-20, have one sign only at rounding level: no retry there.)
    if (not len(faces) and locus_curves and raises < tol.THIN_RETRIES and fine_level < tol.MAX_LEVEL
            and _signs_resolved(surf, tree)):
        try:
            return _mesh(surface, box, coarse, 1 << (fine_level + 1), improve, params, sizing, max_memory,
                         raises + 1, lenses)
        except MemoryBudgetError:
            pass
    # Nothing is dropped silently: a point with branches that is not a
    # vertex, or whose fans differ from its branches, is said aloud.
    # Where F is of one sign and touches 0 (sqrt(y^2 + z^2) - z on a
    # half-plane: a sheet of singular points, and a curve of tips at its
    # edge), the one line saying so is the whole answer.
    if len(faces) == 0 and overflow and not surf.is_polynomial:
        touch = _why_empty(surf, b, 1 << fine_level)
        if "only touches 0" in touch:
            m.stats["touches_zero"] = touch[len("empty mesh: "):]
            warnings.warn(touch, EmptyMeshWarning, stacklevel=3)
            return m
    for note in m.singular_point_warnings() + m.curve_warnings():
        warnings.warn(note, SingularPointWarning, stacklevel=3)
    # Closed across its cuspidal creases (star superquadrics with p = 2/3
    # or 0.8: chi 2, the crease cut by the lattice, not followed), the mesh
    # is kept with the warning; open along them (p = 1/2: 432 open edges),
    # the surface is refused rather than returned broken.
    if unfollowed and _open_inside(m):
        raise SurfaceError(cuspidal_crease_refusal(unfollowed))
    for note in m.crease_warnings():
        warnings.warn(note, CreaseWarning, stacklevel=3)
    if not surf.is_polynomial and len(faces):
        # Where the surface runs into a pole or out of F's domain (tan at
        # pi/2, sqrt(1 - x^2 - y^2) at x^2 + y^2 = 1) the mesh ends up to a
        # cell short of it, open there: said, not left for the user to find.
        m.stats["open_at_domain_edge"] = _open_at_domain_edge(surf, m, float(cell.max()))
        if m.stats["open_at_domain_edge"]:
            warnings.warn(m.domain_edge_note(), SingularPointWarning, stacklevel=3)
    if len(faces) == 0 and not len(points) and not len(curves.points):
        warnings.warn(_why_empty(surf, b, 1 << fine_level), EmptyMeshWarning, stacklevel=3)
    elif len(faces) == 0 and (overflow or any(c.half_sheets for c in curve_list)):
        # Not silent either: only "curves" traced in a plane of singular
        # points came out (x^2 - 1e-20), curves with sheets and no sheet.
        warnings.warn(f"empty mesh: {UNRESOLVED_EMPTY[len('no triangle: '):]}", EmptyMeshWarning, stacklevel=3)
    return m


def _open_at_domain_edge(surf: Surface, m: Mesh, cell: float) -> list:
    """[count, point, others, short] of the mesh's open edges inside the box next to where F is undefined or
    unbounded (others: the open edges inside the box that are not; short: those of count not ending on
    an end of F's domain, facets.domain_edges), or [] where none is next to such places."""
    edges, count = topology.edges_with_counts(m.faces)
    one = edges[count == 1]
    one = one[~(faces_of(m.vertices[one[:, 0]], m.box) & faces_of(m.vertices[one[:, 1]], m.box)).any(axis=1)]
    if not len(one):
        return []
    mid = m.vertices[one].mean(axis=1)
    near = surf.ends_near(mid, tol.DOMAIN_EDGE_REACH * cell)
    if not near.any():
        return []
    p = mid[near][np.lexsort(mid[near].T[::-1])][0]
    # Those not ending on the domain's end (up to a cell short of it, or of a pole).
    ends = np.zeros(len(m.vertices), bool)
    at = np.unique(one[near])
    ends[at] = on_domain_end(surf, m.vertices[at], float(np.max(m.box[:, 1] - m.box[:, 0])))
    short = near & ~(ends[one[:, 0]] & ends[one[:, 1]])
    return [int(near.sum()), p.tolist(), int((~near).sum()), int(short.sum())]


def _signs_resolved(surface: Surface, tree: Octree) -> bool:
    """Whether F takes both signs at the leaves' corners with values above ``SIGN_RESOLVED`` of the largest."""
    corners = (tree.corner[:, None, :] + CHILD_OFFSETS[None] * tree.size[:, None, None]).reshape(-1, 3)
    with np.errstate(all="ignore"):
        f = surface(tree.lattice_to_space(np.unique(corners, axis=0)))
    f = f[np.isfinite(f)]
    if not len(f):
        return False
    floor = tol.SIGN_RESOLVED * float(np.abs(f).max())
    return bool((f > floor).any() and (f < -floor).any())


def _open_inside(m: Mesh) -> bool:
    """Whether an edge with one triangle lies inside the box (not in one of its faces)."""
    if not len(m.faces):
        return False
    edges, count = topology.edges_with_counts(m.faces)
    one = edges[count == 1]
    return bool((~(faces_of(m.vertices[one[:, 0]], m.box) & faces_of(m.vertices[one[:, 1]], m.box)).any(axis=1)).any())


def _strips_failed(m: Mesh) -> bool:
    """Whether a crease edge inside the box has another number of triangles than two, or none has any.

    Edges in a face of the box are left out: there a half-sheet may lie
    in the face itself (a half ball cut by the box at its flat side).
    """
    if all(faces_of(c.points, m.box).all(axis=0).any() for c in m.singular_curves):
        return False
    if not len(m.faces):
        return True

    def inside(p, q):
        return ~(faces_of(p, m.box) & faces_of(q, m.box)).any(axis=1)

    return bool(m.curve_edges_short_of_sheets(inside))


def _skeleton_source(surf: Surface, box: np.ndarray, level: int):
    """A function (picklable) finding the skeleton nodes as :func:`mesh` would."""
    return partial(_find_skeleton_nodes, surf, box, level)


def _find_skeleton_nodes(surf: Surface, box: np.ndarray, level: int):
    """:func:`skeleton_nodes` with one BLAS thread and without warnings, as in :func:`mesh`."""
    with _one_blas_thread(), np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        return skeleton_nodes(surf, box, level=level)


def _why_empty(surface: Surface, box: np.ndarray, fine: int) -> str:
    """One line saying why the mesh of ``surface`` in ``box`` is empty.

    Raises
    ------
    SurfaceError
        Where F changes sign, but no lattice edge of ``fine`` cells a side
        sees it (sheets closer than a cell).
    """
    s = np.linspace(0.0, 1.0, 9)
    grid = np.stack(np.meshgrid(s, s, s, indexing="ij"), -1).reshape(-1, 3)
    with np.errstate(all="ignore"):
        f = surface(box[:, 0] + grid * (box[:, 1] - box[:, 0]))
    where = "[" + ", ".join(f"{lo:g}..{hi:g}" for lo, hi in box) + "]"
    if np.isnan(f).all():
        return f"empty mesh: F = {surface} is undefined everywhere in the box {where} (e.g. sqrt or log of a negative number)"
    x = (box[:, 0] + grid * (box[:, 1] - box[:, 0]))[~np.isnan(f)]
    f = f[~np.isnan(f)]
    if (f > 0).all() or (f < 0).all():
        # The grid may miss where F touches 0 (-|z - 0.3|): climb towards 0
        # from the samples nearest it.
        x, f = _towards_zero(surface, box, x, f)
    if ((f >= 0).all() or (f <= 0).all()) and (f == 0).any():
        p = x[np.argmax(f == 0)]
        other = _other_sign_near(surface, box, p, -1.0 if (f >= 0).all() else 1.0, float(np.abs(f).max()))
        if other is not None:
            # The zero is a crossing, not a touching: the surface is there
            # but thinner than a cell ((x - 0.013)^2 - 1e-6: two planes
            # 0.002 apart between lattice planes 0.0625 apart).  An empty
            # mesh would be a wrong answer; say what to change.
            at = ", ".join(f"{c:.6g}" for c in other)
            cell = float(np.max(box[:, 1] - box[:, 0])) / fine
            raise SurfaceError(
                f"F = {surface} changes sign near ({at}) between lattice points: the surface there is "
                f"thinner than a fine cell ({cell:.3g}) and no lattice edge meets it; raise fine or shrink the box")
        # F touches 0 without changing sign (-|z|, -(x^2 + y^2)): such
        # zeros bound no solid and are not meshed; saying "both signs"
        # would send the user looking for a zero that is not missing.
        side = ">=" if (f >= 0).all() else "<="
        return (f"empty mesh: F = {surface} is {side} 0 in the box {where} and only touches 0 (e.g. at "
                f"({p[0]:.6g}, {p[1]:.6g}, {p[2]:.6g})) without changing sign: such zeros bound no solid "
                "and are not meshed")
    sign = "positive" if (f > 0).all() else "negative" if (f < 0).all() else "of both signs but without a zero found"
    return f"empty mesh: the surface F = {surface} does not meet the box {where} (F is {sign} there)"


def _other_sign_near(surface: Surface, box: np.ndarray, p: np.ndarray, sign: float, scale: float) -> np.ndarray | None:
    """A point near the zero ``p`` where F has ``sign`` above ``EMPTY_TOUCH`` of ``scale``, or None.

    Steps of ``EMPTY_CROSS_STEPS`` of the box along the axes from ``p``: a
    zero where F crosses has the other sign on one side at some step; one
    where F only touches 0 (-|z|, a double root) has not.
    """
    size = float(np.max(box[:, 1] - box[:, 0]))
    steps = size * np.asarray(tol.EMPTY_CROSS_STEPS)
    dirs = np.concatenate([np.eye(3), -np.eye(3)])
    q = np.clip(p + (steps[:, None, None] * dirs[None]).reshape(-1, 3), box[:, 0], box[:, 1])
    with np.errstate(all="ignore"):
        v = surface(q)
    hit = np.flatnonzero(np.isfinite(v) & (sign * v > tol.EMPTY_TOUCH * scale))
    return q[hit[0]] if len(hit) else None


def _towards_zero(surface: Surface, box: np.ndarray, x: np.ndarray, f: np.ndarray):
    """The samples (x, f) of one sign, with points where a local search drove F to 0 added (f = 0).

    Nelder-Mead on |F| from the few samples nearest 0 (F need not be
    smooth where it touches 0: -|z - 0.3|), kept in the box; a value below
    ``EMPTY_TOUCH`` of the largest |F| sampled counts as a zero.
    """
    from scipy.optimize import minimize

    scale = float(np.abs(f).max())
    lo, hi = box[:, 0], box[:, 1]

    def size(p):
        q = np.clip(p, lo, hi)
        with np.errstate(all="ignore"):
            v = float(surface(q[None])[0])
        return abs(v) if np.isfinite(v) else np.inf

    found = []
    for i in np.argsort(np.abs(f), kind="stable")[:tol.EMPTY_TOUCH_STARTS]:
        r = minimize(size, x[i], method="Nelder-Mead",
                     options=dict(xatol=1e-15, fatol=0.0, maxiter=4000, maxfev=8000))
        if r.fun <= tol.EMPTY_TOUCH * scale:
            found.append(np.clip(r.x, lo, hi))
            break
    if not found:
        return x, f
    return np.vstack([x, found]), np.concatenate([f, np.zeros(len(found))])


def _fine_for_creases(gap: float, fine_level: int) -> int:
    """The fine level at which creases ``gap`` fine cells apart are ``CREASE_MIN_GAP`` cells apart.

    At most ``CREASE_MAX_RAISE`` levels more, and ``MAX_LEVEL``.
    """
    if gap >= tol.CREASE_MIN_GAP:
        return fine_level
    more = int(np.ceil(np.log2(tol.CREASE_MIN_GAP / max(gap, 1e-300))))
    return min(fine_level + min(more, tol.CREASE_MAX_RAISE), tol.MAX_LEVEL)


def _fine_for_loops(cramped: float, fine_level: int) -> int:
    """The fine level at which a loop ``cramped`` times too small for its wide tube has room for it.

    At most ``CURVE_CRAMPED_MAX_RAISE`` levels more, and ``MAX_LEVEL``.
    """
    if cramped <= 1.0:
        return fine_level
    more = int(np.ceil(np.log2(cramped)))
    return min(fine_level + min(more, tol.CURVE_CRAMPED_MAX_RAISE), tol.MAX_LEVEL)


def _fine_for_curves(gap: float, fine_level: int) -> int:
    """The fine level at which singular curves ``gap`` fine cells apart are ``CREASE_MIN_GAP`` cells apart.

    Only where one level parts them (``gap`` at least ``CURVE_GAP_LEAST``):
    branches that meet tangentially (a loop of the double curve with a
    cusp at a cone's apex, fuzz s1-270) come arbitrarily close, and no
    level parts them.  At most ``MAX_LEVEL``.
    """
    if not tol.CURVE_GAP_LEAST <= gap < tol.CREASE_MIN_GAP:
        return fine_level
    more = int(np.ceil(np.log2(tol.CREASE_MIN_GAP / gap)))
    return min(fine_level + min(more, tol.CURVE_GAP_MAX_RAISE), tol.MAX_LEVEL)


def _fine_for_points(points: np.ndarray, box: np.ndarray, fine_level: int) -> int:
    """The fine level at which no two of ``points`` are closer than ``STAR_MIN_GAP`` cells.

    Measured in the max norm in cells (the stars are lattice cubes); at most
    ``STAR_MAX_RAISE`` levels more, and ``MAX_LEVEL``: closer points than
    that keep sharing (reported as points too close to have a star).
    """
    if len(points) < 2:
        return fine_level
    from scipy.spatial import cKDTree

    cell = (box[:, 1] - box[:, 0]) / (1 << fine_level)
    gap = float(cKDTree(points / cell).query(points / cell, k=2, p=np.inf)[0][:, 1].min())
    if gap >= tol.STAR_MIN_GAP:
        return fine_level
    more = int(np.ceil(np.log2(tol.STAR_MIN_GAP / max(gap, 1e-300))))
    return min(fine_level + min(more, tol.STAR_MAX_RAISE), tol.MAX_LEVEL)

