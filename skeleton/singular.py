"""Singular points: where F and all three partial derivatives vanish.

1. Candidate boxes: subdivide the domain with the Bernstein forms of F, Fx,
   Fy and Fz side by side (stacked arrays, whole-level operations) and
   keep a box only while all four may vanish on it.
2. Gauss-Newton on (F, Fx, Fy, Fz) from every candidate box centre, all at
   once in double precision.
3. Where the Hessian is degenerate (A2 and beyond, D, E) double precision
   only fixes the point to about eps**(1/k); those points are refined in
   multiple precision (mpmath) on the exact sympy polynomial, with a step
   scaled by the best of 1..8 times the Newton step (the multiplicity of
   the root along the kernel), which restores fast convergence.
4. Deduplicate across neighbouring boxes; read the Hessian's rank and
   signature.
"""

from __future__ import annotations

import numpy as np
import sympy

from singmesh import tolerances as tol
from singmesh.boxes.bernstein import bernstein_on_box, split
from singmesh.surface import VARIABLES, Surface

from .points import SingularPoint


def candidate_boxes(surface: Surface, box: np.ndarray, level: int, max_boxes: int = 4096, polys=None):
    """Boxes at ``level`` on which F, Fx, Fy, Fz (or ``polys``) may all vanish.

    Returns
    -------
    lo, hi : (K, 3) ndarrays, the boxes' corners
    overflow : bool
        True when the candidates grew past ``max_boxes`` (a curve of
        singular points, not isolated ones); the search stopped there.
    """
    if polys is None:
        polys = [surface.coeffs, *surface.gradient_coeffs]
    stacks = [bernstein_on_box(p, box)[None] for p in polys]
    corner = np.zeros((1, 3), np.int64)
    for lvl in range(level + 1):
        keep = np.ones(len(corner), bool)
        for s in stacks:
            flat = s.reshape(len(s), -1)
            # Exact zeros at box corners come out of the conversion as
            # +-1e-17: allow for the rounding, relative to the coefficients.
            slack = tol.CANDIDATE_SLACK * np.abs(flat).max(axis=1)
            keep &= (flat.min(axis=1) <= slack) & (flat.max(axis=1) >= -slack)
        stacks = [s[keep] for s in stacks]
        corner = corner[keep]
        if lvl == level or len(corner) == 0:
            break
        if len(corner) > max_boxes:
            return _corners(box, corner, lvl), True
        stacks = [split(s).reshape((-1,) + s.shape[1:]) for s in stacks]
        offsets = np.array(np.meshgrid([0, 1], [0, 1], [0, 1], indexing="ij")).reshape(3, -1).T
        corner = (2 * corner[:, None, :] + offsets[None]).reshape(-1, 3)
    return _corners(box, corner, level), False


def _corners(box, corner, level):
    h = (box[:, 1] - box[:, 0]) / (1 << level)
    lo = box[:, 0] + corner * h
    return (lo, lo + h)


def gauss_newton(surface: Surface, x: np.ndarray, iterations: int = 40) -> np.ndarray:
    """Least-squares Newton on (F, grad F) = 0 from many starts at once."""
    x = np.array(x, dtype=float)
    for _ in range(iterations):
        f = surface(x)
        g = surface.gradient(x)
        h = surface.hessian(x)
        r = np.concatenate([f[:, None], g], axis=1)  # (K, 4)
        j = np.concatenate([g[:, None, :], h], axis=1)  # (K, 4, 3)
        step = np.einsum("kij,kj->ki", np.linalg.pinv(j, rcond=1e-12), r)
        x = x - step
    return x


def residual(surface: Surface, x: np.ndarray) -> np.ndarray:
    """max(|F|, |grad F|) relative to the size of F's terms at x."""
    f = np.abs(surface(x))
    g = np.abs(surface.gradient(x)).max(axis=-1)
    scale = np.maximum(surface.magnitude(x), np.abs(surface.coeffs).max())
    return np.maximum(f, g) / scale


def hessian_signature(h: np.ndarray, scale: float) -> tuple[int, int, int]:
    """(positive, negative, zero) eigenvalues; zero means below
    ``HESSIAN_RANK`` times ``scale`` (the size of F's second derivatives)."""
    w = np.linalg.eigvalsh(0.5 * (h + h.T))
    cut = tol.HESSIAN_RANK * max(scale, 1e-300)
    return int((w > cut).sum()), int((w < -cut).sum()), int((np.abs(w) <= cut).sum())


# Tried in this order; the search stops at the first group that improves.
_STEP_GROUPS = ((1, 2, 3, 4, 5, 6, 7, 8), (0.5, 0.25, 0.125, 1 / 16, 1 / 64, 1 / 256))


