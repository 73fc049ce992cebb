"""Skeleton curves V(F, grad F . v) from a singular point out to its link cycles.

Around a singular point p the surface meets the boundary of p's star (the
leaves whose closure holds p) in cycles of face links, one per branch.
A skeleton curve through p crosses such a cycle at a *face node*: a point
of the face curve where G = grad F . v changes sign.  This module finds
the face nodes on a cycle (sign change of G between consecutive link
vertices, then Newton on F = G = 0 in the face's plane), traces each one's
curve inward to p (predictor along grad F x grad G, corrector onto
F = G = 0), and keeps the nodes whose curve reaches p.  The traced points
become mesh vertices on the links node -> p.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from singmesh import tolerances as tol
from singmesh.surface import Surface


@dataclass
class SkeletonLink:
    """A traced skeleton curve from a face node to the singular point.

    Attributes
    ----------
    after : int
        The node lies on the cycle link from vertex ``after`` to the next.
    t : float
        Place of the node along that link (0..1), to order nodes.
    node : (3,) ndarray
    trace : (k, 3) ndarray
        Points on the curve from the node towards p (p itself excluded).
    direction : (3,) ndarray
        The v of V(F, grad F . v).
    vertex : int or None
        When the node is (to rounding) a vertex of the cycle, that vertex;
        the spoke then ends there and no new vertex is made.
    """

    after: int
    t: float
    node: np.ndarray
    trace: np.ndarray
    direction: np.ndarray = field(default_factory=lambda: np.zeros(3))
    vertex: int | None = None


def _face_node(surface: Surface, v: np.ndarray, a: np.ndarray, b: np.ndarray, square: np.ndarray):
    """Point of F = 0, grad F . v = 0 in a face square, on the arc from a to b.

    ``square`` is (axis, lo, hi) with lo, hi the square's corners in space.
    Newton starts half-way between the link's midpoint and the square's
    centre: two arcs with the same end points (the two halves of a thin
    lens) then find their own nodes.
    """
    axis, lo, hi = square
    u, w = [i for i in range(3) if i != axis]
    q = 0.5 * (0.5 * (a + b) + 0.5 * (lo + hi))
    q[axis] = a[axis]
    for _ in range(30):
        f, g, h = surface.jet(q)
        gv = g @ v
        hv = h @ v
        jac = np.array([[g[u], g[w]], [hv[u], hv[w]]])
        try:
            step = np.linalg.solve(jac, [f, gv])
        except np.linalg.LinAlgError:
            return None
        q = q.copy()
        q[u] -= step[0]
        q[w] -= step[1]
        if np.abs(step).max() < 1e-15 * (1 + np.abs(q).max()):
            break
    if not np.isfinite(q).all() or abs(surface(q)) > 1e-11 * (1 + np.abs(surface.gradient(q)).max()):
        return None
    # The node must lie in this link's square.
    slack = 1e-9 * (hi - lo).max()
    if (q < lo - slack).any() or (q > hi + slack).any():
        return None
    d = b - a
    t = float(np.clip(np.dot(q - a, d) / max(np.dot(d, d), 1e-300), 0, 1))
    return q, t


def _correct(surface: Surface, v: np.ndarray, q: np.ndarray, iterations: int = 20):
    """Gauss-Newton (minimum-norm steps) from q onto F = 0, grad F . v = 0."""
    for _ in range(iterations):
        f, g, h = surface.jet(q)
        r = np.array([f, g @ v])
        j = np.stack([g, h @ v])
        # Minimum-norm step j^T (j j^T)^-1 r: a 2x2 solve, cheaper than pinv.
        jj = j @ j.T
        if abs(np.linalg.det(jj)) <= 1e-300:
            break
        step = j.T @ np.linalg.solve(jj, r)
        q = q - step
        if np.linalg.norm(step) < 1e-15 * (1 + np.linalg.norm(q)):
            break
    return q


def trace_to_point(surface: Surface, v: np.ndarray, node: np.ndarray, p: np.ndarray, pieces: int = 3):
    """Trace V(F, grad F . v) from ``node`` to ``p``; None if it does not get there.

    The curve is followed in ``pieces`` steps of a third of the distance:
    predictor along the tangent grad F x grad G (oriented towards p),
    corrector onto the curve.  It must come closer to p at every step and
    end within one step of p.
    """
    dist0 = np.linalg.norm(node - p)
    if dist0 == 0:
        return None
    h = dist0 / pieces
    q = node.copy()
    points = []
    for k in range(pieces - 1):
        _, g, hess = surface.jet(q)
        tangent = np.cross(g, hess @ v)
        norm = np.linalg.norm(tangent)
        if norm == 0:
            return None
        tangent /= norm
        if np.dot(tangent, p - q) < 0:
            tangent = -tangent
        target = dist0 * (pieces - 1 - k) / pieces
        guess = q + h * tangent
        new = _correct(surface, v, guess)
        d = np.linalg.norm(new - p)
        on = abs(surface(new)) <= 1e-10 * (1 + np.abs(surface.gradient(new)).max()) * max(dist0, 1e-300)
        if not on or not np.isfinite(new).all() or abs(d - target) > 0.5 * h or np.linalg.norm(new - q) > 2 * h:
            return None
        points.append(new)
        q = new
    return np.array(points).reshape(-1, 3)


def skeleton_links(surface: Surface, p: np.ndarray, cycle_points: np.ndarray, squares: list,
                   directions: np.ndarray, want: int = 4, max_directions: int = 2) -> list[SkeletonLink]:
    """Face nodes on one link cycle of p whose skeleton curve reaches p.

    Parameters
    ----------
    cycle_points : (m, 3) the cycle's vertices in order (consecutive ones
        share a face)
    squares : m entries (axis, lo, hi): the face square of the link from
        vertex i to vertex i + 1
    directions : (k, 3) candidate v, best first
    want : stop adding directions once this many nodes are linked
    max_directions : use at most this many directions per cycle

    Returns
    -------
    list of SkeletonLink, ordered along the cycle
    """
    m = len(cycle_points)
    links: list[SkeletonLink] = []
    used = 0
    for v in directions:
        if used >= max_directions or len(links) >= want:
            break
        g = surface.gradient(cycle_points) @ v
        found = []
        for i in range(m):
            a, b = cycle_points[i], cycle_points[(i + 1) % m]
            if g[i] * g[(i + 1) % m] >= 0:
                continue
            res = _face_node(surface, v, a, b, squares[i])
            if res is None:
                continue
            node, t = res
            near = tol.NODE_ON_VERTEX * np.linalg.norm(b - a)
            vertex = None
            # A node on (or next to) a cycle vertex: the skeleton passes
            # through that vertex; anchor the spoke there.  A separate node a
            # hair away would leave a sliver between the two.
            if np.linalg.norm(node - a) <= near:
                vertex, node, t = i, a.copy(), 0.0
            elif np.linalg.norm(node - b) <= near:
                vertex, node, t = (i + 1) % m, b.copy(), 1.0
            if any(np.linalg.norm(node - s.node) <= near for s in links + found):
                continue  # two directions crossing the cycle at one point
            trace = trace_to_point(surface, v, node, p)
            if trace is None:
                continue
            found.append(SkeletonLink(after=i, t=t, node=node, trace=trace, direction=v, vertex=vertex))
        if found:
            links.extend(found)
            used += 1
    links.sort(key=lambda s: (s.after, s.t))
    return links
