"""Curvature-adaptive sizing: which boxes of a level are too large for the surface's curvature.

The mesh's edges are about as long as the leaf boxes holding them.  An arc
of curvature k over a chord of length e is off the chord by about
``k e^2 / 8``: a chord tolerance ``delta`` asks for edges no longer than
``e = sqrt(8 delta / k)``, with ``k = max(|k1|, |k2|)`` (the principal
curvatures, :mod:`singmesh.curvature`); exactly, the chord whose sagitta
is delta, ``2 sqrt(delta (2/k - delta))``, and no limit where delta is
over the radius 1/k (the arc cannot be farther than that from its chord).  A box is split while its side is
longer than that at some point of the surface in it, down to the level of
the smallest edge allowed.

The surface's points in a box are found by a few Newton steps from the
box's centre and its eight corners (all boxes of a level at once); those
that land in the box (slightly widened) are the samples.  A box whose
curved part no sample reaches is not split for curvature: its children
are sampled again only if the simplicity test splits it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from singmesh import tolerances as tol
from singmesh.errors import SurfaceError
from singmesh.curvature import curvatures

#: The centre and the eight corners of a box, in units of its side.
_SAMPLES = np.vstack([[0.5, 0.5, 0.5], np.array(np.meshgrid([0, 1], [0, 1], [0, 1], indexing="ij")).reshape(3, -1).T])


def sizing_levels(size: str, min_edge, max_edge, chord, fine_level: int) -> tuple[int, int, float] | None:
    """(coarse level, smallest-edge level, chord) of ``size="curvature"``; None for ``"uniform"``.

    Raises
    ------
    SurfaceError
        An unknown ``size``, limits given without ``size="curvature"``, or
        limits that are not numbers in (0, 1] in order.
    """
    if size == "uniform":
        given = [n for n, v in (("min_edge", min_edge), ("max_edge", max_edge), ("chord", chord)) if v is not None]
        if given:
            raise SurfaceError(f"{', '.join(given)} go(es) with size='curvature', not size='uniform'")
        return None
    if size != "curvature":
        raise SurfaceError(f"size must be 'uniform' or 'curvature', not {size!r}")
    values = {"min_edge": 1.0 / (1 << fine_level) if min_edge is None else min_edge,
              "max_edge": tol.SIZING_MAX_EDGE if max_edge is None else max_edge,
              "chord": tol.SIZING_CHORD if chord is None else chord}
    for name, v in values.items():
        if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)) \
                or not np.isfinite(v) or not 0 < v <= 1:
            raise SurfaceError(f"{name} is a fraction of the box's longest side in (0, 1], not {v!r}")
    if values["min_edge"] > values["max_edge"]:
        raise SurfaceError(f"min_edge ({values['min_edge']:g}) is larger than max_edge ({values['max_edge']:g})")
    # Boxes halve level by level: no box longer than max_edge, none split
    # below min_edge (a tiny slack: 1/8 is level 3, not 4 by rounding).
    coarse_level = max(0, int(np.ceil(np.log2(1.0 / values["max_edge"]) - 1e-9)))
    min_level = max(coarse_level, int(np.floor(np.log2(1.0 / values["min_edge"]) + 1e-9)))
    if min_level > fine_level:
        raise SurfaceError(f"min_edge = {values['min_edge']:g} is below the finest boxes (1/fine = "
                           f"{1 / (1 << fine_level):g}): raise fine or min_edge")
    return coarse_level, min_level, float(values["chord"])


@dataclass
class CurvatureSizing:
    """Split boxes longer than the edge the curvature asks for.

    Attributes
    ----------
    surface : Surface
    box : (3, 2) float64
        The domain.
    fine_level : int
        Lattice units are cells of this level (the octree's).
    chord : float
        The chord tolerance delta, in space units.
    min_level : int
        Boxes of this level are never split for curvature (the level of
        the smallest edge allowed).
    """

    surface: object
    box: np.ndarray
    fine_level: int
    chord: float
    min_level: int

    def target_level(self, points: np.ndarray) -> np.ndarray:
        """The level whose triangles' edges are at most ``sqrt(8 chord / k)`` at each point (NaN curvature: 0)."""
        k = np.abs(curvatures(self.surface, points).principal).max(axis=1) if len(points) else np.zeros(0)
        k = np.where(np.isfinite(k), k, 0.0)
        # The sagitta of an arc of radius r = 1/k over a chord e is
        # r - sqrt(r^2 - e^2/4) (about k e^2 / 8), and never more than r:
        # the chord e = 2 sqrt(delta (2r - delta)) keeps it to delta, and
        # where delta >= r (a feature thinner than the tolerance) any edge does.
        r = 1.0 / np.maximum(k, 1e-300)
        d = self.chord
        edge = np.where(d < r, 2 * np.sqrt(np.maximum(d * (2 * r - d), 0.0)), np.inf)
        side = float((self.box[:, 1] - self.box[:, 0]).max())
        # A box's triangles have edges longer than its side (diagonals):
        # box side * SIZING_EDGE_PER_SIDE <= edge  <=>  L >= log2(side * c / edge).
        with np.errstate(divide="ignore"):
            level = np.ceil(np.log2(side * tol.SIZING_EDGE_PER_SIDE / edge))
        return np.clip(level, 0, self.min_level).astype(np.int64)

    def __call__(self, level: int, corner: np.ndarray) -> np.ndarray:
        """(K,) bool: the boxes of ``level`` with lattice corners ``corner`` (K, 3) to split for curvature."""
        if level >= self.min_level or len(corner) == 0:
            return np.zeros(len(corner), bool)
        cell = (self.box[:, 1] - self.box[:, 0]) / (1 << self.fine_level)
        size = (1 << (self.fine_level - level)) * cell
        lo = self.box[:, 0] + corner * cell
        starts = (lo[:, None, :] + _SAMPLES[None] * size).reshape(-1, 3)
        owner = np.repeat(np.arange(len(corner)), len(_SAMPLES))
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            p = self.surface.project(starts, iterations=tol.SIZING_NEWTON)
            f = self.surface(p)
        # Samples: converged (|F| small against its terms) and in their box.
        slack = tol.SIZING_BOX_SLACK * size
        inside = ((p >= lo[owner] - slack) & (p <= lo[owner] + size + slack)).all(axis=1)
        on = np.abs(f) <= tol.SIZING_RESIDUAL * np.maximum(self.surface.magnitude(p), 1e-300)
        keep = inside & on & np.isfinite(p).all(axis=1)
        want = np.zeros(len(corner), np.int64)
        if keep.any():
            np.maximum.at(want, owner[keep], self.target_level(p[keep]))
        return want > level
