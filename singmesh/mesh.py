"""The result of meshing: :class:`Mesh`, its report and its export."""

from __future__ import annotations

import os
import re
import shutil
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np
from scipy.spatial import cKDTree

from . import tolerances as tol
from . import topology
from .surface import Surface

#: Formats written through meshio, by suffix.
FORMATS = {
    ".obj": "obj", ".ply": "ply", ".stl": "stl", ".vtk": "vtk", ".vtu": "vtu",
    ".off": "off", ".msh": "gmsh", ".xdmf": "xdmf", ".mesh": "medit",
    # Not meshio's: a web page with the interactive view (singmesh.view), curves included.
    ".html": "html",
}


#: Formats whose files take the curvatures as scalar point data.
CURVATURE_FORMATS = ("ply", "vtk", "vtu", "xdmf", "gmsh")

#: The names of the curvature arrays in files.
CURVATURE_NAMES = ("gaussian_curvature", "mean_curvature", "k1", "k2")

#: Triangles with a vertex nearer than this (fraction of the box's largest
#: side) to a singular point or curve are left out of the angle statistics
#: "away from singular" of the report (issue #12's rule).
AWAY = 0.05


def _percent(flags: np.ndarray) -> float:
    """Percentage of True in ``flags`` (0 for none)."""
    return float(100.0 * flags.mean()) if flags.size else 0.0


#: Formats whose files hold line cells beside the triangles.
LINE_FORMATS = ("vtk", "vtu", "xdmf", "gmsh")


def _write_atomic(path: Path, write: Callable[[Path], Any], in_place: bool = False) -> None:
    """``write(target)``, then ``target`` renamed to ``path``: no partial file is ever at ``path``.

    The target is a hidden file in the same folder (a rename within a file
    system is atomic), removed if the writer fails.  ``in_place``: formats
    whose file names a companion file (XDMF's ``.h5``) are written at
    ``path`` itself, and removed on failure.
    """
    target = path if in_place else path.with_name(f".{path.name}.{os.getpid()}.part")
    try:
        write(target)
        _drop_timestamp(target)
        if not in_place:
            os.replace(target, path)
    except BaseException:
        target.unlink(missing_ok=True)
        raise


#: meshio's PLY and OBJ writers put the time into the header's comment
#: ("Created by meshio v5.3.5, 2026-11-25T16:16:10.995962"): the same mesh
#: would give other bytes each time.  The time is taken out.
_TIMESTAMP = re.compile(rb"(Created by meshio v[0-9A-Za-z.+-]*), [0-9]{4}-[0-9]{2}-[0-9]{2}T[0-9:.]+")


def _drop_timestamp(path: Path) -> None:
    """Remove meshio's time of writing from the header of the file at ``path`` (same mesh, same bytes)."""
    with open(path, "rb") as f:
        head = f.read(4096)
        fixed, n = _TIMESTAMP.subn(rb"\1", head, count=1)
        if not n:
            return
        rest = path.with_name(path.name + ".t")
        with open(rest, "wb") as out:
            out.write(fixed)
            shutil.copyfileobj(f, out, 1 << 20)
    os.replace(rest, path)


class SingularPointWarning(UserWarning):
    """A singular point is not meshed as it is (not a vertex, or wrong branches)."""


class CreaseWarning(UserWarning):
    """A curve where F = 0 is not smooth (a root of |u| vanishing along it) is not followed by the mesh."""


class EmptyMeshWarning(UserWarning):
    """The mesh has no triangle: the surface does not meet the box (the warning says why)."""


#: Why a mesh with a locus of singular points it could not trace is empty:
#: F and grad F are zero to rounding on more than curves (x^2 - 1e-20: two
#: planes 2e-10 apart, nearly a double plane), so no sign change is seen.
UNRESOLVED_EMPTY = ("no triangle: F and grad F vanish to rounding on more than points and curves here "
                    "(sheets closer than double precision resolves, or a repeated factor written with "
                    "rounded coefficients): F = 0 is not resolved")


