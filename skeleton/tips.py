"""Tips: isolated points of the surface where F is continuous but not differentiable.

A root of a sum of squares in F (``Surface.tip_systems``: the cone
sqrt(x^2 + y^2) = |z|, the tip of (x^2 + y^2)^(1/3) + z^2 = 1/2) has
infinite derivatives on the zero set of its squares; where that meets
F = 0 the surface has a point that is not smooth, which grad F = 0 does
not find.  Each such point is found as the common zero of the tip
system's smooth equations (F with the root replaced by 0, and the bases
of the squares):

1. Candidate boxes: subdivide the box, keeping those where all the
   equations may vanish (interval bounds), ``level`` times.
2. Gauss-Newton on the equations from each candidate's centre, all at
   once; a start that ends on a common zero (to rounding) inside the box,
   where F - F0 grows like the root away from it (slower than t^2), is a
   tip.
3. Tips closer than ``SINGULAR_MERGE`` of the box are one.

They are meshed as singular points are, with a star whose link cycles
are coned to the point; the classification says what they are.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from singmesh import tolerances as tol
from singmesh.surface import Surface, boxes_where

from .classify import SingularityType
from .points import SingularPoint
from .singular import _clumps

#: The name tips are classified by.
TIP = "non-differentiable"


def tip_points(surface: Surface, box, level: int = 8) -> tuple[list[SingularPoint], bool]:
    """The points of F = 0 in ``box`` where a root of a sum of squares in F vanishes.

    Returns
    -------
    points : list of SingularPoint, sorted by coordinates, each classified
        ``TIP`` (its note names the root)
    not_isolated : bool
        True when such zeros lie along a curve (the edge y = z = 0 of the
        half-plane where sqrt(y^2 + z^2) - z touches 0): they are not
        points, and are not in ``points``.
    """
    box = np.asarray(box, dtype=float)
    size = box[:, 1] - box[:, 0]
    found, names = [], []
    not_isolated = False
    for system in surface.tip_systems():
        x = _kinked_zeros(surface, system, box, level)
        chain = _chains(x, box, level)
        not_isolated |= bool(chain.any())
        x = x[~chain]
        found.append(x)
        names += [system.name] * len(x)
    if not found or not sum(len(f) for f in found):
        return [], not_isolated
    x = np.concatenate(found)
    order = np.lexsort(x.T[::-1])
    x, names = x[order], [names[i] for i in order]
    out = []
    merge = tol.SINGULAR_MERGE * float(size.max())
    tree = cKDTree(x)
    taken = np.zeros(len(x), bool)
    for i, (p, name) in enumerate(zip(x, names)):
        if taken[i]:
            continue
        taken[tree.query_ball_point(p, merge)] = True
        kind = SingularityType(name=TIP, real_form=None, corank=3, milnor=None, branches=None, axis=None,
                               hessian_signature=(0, 0, 3), jet="", point=tuple(float(c) for c in p),
                               note=f"F is not differentiable here (a {name} vanishes): not an ADE point")
        out.append(SingularPoint(point=p, residual=float(abs(surface(p[None])[0])), hessian_rank=0,
                                 signature=(0, 0, 3), classification=kind))
    return out, not_isolated


def _chains(x: np.ndarray, box: np.ndarray, level: int) -> np.ndarray:
    """(k,) bool: the zeros ``x`` in a clump of boxes of ``level`` at least ``CURVE_SPAN`` long.

    Gauss-Newton from the candidate boxes along a curve of such zeros ends
    all along it, a few per box: a chain, not isolated points (as the
    singular point search reads its candidate clumps).
    """
    if len(x) < tol.CURVE_SPAN:
        return np.zeros(len(x), bool)
    h = (box[:, 1] - box[:, 0]) / (1 << level)
    cells = np.floor((x - box[:, 0]) / h).astype(np.int64)
    label, span = _clumps(cells)
    return span[label] >= tol.CURVE_SPAN


def _kinked_zeros(surface: Surface, system, box: np.ndarray, level: int) -> np.ndarray:
    """Common zeros (k, 3) of the system's equations on F = 0 in ``box`` where the root kinks F.

    Gauss-Newton (minimum-norm steps) from the centres of the boxes at
    ``level`` where all the equations may vanish.
    """
    size = box[:, 1] - box[:, 0]
    _, corner = boxes_where(surface, box, level, system.may_vanish)
    if len(corner) == 0:
        return np.zeros((0, 3))
    x = box[:, 0] + (corner + 0.5) * size / (1 << level)
    for _ in range(tol.TIP_NEWTON_STEPS):
        r, j = system.values(x)
        good = np.isfinite(r).all(axis=1) & np.isfinite(j).all(axis=(1, 2))
        step = np.zeros_like(x)
        step[good] = np.einsum("kij,kj->ki", np.linalg.pinv(j[good], rcond=1e-12), r[good])
        x = np.where(good[:, None], x - step, np.nan)
    r, j = system.values(x)
    scale = np.maximum(np.abs(j).max(axis=(1, 2)), 1.0) * float(size.max())
    ok = np.isfinite(x).all(axis=1) & (np.abs(r).max(axis=1) <= tol.TIP_RESIDUAL * scale)
    ok &= np.all((x >= box[:, 0]) & (x <= box[:, 1]), axis=1)
    ok[ok] = surface.is_zero(x[ok]) | (np.abs(surface(x[ok])) <= tol.TIP_RESIDUAL * scale[ok])
    # The root must make F non-differentiable there: F - F0 grows like
    # the root (t, t^(2/3)) away from the point, not like t^2 (as
    # cos(k sqrt(u)) - 1, analytic in u, on seed 000's cosine bump,
    # whose axis point is a smooth or ADE point of its own).
    if ok.any():
        ok[ok] = _kinked(surface, system, x[ok], tol.TIP_PROBE * float(size.max()))
    return x[ok]


def root_creases(surface: Surface, box, level: int = 6) -> list[tuple[str, np.ndarray]]:
    """Roots in F that vanish along a curve of F = 0 (a cuspidal crease): (name, a point of it) each.

    Not meshed as creases (the mesh near them is not right): :func:`singmesh.mesh` says so.
    """
    box = np.asarray(box, dtype=float)
    out = []
    for system in surface.root_crease_systems():
        x = _kinked_zeros(surface, system, box, level)
        if len(x):
            out.append((system.name, x[np.lexsort(x.T[::-1])][0]))
    return out


def _kinked(surface: Surface, system, x: np.ndarray, t: float) -> np.ndarray:
    """(k,) bool: F - F0 at distance t and 2t from the points x grows slower than quadratically."""
    e = np.concatenate([np.eye(3), -np.eye(3)])
    size = []
    for step in (t, 2.0 * t):
        p = (x[:, None, :] + step * e[None]).reshape(-1, 3)
        d = surface(p) - system.values(p)[0][:, 0]
        size.append(np.nanmax(np.abs(d).reshape(len(x), 6), axis=1))
    d1, d2 = size
    return (d1 > 0) & (d2 < tol.TIP_ORDER * d1)