class _MultiPrecision:
    """grad F and the Hessian of the exact polynomial, in mpmath."""

    def __init__(self, surface: Surface, dps: int):
        import mpmath

        self.mp = mpmath.mp.clone() if hasattr(mpmath.mp, "clone") else mpmath.mp
        self.dps = dps
        grad = [sympy.diff(surface.expr, v) for v in VARIABLES]
        hess = [[sympy.diff(g, v) for v in VARIABLES] for g in grad]
        self.grad = sympy.lambdify(VARIABLES, grad, modules="mpmath")
        self.hess = sympy.lambdify(VARIABLES, hess, modules="mpmath")

    def refine(self, x0: np.ndarray, iterations: int = 200) -> np.ndarray:
        import mpmath

        with mpmath.workdps(self.dps):
            x = mpmath.matrix([mpmath.mpf(float(c)) for c in x0])
            norm = lambda v: mpmath.sqrt(sum(c * c for c in v))  # noqa: E731
            g = mpmath.matrix(self.grad(*x))
            for _ in range(iterations):
                h = mpmath.matrix(self.hess(*x))
                u, s, v = mpmath.svd_r(h)
                smax = max(s)
                if smax == 0:
                    break
                # Pseudo-inverse step, ignoring directions the Hessian does
                # not see at this precision.
                # Near an A_k point the kernel eigenvalue is ~t^(k-1): keep it
                # down to what the working precision can still resolve.
                cut = smax * mpmath.mpf(10) ** (-(self.dps - 10))
                coeff = [(u[:, i].T * g)[0] / s[i] if s[i] > cut else 0 for i in range(3)]
                step = sum((v[i, :].T * coeff[i] for i in range(3)), mpmath.matrix(3, 1))
                best, best_x, best_g = norm(g), None, None
                # Along the kernel of an A_k point, grad F ~ t^k and the
                # Newton step is t/k: try multiples of it; where the
                # Jacobian is nearly singular it may overshoot: try halves.
                for group in _STEP_GROUPS:
                    for m in group:
                        xt = x - m * step
                        gt = mpmath.matrix(self.grad(*xt))
                        if norm(gt) < best:
                            best, best_x, best_g = norm(gt), xt, gt
                    if best_x is not None:
                        break
                if best_x is None:
                    break
                moved = norm(best_x - x)
                x, g = best_x, best_g
                if moved < mpmath.mpf(10) ** (-self.dps + 10):
                    break
            return np.array([float(c) for c in x])


def singular_points(surface: Surface, box, level: int = 8) -> tuple[list[SingularPoint], bool]:
    """Isolated singular points of F = 0 in ``box``.

    Parameters
    ----------
    surface : Surface
    box : (3, 2) array_like
    level : int
        Depth of the candidate search (``2**level`` boxes per axis).

    Returns
    -------
    points : list of SingularPoint, sorted by coordinates
    overflow : bool
        True when the candidates look like a curve of singular points
        (non-isolated singularities); the points found are then partial.
    """
    box = np.asarray(box, dtype=float)
    (lo, hi), overflow = candidate_boxes(surface, box, level)
    if len(lo) == 0:
        return [], overflow

    x = gauss_newton(surface, (lo + hi) / 2)
    size = box[:, 1] - box[:, 0]
    margin = 1e-9 * size
    inside = np.all((x >= box[:, 0] - margin) & (x <= box[:, 1] + margin), axis=1)
    # Accept loosely first: degenerate points are only fixed to ~eps^(1/k)
    # in double precision.  The multiple-precision pass decides.
    near_cell = np.all(np.abs(x - (lo + hi) / 2) <= 2.0 * (hi - lo), axis=1)
    ok = inside & near_cell & np.isfinite(x).all(axis=1) & (residual(surface, x) < tol.SINGULAR_LOOSE)
    # Double precision scatters the candidates of one degenerate point over
    # about eps^(1/k): one representative per cluster of candidates within
    # two candidate boxes (the best residual) is refined, not every one.
    x = x[ok]
    x, spans = _dedupe(x, 2.0 * float(np.max(hi[0] - lo[0])), key=residual(surface, x), spans=True)
    # A cluster spreading over many candidate boxes is a curve of singular
    # points (cross-cap, Whitney umbrella): not meshed as a point.
    curve = spans > 8.0 * float(np.max(hi[0] - lo[0]))
    overflow = overflow or bool(curve.any())
    x = x[~curve]
    hscale = max(max(np.abs(c).max() for row in surface.hessian_coeffs for c in row), 1e-300)
    mp = None
    out = []
    refined = 0
    for p in x:
        h = surface.hessian(p)
        sig = hessian_signature(h, hscale)
        w = np.abs(np.linalg.eigvalsh(0.5 * (h + h.T)))
        # Near-degenerate (or not yet converged) points go to multiple
        # precision: at a point off by 1e-8 a degenerate Hessian can look
        # regular at the rank tolerance.
        if w.min() < tol.SINGULAR_REFINE * max(w.max(), 1e-300) or residual(surface, p) > tol.SINGULAR_RESIDUAL:
            if refined >= tol.SINGULAR_MAX_REFINE:
                # So many degenerate candidates are a curve of singular
                # points, not isolated ones: stop, and say so.
                overflow = True
                continue
            refined += 1
            mp = mp or _MultiPrecision(surface, tol.SINGULAR_DPS)
            p = mp.refine(p)
            h = surface.hessian(p)
            sig = hessian_signature(h, hscale)
        res = float(residual(surface, p))
        if res > tol.SINGULAR_RESIDUAL:
            continue
        if not np.all((p >= box[:, 0] - margin) & (p <= box[:, 1] + margin)):
            continue
        out.append(SingularPoint(point=p, residual=res, hessian_rank=3 - sig[2], signature=sig))
    pts = _dedupe(np.array([s.point for s in out]).reshape(-1, 3), tol.SINGULAR_MERGE * size.max())
    keep = []
    for q in pts:
        keep.append(min(out, key=lambda s: np.linalg.norm(s.point - q)))
    keep.sort(key=lambda s: tuple(s.point))
    return keep, overflow