def unit_normals(g: np.ndarray) -> np.ndarray:
    """Rows of ``g`` (grad F at vertices) scaled to unit length.

    Zero where grad F is 0 (an isolated line) or not finite (a vertex on a
    pole line, where F = 0 / 0).
    """
    g = np.asarray(g, float).reshape(-1, 3)
    norm = np.linalg.norm(g, axis=1, keepdims=True)
    ok = (norm > 0) & np.isfinite(norm)
    return np.where(ok, g / np.where(ok, norm, 1), 0.0)


def cuspidal_crease_refusal(roots: list) -> str:
    """The one line refusing a surface with cuspidal creases: ``roots`` is (name, point) per crease."""
    name, p = roots[0]
    return (f"F is not differentiable along {len(roots)} curve(s) of the surface where a root of |u| "
            f"vanishes (cuspidal creases, e.g. through ({p[0]:.6g}, {p[1]:.6g}, {p[2]:.6g}), from "
            f"{name}): singmesh does not mesh such creases (the mesh would be open along them); "
            "a power p >= 1 of |u| is differentiable there")


@dataclass
class Mesh:
    """A triangle mesh of a surface F = 0 inside a box.

    Attributes
    ----------
    vertices : (n, 3) float64
    faces : (m, 3) int64
        Triangles, counter-clockwise around ``grad F``.
    normals : (n, 3) float64
        Unit ``grad F`` at the vertices (zero where grad F vanishes).
    singular_points : (k, 3) float64
    singularities : list
        One record per singular point (location, Hessian rank and
        signature, branches, classification).
    surface : Surface
    box : (3, 2) float64
    stats : dict
        How the mesher got there (boxes, levels, timings).
    skeleton_nodes : (j, 3) float64
        Points where F and two partial derivatives vanish but grad F does
        not: where the x-, y- and z-skeletons meet (isolated ones only).
        Reference data the mesh does not use: found on first access (from
        ``skeleton_source``), not while meshing.
    skeleton_node_axes : (j, 2) int64
        The two derivatives vanishing at each skeleton node.
    singular_curves : list of :class:`singmesh.skeleton.singular_curves.SingularCurve`
        The curves of singular points, one record per piece of one
        transversal type (polyline, type, sheets, end points, mesh vertices),
        and the creases of a non-polynomial F (type ``"crease"``: where its
        Min/Max, Abs or R-function has a kink on the surface, two half-sheets
        at an angle), each edge a mesh edge.
    special_points : list of :class:`singmesh.skeleton.singular_curves.SpecialPoint`
        Pinch points, triple points, crossings, changes of type and ends on
        the box of the curves, corners of creases, each a mesh vertex.
    curve_graph : ((c, 3) float64, (e, 2) int64, (c,) int64)
        All curves as one graph: its points, its edges (pairs of points)
        and the mesh vertex at each point (-1 where no triangle has it:
        an isolated real line).
    gaussian_curvature, mean_curvature : (n,) float64
        Per vertex, from F's exact derivatives (:mod:`singmesh.curvature`:
        Goldman's formulas; the mean curvature is positive where the
        surface bends towards ``normals``, so a sphere F = |p|^2 - r^2,
        whose normals point out, has -1/r).  NaN at singular vertices, on singular curves and
        creases, and wherever grad F vanishes.  Computed on first access.
    principal_curvatures : (n, 2) float64
        k1 >= k2 per vertex (NaN as above).
    principal_directions : (n, 2, 3) float64
        Unit tangent directions of k1 and k2 per vertex.
    """

    vertices: np.ndarray
    faces: np.ndarray
    surface: Surface
    box: np.ndarray
    normals: np.ndarray = None
    singularities: list = field(default_factory=list)
    stats: dict = field(default_factory=dict)
    #: Returns (skeleton_nodes, skeleton_node_axes) when first asked for.
    skeleton_source: Callable[[], tuple[np.ndarray, np.ndarray]] | None = field(default=None, repr=False,
                                                                                  compare=False)
    singular_curves: list = field(default_factory=list)
    special_points: list = field(default_factory=list)
    curve_graph: tuple = field(default_factory=lambda: (np.zeros((0, 3)), np.zeros((0, 2), np.int64),
                                                        np.zeros(0, np.int64)))

    def __post_init__(self):
        if self.normals is None:
            g = self.surface.gradient(self.vertices) if len(self.vertices) else np.zeros((0, 3))
            self.normals = unit_normals(g)

    @property
    def skeleton_nodes(self) -> np.ndarray:
        return self._skeleton()[0]

    @property
    def skeleton_node_axes(self) -> np.ndarray:
        return self._skeleton()[1]

    def _skeleton(self) -> tuple[np.ndarray, np.ndarray]:
        """The skeleton nodes and their axes, found once."""
        cache = self.__dict__.get("_skeleton_cache")
        if cache is None:
            cache = self.skeleton_source() if self.skeleton_source is not None \
                else (np.zeros((0, 3)), np.zeros((0, 2), np.int64))
            self.__dict__["_skeleton_cache"] = cache
        return cache

    @property
    def gaussian_curvature(self) -> np.ndarray:
        """(V,) Gaussian curvature K = k1 k2 at each vertex (NaN where F is not smooth)."""
        return self._curvatures().gaussian

    @property
    def mean_curvature(self) -> np.ndarray:
        """(V,) mean curvature (k1 + k2) / 2, positive where the surface bends towards grad F."""
        return self._curvatures().mean

    @property
    def principal_curvatures(self) -> np.ndarray:
        """(V, 2) principal curvatures k1 >= k2."""
        return self._curvatures().principal

    @property
    def principal_directions(self) -> np.ndarray:
        """(V, 2, 3) unit tangent directions of k1 and k2."""
        return self._curvatures().directions

    def _curvatures(self):
        """The vertices' curvatures, computed once (NaN where F is not smooth)."""
        cache = self.__dict__.get("_curvature_cache")
        if cache is None:
            from .curvature import curvatures

            cache = curvatures(self.surface, self.vertices)
            # Singular points and the vertices of singular curves and
            # creases: F's gradient vanishes or jumps there.
            undefined = [s.vertex for s in self.singularities if s.vertex is not None]
            undefined += [int(v) for v in self.curve_graph[2] if v >= 0]
            for a in (cache.gaussian, cache.mean, cache.principal, cache.directions):
                a[undefined] = np.nan
            self.__dict__["_curvature_cache"] = cache
        return cache

    def curvature_data(self) -> dict[str, np.ndarray]:
        """The per-vertex curvatures as named scalar arrays (file point data)."""
        k = self.principal_curvatures
        arrays = (self.gaussian_curvature, self.mean_curvature, np.ascontiguousarray(k[:, 0]),
                  np.ascontiguousarray(k[:, 1]))
        return dict(zip(CURVATURE_NAMES, arrays))

    @property
    def singular_points(self) -> np.ndarray:
        if not self.singularities:
            return np.zeros((0, 3))
        return np.array([s.point for s in self.singularities], dtype=float)

    # ------------------------------------------------------------ report
    def report(self) -> dict[str, Any]:
        """Facts computed from the mesh itself (not from the mesher's state)."""
        v, f = self.vertices, self.faces
        edges, counts = topology.edges_with_counts(f) if len(f) else (np.zeros((0, 2), int), np.zeros(0, int))
        boundary = edges[counts == 1]
        on_box = topology.on_box_boundary(v, self.box)
        boundary_on_box = on_box[boundary].all(axis=1) if len(boundary) else np.zeros(0, bool)
        size = float(np.max(self.box[:, 1] - self.box[:, 0]))
        if len(v):
            residual = np.abs(self.surface(v))
            grad = np.linalg.norm(self.surface.gradient(v), axis=1)
            dist = residual / np.maximum(grad, 1e-300)
            # Singular vertices have grad F = 0: there |F| itself is the test.
            dist = np.where(grad > 1e-8 * max(size, 1.0), dist, residual)
        else:
            dist = np.zeros(0)
        angles = topology.triangle_angles(v, f) if len(f) else np.zeros((0, 3))
        away = self.away_from_singularities()
        return {
            "vertices": len(v),
            "faces": len(f),
            "edges": len(edges),
            "boundary_edges": int(len(boundary)),
            "boundary_edges_off_box": int((~boundary_on_box).sum()),
            "non_manifold_edges": int((counts > 2).sum()),
            "euler_characteristic": int(len(v) - len(edges) + len(f)),
            "components": topology.component_count(len(v), f),
            "max_distance": float(dist.max() / size) if len(dist) else 0.0,
            "min_angle": float(angles.min()) if len(angles) else float("nan"),
            "angles_below_10_percent": _percent(angles < 10),
            "angles_below_20_percent": _percent(angles < 20),
            # The same on the triangles of away_from_singularities().
            "triangles_away": int(away.sum()),
            "min_angle_away": float(angles[away].min()) if away.any() else float("nan"),
            "angles_below_10_percent_away": _percent(angles[away] < 10),
            "angles_below_20_percent_away": _percent(angles[away] < 20),
            "singular_points": len(self.singularities),
            "singular_curves": len(self.singular_curves),
            "creases": sum(c.type == "crease" for c in self.singular_curves),
            "special_points": len(self.special_points),
            "line_cells": int(len(self.curve_lines()[1])),
        }

    def away_from_singularities(self, reach: float | None = None) -> np.ndarray:
        """The triangles away from singular points and curves: (T,) bool.

        A triangle is away when none of its vertices lies within ``reach``
        (default ``AWAY``, 5%) of the box's largest side of a singular
        point, of a point of a singular curve or crease, or of a special
        point (the angle statistics of :meth:`report` are also given on
        these alone: at such points the triangles must meet the
        singularity and cannot all be well-shaped).
        """
        reach = AWAY if reach is None else reach
        f = self.faces
        if len(f) == 0:
            return np.zeros(0, bool)
        centres = [self.singular_points, np.asarray(self.curve_graph[0], float).reshape(-1, 3)]
        centres += [np.array([sp.point for sp in self.special_points], float).reshape(-1, 3)]
        centres = np.concatenate(centres)
        if len(centres) == 0:
            return np.ones(len(f), bool)
        size = float(np.max(self.box[:, 1] - self.box[:, 0]))
        near = cKDTree(centres).query(self.vertices, distance_upper_bound=reach * size)[0] <= reach * size
        return ~near[f].any(axis=1)

    def report_text(self) -> str:
        """The report as aligned lines, singular points after it."""
        r = self.report()
        lines = [
            f"surface              {self.surface}",
            "box                  " + " x ".join(f"[{a:g}, {b:g}]" for a, b in self.box),
            f"vertices             {r['vertices']}",
            f"faces                {r['faces']}",
            f"boundary edges       {r['boundary_edges']} ({r['boundary_edges_off_box']} off the box faces)",
            f"non-manifold edges   {r['non_manifold_edges']}",
            f"Euler characteristic {r['euler_characteristic']}",
            f"components           {r['components']}",
            f"max |F|/|grad F|     {r['max_distance']:.2e} of the box size",
            f"min angle            {r['min_angle']:.2f} degrees ({r['angles_below_10_percent']:.2f}% of the angles "
            f"< 10, {r['angles_below_20_percent']:.2f}% < 20)",
            f"  away from singular {r['min_angle_away']:.2f} degrees ({r['angles_below_10_percent_away']:.2f}% < 10, "
            f"{r['angles_below_20_percent_away']:.2f}% < 20; the {r['triangles_away']} triangles "
            f"{100 * AWAY:g}% of the box or more from singular points and curves)",
        ]
        if "time" in self.stats:
            lines.append(f"time                 {self.stats['time']:.3f} s")
        lines.append(f"singular points      {r['singular_points']}")
        for s in self.singularities:
            lines.append("  " + (s.describe() if hasattr(s, "describe") else str(s)))
        if self.singular_curves:
            # Creases (kinks of F on the surface) are meshed as the curves
            # of singular points are, and listed apart.
            locus = [c for c in self.singular_curves if c.type != "crease"]
            creases = [c for c in self.singular_curves if c.type == "crease"]
            if locus:
                lines.append(f"singular curves      {len(locus)} (line cells {r['line_cells']})")
                for c in locus:
                    lines.append("  " + c.describe())
            if creases:
                lines.append(f"creases              {len(creases)}")
                for c in creases:
                    lines.append("  " + c.describe())
            lines.append(f"special points       {r['special_points']}")
            for sp in self.special_points:
                lines.append("  " + sp.describe())
        lines += [f"note: {n}" for n in self.notes()]
        return "\n".join(lines)

    def singular_point_warnings(self) -> list[str]:
        """Singular points the mesh does not show as they are, one line each kind.

        A point whose surface has branches (by its classification) but is
        not a mesh vertex, and a point whose number of triangle fans differs
        from its branches, with the reason where it is known.
        """
        # On a face of the box only the branches inside it meet the point:
        # none where the cone points out of the box (its star has no cycle),
        # and it is no vertex then unless its star was given up.
        cut = topology.on_box_boundary(np.array([s.point for s in self.singularities], float).reshape(-1, 3),
                                       self.box, tol.STAR_ON_BOX)
        lost = [s for s, c in zip(self.singularities, cut.tolist())
                if s.vertex is None and (getattr(s.classification, "branches", None) or 0) > 0
                and (not c or self.stats.get("overlapping_stars"))]
        wrong = [s for s, c in zip(self.singularities, cut.tolist()) if s.vertex is not None and not c
                 and getattr(s.classification, "branches", None) not in (None, s.branches)]
        out = []
        if lost:
            why = []
            if self.stats.get("untraced_curve"):
                why.append("a curve of singular points in the box that was not traced")
            if self.stats.get("overlapping_stars"):
                why.append(f"{self.stats['overlapping_stars']} too close to another point to have a star")
            out.append(f"{len(lost)} of {len(self.singularities)} singular point(s) with branches are not "
                       f"mesh vertices" + (f" ({'; '.join(why)})" if why else "") + ": "
                       + ", ".join(s.name + " at (" + ", ".join(f"{c:.6g}" for c in s.point) + ")" for s in lost[:5])
                       + (" ..." if len(lost) > 5 else ""))
        if wrong:
            out.append(f"{len(wrong)} singular point(s) meshed with a number of branches other than their "
                       "type has: " + ", ".join(f"{s.name} at (" + ", ".join(f"{c:.6g}" for c in s.point)
                                                + f") {s.branches} instead of {s.classification.branches}"
                                                for s in wrong[:5]) + (" ..." if len(wrong) > 5 else ""))
        return out

    def curve_warnings(self) -> list[str]:
        """A curve of singular points found in the box but not traced (so not meshed right): one line, or none."""
        if not self.stats.get("untraced_curve") or self.stats.get("touches_zero"):
            return []
        return ["F has a curve of singular points in the box that could not be traced; "
                "near it the mesh is not right"]

    def crease_warnings(self) -> list[str]:
        """Creases the mesh does not follow (roots of |u|), or a crease mesh open inside the box: lines, or none."""
        out = []
        one = self.crease_open_edges()
        if len(one):
            p = self.vertices[one[0, 0]]
            out.append(f"the mesh of a surface with creases (sharp edges) is open inside the box: {len(one)} "
                       f"edge(s) with one triangle, e.g. at ({p[0]:.6g}, {p[1]:.6g}, {p[2]:.6g}); it is not "
                       "right there")
        roots = self.stats.get("unfollowed_creases", [])
        if not roots:
            return out
        name, p = roots[0]
        return out + [f"F is not differentiable along {len(roots)} curve(s) of the surface where a root of |u| "
                      f"vanishes (cuspidal creases, e.g. through ({p[0]:.6g}, {p[1]:.6g}, {p[2]:.6g})): "
                      "the mesh does not follow them and is not right near them"]

    def crease_open_edges(self) -> np.ndarray:
        """(k, 2): the edges with one triangle inside the box (not in a face of it) of a mesh with creases.

        None (an empty array) for a mesh without creases.  The tubes round
        the creases of float-rotated boxes joined by Min (a box standing on
        another) left strips of the faces next to them out: such a mesh is
        said to be open (:meth:`crease_warnings`), not returned silently.
        """
        if not len(self.faces) or not any(c.type == "crease" for c in self.singular_curves):
            return np.zeros((0, 2), np.int64)
        edges, count = topology.edges_with_counts(self.faces)
        one = edges[count == 1]
        box = np.asarray(self.box, float)
        size = 1e-9 * float(np.max(box[:, 1] - box[:, 0]))

        def faces(q):
            return np.concatenate([np.abs(q - box[:, 0]) <= size, np.abs(q - box[:, 1]) <= size], axis=1)

        return one[~(faces(self.vertices[one[:, 0]]) & faces(self.vertices[one[:, 1]])).any(axis=1)]

    def domain_edge_note(self) -> str:
        """One line on the open edges where the surface runs into a pole or out of F's domain, or ""."""
        edge = self.stats.get("open_at_domain_edge")
        if not edge:
            return ""
        n, p, others, short = edge
        where = ("there" if not short else "up to a cell short of there" if short == n else
                 f"there, and up to a cell short of there along {short} of them")
        return (f"the surface runs into a pole of F or out of its domain (sqrt or log of a negative number, "
                f"0/0): the mesh ends {where}, open along {n} edge(s) inside the box "
                f"(e.g. at ({p[0]:.6g}, {p[1]:.6g}, {p[2]:.6g}))"
                + (f"; {others} other open edge(s) inside the box are not next to such places: the mesh is "
                   "not right there" if others else ""))

    def notes(self) -> list[str]:
        """What the user must know about this mesh beyond the counts."""
        out = self.singular_point_warnings() + self.curve_warnings() + self.crease_warnings()
        if self.stats.get("open_at_domain_edge"):
            out.append(self.domain_edge_note())
        if self.stats.get("speck_triangles"):
            out.append(f"two sheets of F = 0 come closer than a cell: {self.stats['speck_triangles']} triangles "
                       "of closed specks between them were dropped (no extremum of F inside); there the mesh "
                       "is right only to a cell (a larger fine level resolves them)")
        for factor, k in self.stats.get("repeated_factors", []):
            out.append(f"F has the factor ({factor})^{k}: the mesh is of F without the repeated powers "
                       "(a repeated factor does not change sign, so its zeros are all singular)")
        denominator = getattr(self.surface, "denominator", "")
        if denominator:
            out.append(f"F is a fraction N / D with D = {denominator}: the mesh is of N = 0, the closure of "
                       "F = 0 (where D = 0 on it, F itself is undefined)")
        removable = getattr(self.surface, "removable", "")
        if removable:
            out.append(f"F is 0/0 where {removable} = 0 (a factor of both its numerator and denominator): "
                       f"the mesh there is of its limit, F with the factor cancelled, {self.surface.expr} = 0")
        bad = self.curve_edges_short_of_sheets()
        if bad:
            out.append(f"{bad} edge(s) of the singular curves have another number of triangles than their "
                       "type has half-sheets (the mesh is not right there)")
        if len(self.faces) == 0:
            if self.stats.get("touches_zero"):
                # (F of one sign touching 0 along a sheet of singular points)
                out.append(f"no triangle: {self.stats['touches_zero']}")
            elif self.stats.get("untraced_curve") or any(c.half_sheets for c in self.singular_curves):
                out.append(UNRESOLVED_EMPTY)
            elif self.singularities or self.singular_curves:
                out.append("no triangle: in this box the real surface is only isolated point(s) and line(s)")
            else:
                out.append("no triangle: F has no real zero in this box")
        return out

    # ------------------------------------------------------------ export
    def curve_lines(self) -> tuple[np.ndarray, np.ndarray]:
        """The one-dimensional part: curve edges that no triangle has.

        Returns
        -------
        points : (n + k, 3)
            The vertices, then the k curve points that are no vertex.
        lines : (L, 2) int64
            Line cells, indices into ``points``.
        """
        pts, edges, vertex = self.curve_graph
        if len(edges) == 0:
            return self.vertices, np.zeros((0, 2), np.int64)
        extra = vertex < 0
        index = vertex.copy()
        index[extra] = len(self.vertices) + np.arange(extra.sum())
        lines = index[edges]
        if len(self.faces):
            tri_edges, _ = topology.edges_with_counts(self.faces)
            n = len(self.vertices) + int(extra.sum())
            have = np.isin(np.sort(lines, axis=1) @ np.array([n, 1]), np.sort(tri_edges, axis=1) @ np.array([n, 1]))
            lines = lines[~have]
        return np.vstack([self.vertices, pts[extra]]), lines

    def curve_edges_short_of_sheets(self, where=None) -> int:
        """Edges of the singular curves with another number of triangles than their type has half-sheets.

        ``where``: optional ``(p, q) -> (k,) bool`` on the edges' end points
        (k, 3) each, the edges to count (all by default).
        """
        if not self.singular_curves or not len(self.faces):
            return 0
        edges, counts = topology.edges_with_counts(self.faces)
        n = len(self.vertices) + len(self.curve_graph[0])
        count = dict(zip((np.sort(edges, axis=1) @ np.array([n, 1])).tolist(), counts.tolist()))
        bad = 0
        for c in self.singular_curves:
            v = np.asarray(c.vertices)
            k = np.arange(len(v))
            ends = np.stack([k, np.roll(k, -1)], axis=1) if c.closed else np.stack([k[:-1], k[1:]], axis=1)
            if where is not None:
                ends = ends[np.asarray(where(c.points[ends[:, 0]], c.points[ends[:, 1]]), bool)]
            keys = (np.sort(v[ends], axis=1) @ np.array([n, 1])).tolist()
            bad += sum(count.get(k, 0) != c.half_sheets for k in keys)
        return bad

    def write_curves(self, path) -> Path:
        """Write the singular curves alone (every curve edge as a line cell) through meshio."""
        import meshio

        path = Path(path)
        pts, edges, _ = self.curve_graph
        m = meshio.Mesh(pts, [("line", np.asarray(edges, np.int64).reshape(-1, 2))])
        _write_atomic(path, lambda target: m.write(target, file_format="vtk"))
        return path

    def to_meshio(self):
        """The mesh as a ``meshio.Mesh``: triangles, and line cells for the one-dimensional part.

        Vertex normals are point data (zero at the points of an isolated
        line), and the curvatures (:meth:`curvature_data`; NaN there).
        """
        import meshio

        points, lines = self.curve_lines()
        cells = [("triangle", self.faces)] + ([("line", lines)] if len(lines) else [])
        extra = len(points) - len(self.vertices)
        data = {"Normals": np.vstack([self.normals, np.zeros((extra, 3))])}
        data.update({k: np.concatenate([v, np.full(extra, np.nan)]) for k, v in self.curvature_data().items()})
        return meshio.Mesh(points, cells, point_data=data)

    def to_trimesh(self):
        """The triangles as a ``trimesh.Trimesh`` (:func:`singmesh.convert.to_trimesh`; needs ``singmesh[trimesh]``)."""
        from .convert import to_trimesh

        return to_trimesh(self)

    def to_pyvista(self, curvature: bool = True):
        """The mesh as a ``pyvista.PolyData`` with line cells (:func:`singmesh.convert.to_pyvista`; needs ``singmesh[pyvista]``)."""
        from .convert import to_pyvista

        return to_pyvista(self, curvature=curvature)

    def to_html(self, *, inline_script: bool = True, script_src: str | None = None, height: int = 480) -> str:
        """A web page with the interactive 3-D view of the mesh (:func:`singmesh.view.mesh_html`), offline."""
        from .view import mesh_html

        return mesh_html(self, inline_script=inline_script, script_src=script_src, height=height)

    def _repr_html_(self) -> str:
        """The interactive 3-D view in a notebook (three.js inlined: no network needed)."""
        from .view import notebook_html

        return notebook_html(self)

    def write(self, path, file_format: str | None = None, curvature: bool = True) -> Path:
        """Write through meshio; the format comes from the suffix.

        ``.html`` is not meshio's: it writes :meth:`to_html`, a page with
        the interactive 3-D view (no network needed to open it).

        Formats with per-vertex arrays get the normals and, with
        ``curvature`` (the default), the curvatures as point data
        (``CURVATURE_FORMATS``: ``gaussian_curvature``, ``mean_curvature``,
        ``k1``, ``k2``; NaN where undefined and at the extra points of
        line cells).  OBJ, STL and OFF files hold neither.

        Raises
        ------
        ValueError
            For a suffix meshio is not asked to write here.
        """
        path = Path(path)
        fmt = file_format or FORMATS.get(path.suffix.lower())
        if fmt is None:
            raise ValueError(
                f"unknown mesh format {path.suffix!r}: use one of {', '.join(sorted(FORMATS))}")
        if fmt == "html":  # the interactive view, one self-contained page (curves and points in it)
            _write_atomic(path, lambda target: target.write_text(self.to_html(), encoding="utf-8"))
            return path
        import meshio

        faces = self.faces.astype(np.int32) if fmt == "ply" else self.faces
        if fmt in ("obj", "stl", "off"):
            point_data = {}  # these writers take no per-vertex arrays
        elif fmt == "ply":  # PLY stores normals as three scalar properties
            point_data = {k: np.ascontiguousarray(self.normals[:, i]) for i, k in enumerate(("nx", "ny", "nz"))}
        else:
            point_data = {"Normals": self.normals}
        if curvature and fmt in CURVATURE_FORMATS:
            point_data.update(self.curvature_data())
        points, lines = self.curve_lines()
        if fmt in LINE_FORMATS and len(lines):
            # Line cells in the same file: the one-dimensional part.
            extra = len(points) - len(self.vertices)
            # Curvature is not defined on the curves' extra points: NaN there.
            point_data = {k: np.concatenate([v, np.full((extra,) + v.shape[1:], np.nan if k in CURVATURE_NAMES
                                                        else 0.0)]) for k, v in point_data.items()}
            cell_data = {}
            if fmt == "gmsh":
                # Gmsh files with two cell types need the entity of each
                # node and cell (meshio refuses them otherwise): the
                # triangles are surface 1, the lines curve 2; a node is on
                # the surface if a triangle has it.
                dim_tags = np.tile([1, 2], (len(points), 1))
                dim_tags[np.unique(faces)] = [2, 1]
                point_data["gmsh:dim_tags"] = dim_tags
                cell_data = {k: [np.ones(len(faces), int), np.full(len(lines), 2)]
                             for k in ("gmsh:physical", "gmsh:geometrical")}
            m = meshio.Mesh(points, [("triangle", faces), ("line", lines)], point_data=point_data,
                            cell_data=cell_data)
        else:
            m = meshio.Mesh(self.vertices, [("triangle", faces)], point_data=point_data)
        kwargs = {"binary": True} if fmt in ("ply", "stl") else {}
        try:
            _write_atomic(path, lambda target: m.write(target, file_format=fmt, **kwargs), in_place=fmt == "xdmf")
        except ImportError as exc:  # XDMF needs h5py, an optional dependency of meshio
            raise ValueError(f"writing {path.suffix} files needs the package {exc.name} (pip install {exc.name})") from None
        if self.singular_curves and fmt not in LINE_FORMATS:
            # The format has no line cells: the curves go to a companion
            # file beside it (all curve edges, as a VTK polyline set).
            self.write_curves(path.with_suffix(".curves.vtk"))
        return path
