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

from .swing import Swing


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
    return skeleton_links_many(surface, [(p, cycle_points, squares, directions)], want, max_directions)[0]


# ------------------------------------------------------------- all at once
def _lengths(v: np.ndarray) -> np.ndarray:
    """np.linalg.norm of each row of ``v`` (K, 3), with its bits: the square
    root of the same BLAS dot product (matmul of a row by a column)."""
    return np.sqrt(np.matmul(v[:, None, :], v[:, :, None])[:, 0, 0])


def _solve_stack(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Solve stacked systems a x = b; (x, ok), ok False where a is singular.

    One LAPACK call for the stack; only if one of them is singular are they
    solved one by one, to tell which.
    """
    try:
        return np.linalg.solve(a, b[..., None])[..., 0], np.ones(len(a), bool)
    except np.linalg.LinAlgError:
        x = np.zeros(b.shape)
        ok = np.ones(len(a), bool)
        for k in range(len(a)):
            try:
                x[k] = np.linalg.solve(a[k], b[k])
            except np.linalg.LinAlgError:
                ok[k] = False
        return x, ok


def _face_nodes(surface: Surface, v, a, b, axis, lo, hi):
    """Points of F = 0, grad F . v = 0 in face squares, on the arcs from a to b.

    One row per link: its v, end points ``a``, ``b`` and face square (the
    ``axis`` normal to it, corners ``lo``, ``hi`` in space).  Newton in the
    face's plane starts half-way between the link's midpoint and the
    square's centre: two arcs with the same end points (the two halves of
    a thin lens) then find their own nodes.

    Returns
    -------
    q : (K, 3) the nodes
    t : (K,) place of each along its link (0..1), to order them
    ok : (K,) False where Newton failed or the node is outside the square
    """
    k = len(v)
    rows = np.arange(k)
    u = np.where(axis == 0, 1, 0)
    w = np.where(axis == 2, 1, 2)
    q = 0.5 * (0.5 * (a + b) + 0.5 * (lo + hi))
    q[rows, axis] = a[rows, axis]
    ok = np.ones(k, bool)
    live = np.ones(k, bool)
    swing = Swing(30)
    with np.errstate(all="ignore"):
        for _ in range(30):
            at = np.nonzero(live)[0]
            if len(at) == 0:
                break
            last = swing.cycle(at, q[at])
            if last is not None:
                q[at] = last  # the live points alternate between two values to the end
                break
            f, g, h = surface.jet(q[at])
            r = np.arange(len(at))
            gv = np.einsum("ki,ki->k", g, v[at])
            hv = np.einsum("kij,kj->ki", h, v[at])
            uu, ww = u[at], w[at]
            jac = np.stack([np.stack([g[r, uu], g[r, ww]], 1), np.stack([hv[r, uu], hv[r, ww]], 1)], 1)
            step, solved = _solve_stack(jac, np.stack([f, gv], 1))
            ok[at[~solved]] = False
            live[at[~solved]] = False
            at, step, uu, ww = at[solved], step[solved], uu[solved], ww[solved]
            q[at, uu] -= step[:, 0]
            q[at, ww] -= step[:, 1]
            live[at[np.abs(step).max(axis=1) < 1e-15 * (1 + np.abs(q[at]).max(axis=1))]] = False
        ok &= np.isfinite(q).all(axis=1)
        at = np.nonzero(ok)[0]
        ok[at] = ~(np.abs(surface(q[at])) > 1e-11 * (1 + np.abs(surface.gradient(q[at])).max(axis=1)))
        # The node must lie in this link's square.
        slack = 1e-9 * (hi - lo).max(axis=1, keepdims=True)
        ok &= ~((q < lo - slack).any(axis=1) | (q > hi + slack).any(axis=1))
        d = b - a
        t = np.clip(np.einsum("ki,ki->k", q - a, d) / np.maximum(np.einsum("ki,ki->k", d, d), 1e-300), 0, 1)
    return q, t, ok


def _correct_many(surface: Surface, v: np.ndarray, q: np.ndarray, iterations: int = 20) -> np.ndarray:
    """Gauss-Newton (minimum-norm steps) from each q onto F = 0, grad F . v = 0 (its own v)."""
    q = np.array(q, dtype=float)
    live = np.ones(len(q), bool)
    swing = Swing(iterations)
    for _ in range(iterations):
        at = np.nonzero(live)[0]
        if len(at) == 0:
            break
        last = swing.cycle(at, q[at])
        if last is not None:
            q[at] = last  # the live points alternate between two values to the end
            break
        f, g, h = surface.jet(q[at])
        r = np.stack([f, np.einsum("ki,ki->k", g, v[at])], 1)
        j = np.stack([g, np.einsum("kij,kj->ki", h, v[at])], 1)  # (n, 2, 3)
        jj = j @ j.transpose(0, 2, 1)
        flat = np.abs(np.linalg.det(jj)) <= 1e-300
        live[at[flat]] = False
        at, j, jj, r = at[~flat], j[~flat], jj[~flat], r[~flat]
        sol, solved = _solve_stack(jj, r)
        live[at[~solved]] = False
        at, j, sol = at[solved], j[solved], sol[solved]
        step = np.einsum("kji,kj->ki", j, sol)
        q[at] = q[at] - step
        live[at[np.linalg.norm(step, axis=1) < 1e-15 * (1 + np.linalg.norm(q[at], axis=1))]] = False
    return q


def _trace_many(surface: Surface, v: np.ndarray, node: np.ndarray, p: np.ndarray, pieces: int = 3):
    """Trace V(F, grad F . v) from each node to its p; ok False where it does not get there.

    The curve is followed in ``pieces`` steps of a fraction of the distance:
    predictor along the tangent grad F x grad G (oriented towards p),
    corrector onto the curve.  It must come closer to p at every step and
    end within one step of p.

    Returns
    -------
    points : (K, pieces - 1, 3) the points from the node towards p (p excluded)
    ok : (K,) bool
    """
    dist0 = np.linalg.norm(node - p, axis=1)
    ok = dist0 != 0
    h = dist0 / pieces
    q = node.copy()
    points = np.zeros((len(node), pieces - 1, 3))
    with np.errstate(all="ignore"):
        for k in range(pieces - 1):
            at = np.nonzero(ok)[0]
            if len(at) == 0:
                break
            _, g, hess = surface.jet(q[at])
            tangent = np.cross(g, np.einsum("kij,kj->ki", hess, v[at]))
            norm = np.linalg.norm(tangent, axis=1)
            ok[at[norm == 0]] = False
            at, tangent, norm = at[norm != 0], tangent[norm != 0], norm[norm != 0]
            tangent /= norm[:, None]
            tangent[np.einsum("ki,ki->k", tangent, p[at] - q[at]) < 0] *= -1
            target = dist0[at] * (pieces - 1 - k) / pieces
            new = _correct_many(surface, v[at], q[at] + h[at, None] * tangent)
            d = np.linalg.norm(new - p[at], axis=1)
            on = np.abs(surface(new)) <= (1e-10 * (1 + np.abs(surface.gradient(new)).max(axis=1))
                                          * np.maximum(dist0[at], 1e-300))
            bad = (~on | ~np.isfinite(new).all(axis=1) | (np.abs(d - target) > 0.5 * h[at])
                   | (np.linalg.norm(new - q[at], axis=1) > 2 * h[at]))
            ok[at[bad]] = False
            points[at, k] = new
            q[at] = new
    return points, ok


def _near_nodes(node: np.ndarray, ok: np.ndarray, cyc: np.ndarray, near: np.ndarray, before: list):
    """For the nodes of one round: which lie within ``near`` of a node an
    earlier round kept on their cycle (``before[cyc]``), and a test of
    whether node k lies within ``near[k]`` of node q of its cycle.

    The distances are those of ``_lengths`` of the same differences, all
    pairs of a cycle in one call.
    """
    k_all = np.flatnonzero(ok)
    near_before = np.zeros(len(node), bool)
    # Earlier nodes: every (node, earlier node of its cycle) pair.
    counts = np.array([len(before[j]) for j in cyc[k_all].tolist()], np.int64)
    if counts.sum():
        rows = np.repeat(k_all, counts)
        prev = np.array([s.node for j in cyc[k_all].tolist() for s in before[j]]).reshape(-1, 3)
        close = _lengths(node[rows] - prev) <= near[rows]
        near_before[rows[close]] = True
    # This round: the pairs (k, q) of nodes on one cycle, q before k.
    same = {}
    by_cycle: dict = {}
    for k in k_all.tolist():
        by_cycle.setdefault(int(cyc[k]), []).append(k)
    first, second = [], []
    for ks in by_cycle.values():
        for i, k in enumerate(ks):
            first += [k] * i
            second += ks[:i]
    if first:
        first, second = np.array(first, np.int64), np.array(second, np.int64)
        close = _lengths(node[first] - node[second]) <= near[first]
        same = dict(zip(zip(first.tolist(), second.tolist()), close.tolist()))
    return near_before, lambda k, q: same[(k, q)]


class StarPoints:
    """The cycle vertices of every star of a batch of jobs, to measure nodes against.

    The jobs of one singular point (the same p, to the bit) share a star:
    their cycles' vertices together, in the order of the jobs.
    """

    def __init__(self, jobs: list):
        star_of: dict = {}
        job_star, members = [], []
        for jb in jobs:
            key = np.asarray(jb[0], float).tobytes()
            if key not in star_of:
                star_of[key] = len(members)
                members.append([])
            job_star.append(star_of[key])
            members[star_of[key]].append(np.asarray(jb[1], float).reshape(-1, 3))
        #: The star of each job; its points ``points[start[s]:start[s] + count[s]]``.
        self.job_star = np.array(job_star, np.int64)
        self.count = np.array([sum(len(q) for q in m) for m in members], np.int64)
        self.start = np.cumsum(self.count) - self.count
        self.points = np.concatenate([q for m in members for q in m]).reshape(-1, 3) if members else np.zeros((0, 3))

    def distance(self, job: np.ndarray, q: np.ndarray) -> np.ndarray:
        """Chebyshev (max-norm) distance from each point ``q[k]`` (K, 3) to the nearest
        vertex of the star of job ``job[k]`` (inf where that star has none).

        The distances of all (point, star vertex) pairs at once: the same
        differences and maxima as a k-d tree's query with ``p=inf``.
        """
        star = self.job_star[np.asarray(job, np.int64)]
        count = self.count[star]
        out = np.full(len(star), np.inf)
        some = count > 0
        if not some.any():
            return out
        rows = np.repeat(np.flatnonzero(some), count[some])
        first = np.cumsum(count[some]) - count[some]
        within = np.arange(len(rows)) - np.repeat(first, count[some])
        d = np.abs(self.points[np.repeat(self.start[star[some]], count[some]) + within] - q[rows]).max(axis=1)
        out[some] = np.minimum.reduceat(d, first)
        return out


def skeleton_links_many(surface: Surface, jobs: list, want: int = 4,
                        max_directions: int = 2) -> list[list[SkeletonLink]]:
    """:func:`skeleton_links` for many cycles at once.

    Parameters
    ----------
    jobs : list of (p, cycle_points, squares, directions)
        The arguments of :func:`skeleton_links` for each cycle.

    Returns
    -------
    list of lists of SkeletonLink, one per job

    Notes
    -----
    Each round tries every unfinished cycle's next direction: the sign
    changes of grad F . v along all those cycles, the face nodes and their
    traces to p are each one batched Newton run; only the choice of nodes
    along a cycle (skip one next to a node kept before it) is a loop.
    """
    n = len(jobs)
    star_points = None  # the cycle vertices of each star, read when a node is not on its link's ends
    links: list[list[SkeletonLink]] = [[] for _ in range(n)]
    used = [0] * n
    nxt = [0] * n
    while True:
        active = [c for c in range(n) if used[c] < max_directions and len(links[c]) < want
                  and nxt[c] < len(jobs[c][3])]
        if not active:
            break
        # Sign changes of G = grad F . v between consecutive cycle vertices.
        vs = [np.asarray(jobs[c][3][nxt[c]], float) for c in active]
        pts = [np.asarray(jobs[c][1], float) for c in active]
        sizes = np.array([len(q) for q in pts])
        allp = np.concatenate(pts)
        g = np.einsum("ki,ki->k", surface.gradient(allp), np.repeat(np.array(vs), sizes, axis=0))
        # All cycles at once: each vertex against the next one of its cycle.
        starts = np.cumsum(sizes) - sizes
        follow = np.arange(len(g)) + 1
        follow[(starts + sizes - 1)[sizes > 0]] = starts[sizes > 0]
        change = np.nonzero(~(g * g[follow] >= 0))[0]
        cyc = (np.searchsorted(starts, change, side="right") - 1).astype(np.int64)
        idx = (change - starts[cyc]).astype(np.int64)
        if len(cyc):
            # The link's two cycle vertices, gathered from all cycles' points at once.
            a = allp[starts[cyc] + idx]
            b = allp[starts[cyc] + (idx + 1) % sizes[cyc]]
            sq = [jobs[active[j]][2][i] for j, i in zip(cyc.tolist(), idx.tolist())]
            axis = np.array([int(s[0]) for s in sq], np.int64)
            lo = np.array([s[1] for s in sq], float).reshape(-1, 3)
            hi = np.array([s[2] for s in sq], float).reshape(-1, 3)
            v = np.array(vs)[cyc]
            node, t, ok = _face_nodes(surface, v, a, b, axis, lo, hi)
            near = tol.NODE_ON_VERTEX * np.linalg.norm(b - a, axis=1)
            vertex = np.full(len(cyc), -1, np.int64)
            on_a = ok & (np.linalg.norm(node - a, axis=1) <= near)
            on_b = ok & ~on_a & (np.linalg.norm(node - b, axis=1) <= near)
            node[on_a], t[on_a], vertex[on_a] = a[on_a], 0.0, idx[on_a]
            node[on_b], t[on_b], vertex[on_b] = b[on_b], 1.0, (idx[on_b] + 1) % sizes[cyc[on_b]]
            # A node on a vertex of another link of its star's cycles (the
            # link's square reaches an event of a smaller square beside it,
            # fuzz s1-324: a 2-event cycle's node on another cycle's event)
            # would be a second vertex at that event's place: no spoke there.
            loose = np.nonzero(ok & (vertex < 0))[0]
            if len(loose):
                if star_points is None:
                    star_points = StarPoints(jobs)
                d = star_points.distance(np.asarray(active, np.int64)[cyc[loose]], node[loose])
                ok[loose] = ~(d <= tol.NODE_ON_OTHER * near[loose] / tol.NODE_ON_VERTEX)
            centre = np.array([jobs[active[j]][0] for j in cyc.tolist()], float).reshape(-1, 3)
            trace, traced = np.zeros((len(cyc), 2, 3)), np.zeros(len(cyc), bool)
            if ok.any():
                trace[ok], traced[ok] = _trace_many(surface, v[ok], node[ok], centre[ok])
        found: list[list[SkeletonLink]] = [[] for _ in active]
        # Whether each node is near a node of an earlier round on its cycle,
        # and near which nodes of this round on its cycle (the lengths of
        # the same differences as one by one), for the choice below.
        if len(cyc):
            near_before, near_now = _near_nodes(node, ok, cyc, near, [links[c] for c in active])
        kept: list[list[int]] = [[] for _ in active]
        for k in range(len(cyc)):
            j = int(cyc[k])
            if not ok[k]:
                continue
            c = active[j]
            if near_before[k] or any(near_now(k, q) for q in kept[j]):
                continue  # two directions crossing the cycle at one point
            if not traced[k]:
                continue
            kept[j].append(k)
            found[j].append(SkeletonLink(after=int(idx[k]), t=float(t[k]), node=node[k].copy(),
                                         trace=trace[k].copy(), direction=vs[j],
                                         vertex=None if vertex[k] < 0 else int(vertex[k])))
        for j, c in enumerate(active):
            nxt[c] += 1
            if found[j]:
                links[c].extend(found[j])
                used[c] += 1
    for lk in links:
        lk.sort(key=lambda s: (s.after, s.t))
    return links