def _dedupe(x: np.ndarray, radius: float, key: np.ndarray | None = None, spans: bool = False):
    """One representative per cluster of points closer than ``radius``.

    The representative is the member with the smallest ``key`` (default:
    the one nearest the cluster's centre); the choice is deterministic.
    With ``spans``, also return each cluster's extent (largest side of its
    bounding box).
    """
    from scipy.cluster.hierarchy import fcluster, linkage

    if len(x) <= 1:
        x = x.reshape(-1, 3)
        return (x, np.zeros(len(x))) if spans else x
    # linkage takes the (n, 3) observations; a 3x3 array of points only
    # looks like a distance matrix to it, hence the explicit metric.
    labels = fcluster(linkage(x, method="single", metric="euclidean"), t=radius, criterion="distance")
    reps, extent = [], []
    for lab in np.unique(labels):
        sel = labels == lab
        members = x[sel]
        extent.append(np.ptp(members, axis=0).max())
        if key is not None:
            reps.append(members[np.lexsort((members[:, 2], members[:, 1], members[:, 0], key[sel]))[0]])
            continue
        c = members.mean(axis=0)
        reps.append(members[np.argmin(np.linalg.norm(members - c, axis=1))])
    reps = np.array(reps)
    order = np.lexsort(reps.T[::-1])
    return (reps[order], np.array(extent)[order]) if spans else reps[order]


def skeleton_nodes(surface: Surface, box, level: int = 6) -> tuple[np.ndarray, np.ndarray]:
    """Points where F and two partial derivatives vanish but grad F does not.

    There the x-, y- or z-skeleton curves V(F, F_a), V(F, F_b) meet: the
    surface normal is along the third axis.  Found like singular points:
    Bernstein candidates for (F, F_a, F_b), then Newton on that square
    system from every candidate at once.

    Returns
    -------
    points : (k, 3) ndarray, sorted
    axes : (k, 2) int64, the pair (a, b) of vanishing derivatives
    """
    box = np.asarray(box, dtype=float)
    grads = surface.gradient_coeffs
    size = box[:, 1] - box[:, 0]
    found, pairs = [], []
    for a, b in ((0, 1), (0, 2), (1, 2)):
        (lo, hi), overflow = candidate_boxes(surface, box, level, polys=[surface.coeffs, grads[a], grads[b]])
        if overflow or len(lo) == 0:
            continue  # a whole curve of them (e.g. a surface of revolution): not points
        x = (lo + hi) / 2
        live = np.ones(len(x), bool)
        for _ in range(30):
            f, g, h = surface.jet(x[live])
            r = np.stack([f, g[:, a], g[:, b]], axis=1)
            j = np.stack([g, h[:, a], h[:, b]], axis=1)
            with np.errstate(over="ignore", invalid="ignore"):
                ok = np.abs(np.linalg.det(j)) > 1e-300
            step = np.zeros((live.sum(), 3))
            step[ok] = np.linalg.solve(j[ok], r[ok][..., None])[..., 0]
            x[live] = x[live] - step
            # Starts that run off the box are dropped, not followed to overflow.
            live &= np.all(np.abs(x - box.mean(axis=1)) <= size, axis=1)
            if not live.any():
                break
        x = x[live]
        f, g, _ = surface.jet(x)
        scale = np.maximum(surface.magnitude(x), 1e-300)
        gn = np.linalg.norm(g, axis=1)
        good = (np.isfinite(x).all(axis=1)
                & np.all((x >= box[:, 0] - 1e-9 * size) & (x <= box[:, 1] + 1e-9 * size), axis=1)
                & (np.abs(f) <= 1e-12 * scale) & (np.abs(g[:, a]) <= 1e-10 * gn) & (np.abs(g[:, b]) <= 1e-10 * gn)
                & (gn > tol.SINGULAR_LOOSE * np.abs(surface.coeffs).max()))
        # Newton from boxes along a curve of such points (Cayley's cubic has
        # lines of them) lands all along it: clusters that long are curves.
        step = float(np.max(hi[0] - lo[0]))
        reps, extent = _dedupe(x[good], 2.0 * step, spans=True)
        pts = _dedupe(reps[extent <= 8.0 * step], tol.SINGULAR_MERGE * size.max())
        found.append(pts)
        pairs.append(np.tile([a, b], (len(pts), 1)))
    if not found:
        return np.zeros((0, 3)), np.zeros((0, 2), np.int64)
    return np.concatenate(found), np.concatenate(pairs).astype(np.int64)
