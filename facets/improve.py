"""Well-shaped triangles on the surface, without changing what the mesh represents.

The crossings of the surface with the lattice make triangles of any shape:
a crossing near a lattice point gives an edge of almost no length beside
edges of a whole cell.  This stage makes them well-shaped (issue #12) by
rounds of

* edge flips: an interior edge whose two triangles are not locally
  Delaunay (opposite angles summing over 180 degrees) is flipped where
  that raises the smallest of their six angles and makes no edge that
  exists, no fold and no triangle leaning further from the surface; each
  pass flips a set of edges no two of which share a triangle;
* tangential relaxation: each free vertex moves in its tangent plane
  towards the area-weighted mean of its triangles' centroids (a step of
  Lloyd's CVT iteration), a vertex on one face of the domain box along the
  curve where the surface meets that face (to the middle of its two
  boundary neighbours), then back onto F = 0 by Newton.

Kept as they are: the vertices at singular points and every edge at them
(so the fans there are the same), the vertices on singular curves and
creases and the edges joining two of them, the vertices on two or more
faces of the box (corners of the boundary), and the vertices of boundary
edges off the box or of non-manifold edges.  A move is undone where
Newton does not land on the surface near where it started (a jump to
another sheet near a double curve or a crease), where the normal turns
away, where it leaves the box, and where a triangle at the vertex would
fold or lean further from the surface.  Flips change no boundary edge,
no vertex and no triangle count: the Euler characteristic, the
components and the fans at singular points stay.
"""

from __future__ import annotations

import numpy as np

from singmesh import tolerances as tol


def improve_mesh(vertices: np.ndarray, faces: np.ndarray, surface, box: np.ndarray,
                 apex: np.ndarray, curve: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict]:
    """Flip and relax the triangles of a mesh of ``surface`` into good shape.

    Parameters
    ----------
    vertices : (V, 3) float64
        On the surface.
    faces : (T, 3) int64
        Consistently oriented triangles.
    surface : Surface
        Only ``value_gradient`` is used: any surface.
    box : (3, 2) float64
        The domain: vertices on one of its faces stay in that face.
    apex : (V,) bool
        Singular points: they stay, and no edge at them is flipped or made.
    curve : (V,) bool
        Vertices on singular curves and creases: they stay, and no edge
        joining two of them is flipped or made.

    Returns
    -------
    vertices : (V, 3) float64
        The same vertices in the same order, some moved on the surface.
    faces : (T, 3) int64
        As many triangles.
    gradient : (V, 3) float64
        grad F at the returned vertices.
    info : dict
        Counts of flips, moves and moves undone.
    """
    v = np.array(vertices, dtype=float)
    f = np.array(faces, dtype=np.int64).reshape(-1, 3)
    info = {"flips": 0, "moves": 0, "undone": 0}
    _, g = surface.value_gradient(v)
    if len(f) == 0:
        return v, f, g, info
    box = np.asarray(box, float)
    size = float(np.max(box[:, 1] - box[:, 0]))
    normal, gnorm = _unit(g)
    roles = _roles(v, f, box, size, apex, curve, gnorm)
    mesh = _Flipper(f, len(v), apex, curve)
    for last in [False] * tol.IMPROVE_ROUNDS + [True]:
        dirty = None
        for _ in range(tol.IMPROVE_FLIP_PASSES):
            n, dirty = mesh.flip_pass(v, normal, dirty)
            info["flips"] += n
            if n == 0:
                break
        if last:
            break
        moved, undone = _relax(v, mesh.f, normal, g, roles, surface, box, size)
        info["moves"] += moved
        info["undone"] += undone
    return v, mesh.f, g, info


def _unit(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rows of ``a`` scaled to unit length (zero where the length is 0 or not finite), and the lengths."""
    n = np.sqrt(np.einsum("ij,ij->i", a, a))
    ok = (n > 0) & np.isfinite(n)
    return np.where(ok[:, None], a / np.where(ok, n, 1.0)[:, None], 0.0), np.where(ok, n, 0.0)


class _Roles:
    """What each vertex may do: ``free`` (move in its tangent plane), ``face`` (move in its box face
    along the boundary, with ``axis`` the face's axis and ``ends`` its two boundary neighbours)."""

    def __init__(self, free, face, axis, ends):
        self.free, self.face, self.axis, self.ends = free, face, axis, ends


def _roles(v, f, box, size, apex, curve, gnorm) -> _Roles:
    """Which vertices move, and how: see :class:`_Roles`."""
    nv = len(v)
    on = (np.abs(v[:, :, None] - box[None, :, :]) <= tol.IMPROVE_ON_BOX * size).any(axis=2)  # (V, 3)
    faces_on = on.sum(axis=1)
    e = np.sort(f[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    key = e[:, 0] * nv + e[:, 1]
    uniq, counts = np.unique(key, return_counts=True)
    a, b = uniq // nv, uniq % nv
    stay = apex | curve | (faces_on >= 2) | (gnorm <= 0)
    # grad F vanishing or not finite: no tangent plane.
    stay |= gnorm < 1e-8 * np.median(gnorm[gnorm > 0]) if (gnorm > 0).any() else True
    odd = counts > 2
    border = counts == 1
    # A boundary edge must lie in one face of the box; the others (and
    # non-manifold edges) keep their vertices.
    same_face = (on[a] & on[b] & (np.abs(v[a] - v[b]) <= tol.IMPROVE_ON_BOX * size)).any(axis=1)
    bad = odd | (border & ~same_face)
    stay[a[bad]] = True
    stay[b[bad]] = True
    # Vertices on one box face: exactly two boundary neighbours to slide between.
    ba, bb = a[border & ~bad], b[border & ~bad]
    nb = np.bincount(np.concatenate([ba, bb]), minlength=nv)
    face = (faces_on == 1) & ~stay & (nb == 2)
    stay |= (faces_on == 1) & ~face
    ends = np.full((nv, 2), -1, np.int64)
    src = np.concatenate([ba, bb])
    dst = np.concatenate([bb, ba])
    order = np.argsort(src, kind="stable")
    src, dst = src[order], dst[order]
    first = np.r_[True, src[1:] != src[:-1]] if len(src) else np.zeros(0, bool)
    ends[src[first], 0] = dst[first]
    ends[src[~first], 1] = dst[~first]
    axis = np.argmax(on, axis=1)
    free = ~stay & ~face
    return _Roles(free, face, axis, ends)


class _Flipper:
    """Triangles with their half-edge twins, flipped in independent sets.

    Half-edge ``h = 3 t + i`` runs from ``f[t, i]`` to ``f[t, (i + 1) % 3]``;
    ``twin[h]`` is the opposite half-edge of the triangle across, -1 on the
    boundary, at non-manifold edges and where the two triangles disagree in
    orientation (such edges are never flipped).
    """

    def __init__(self, f: np.ndarray, nv: int, apex: np.ndarray, curve: np.ndarray):
        self.f, self.nv, self.apex, self.curve = f, nv, apex, curve
        m = 3 * len(f)
        h = np.arange(m)
        self.next = h - h % 3 + (h % 3 + 1) % 3
        self.prev = h - h % 3 + (h % 3 + 2) % 3
        u = f.ravel()
        w = u[self.next]
        key = np.minimum(u, w) * nv + np.maximum(u, w)
        order = np.argsort(key, kind="stable")
        ks = key[order]
        start = np.flatnonzero(np.r_[True, ks[1:] != ks[:-1]])
        length = np.diff(np.r_[start, m])
        two = start[length == 2]
        h1, h2 = order[two], order[two + 1]
        ok = u[h1] == w[h2]
        self.twin = np.full(m, -1, np.int64)
        self.twin[h1[ok]] = h2[ok]
        self.twin[h2[ok]] = h1[ok]
        #: Sorted keys ``min * nv + max`` of all edges.
        self.keys = ks[start]

    def flip_pass(self, v, normal, dirty):
        """One pass of flips among the edges of triangles ``dirty`` (all if None).

        Returns the number of flips and the triangles to look at next.
        """
        f, nv, twin = self.f, self.nv, self.twin
        fl = f.ravel()
        if dirty is None:
            h = np.flatnonzero(twin > np.arange(len(twin)))
        else:
            h = (3 * dirty[:, None] + np.arange(3)).ravel()
            h = np.unique(np.minimum(h, np.where(twin[h] >= 0, twin[h], h))[twin[h] >= 0])
        h2 = twin[h]
        a, b, c, d = fl[h], fl[self.next[h]], fl[self.prev[h]], fl[self.prev[h2]]
        apex, curve = self.apex, self.curve
        ok = (c != d) & ~apex[a] & ~apex[b] & ~apex[c] & ~apex[d]
        ok &= ~(curve[a] & curve[b]) & ~(curve[c] & curve[d])
        h, h2, a, b, c, d = h[ok], h2[ok], a[ok], b[ok], c[ok], d[ok]
        pa, pb, pc, pd = v[a], v[b], v[c], v[d]
        # Locally Delaunay unless the angles at c and d sum over 180
        # degrees: sin(gamma + delta) < 0.
        ca, cb, da, db = pa - pc, pb - pc, pa - pd, pb - pd
        lca, lcb, lda, ldb = _norm(ca), _norm(cb), _norm(da), _norm(db)
        want = _dot(ca, cb) * _norm(_cross(da, db)) + _dot(da, db) * _norm(_cross(ca, cb)) \
            < -1e-9 * lca * lcb * lda * ldb
        h, h2, a, b, c, d = h[want], h2[want], a[want], b[want], c[want], d[want]
        pa, pb, pc, pd = v[a], v[b], v[c], v[d]
        # The new edge c-d must not exist already.
        new = np.minimum(c, d) * nv + np.maximum(c, d)
        keys = self.keys
        ok = keys[np.minimum(np.searchsorted(keys, new), len(keys) - 1)] != new
        # The smallest of the six angles (largest cosine) must grow.
        old = np.maximum(_max_cos(pa, pb, pc), _max_cos(pb, pa, pd))
        cos_new = np.maximum(_max_cos(pa, pd, pc), _max_cos(pb, pc, pd))
        ok &= cos_new < old - 1e-12
        # No fold, no zero area, no more lean from the surface than before.
        na, nb, nc, nd = normal[a], normal[b], normal[c], normal[d]
        lean_old = np.minimum(_lean(pa, pb, pc, na + nb + nc), _lean(pb, pa, pd, nb + na + nd))
        lean_new = np.minimum(_lean(pa, pd, pc, na + nd + nc), _lean(pb, pc, pd, nb + nc + nd))
        ok &= (lean_new >= np.minimum(lean_old, tol.IMPROVE_LEAN)) & (lean_new > 0)
        h, h2, a, b, c, d, new = h[ok], h2[ok], a[ok], b[ok], c[ok], d[ok], new[ok]
        if len(h) == 0:
            return 0, np.zeros(0, np.int64)
        t1, t2 = h // 3, h2 // 3
        gain = old[ok] - cos_new[ok]
        # An independent set: each triangle goes to its best flip; a flip is
        # done when it is the best of both its triangles, and of the flips
        # making the same new edge.
        rank = np.empty(len(gain), np.int64)
        rank[np.argsort(-gain, kind="stable")] = np.arange(len(gain))
        best = np.full(len(f), len(gain), np.int64)
        np.minimum.at(best, t1, rank)
        np.minimum.at(best, t2, rank)
        take = np.flatnonzero((best[t1] == rank) & (best[t2] == rank))
        take = take[np.argsort(rank[take], kind="stable")]
        _, first = np.unique(new[take], return_index=True)
        take = np.sort(take[first])
        later = np.setdiff1d(np.arange(len(h)), take)
        dirty = np.unique(np.concatenate([t1[take], t2[take], t1[later], t2[later]]))
        h, h2, a, b, c, d, new, t1, t2 = (x[take] for x in (h, h2, a, b, c, d, new, t1, t2))
        # New triangles t1 = (a, d, c), t2 = (b, c, d); the old half-edges
        # b->c, c->a, a->d, d->b move to their places in them.
        n1, p1, n2, p2 = self.next[h], self.prev[h], self.next[h2], self.prev[h2]
        remap = np.arange(len(twin))
        remap[n1], remap[p1], remap[n2], remap[p2] = 3 * t2, 3 * t1 + 2, 3 * t1, 3 * t2 + 2
        out = np.where(twin >= 0, remap[np.maximum(twin, 0)], -1)
        moving = [out[n1], out[p1], out[n2], out[p2]]
        out[remap[n1]], out[remap[p1]], out[remap[n2]], out[remap[p2]] = moving
        out[3 * t1 + 1], out[3 * t2 + 1] = 3 * t2 + 1, 3 * t1 + 1
        self.twin = out
        f[t1] = np.stack([a, d, c], axis=1)
        f[t2] = np.stack([b, c, d], axis=1)
        gone = np.minimum(a, b) * nv + np.maximum(a, b)
        self.keys = np.sort(np.concatenate([np.delete(keys, np.searchsorted(keys, gone)), new]))
        return len(h), dirty


def _cross(a, b):
    """Row-wise cross product (np.cross costs more for short rows)."""
    return a[:, [1, 2, 0]] * b[:, [2, 0, 1]] - a[:, [2, 0, 1]] * b[:, [1, 2, 0]]


def _dot(a, b):
    return np.einsum("ij,ij->i", a, b)


def _norm(a):
    return np.sqrt(np.einsum("ij,ij->i", a, a))


def _max_cos(p, q, r):
    """Largest cosine of the three angles of triangles (p, q, r): the smallest angle's."""
    u, w, x = q - p, r - q, p - r
    lu, lw, lx = _norm(u), _norm(w), _norm(x)
    tiny = 1e-300
    c0 = -_dot(x, u) / np.maximum(lx * lu, tiny)
    c1 = -_dot(u, w) / np.maximum(lu * lw, tiny)
    c2 = -_dot(w, x) / np.maximum(lw * lx, tiny)
    return np.maximum(np.maximum(c0, c1), c2)


def _lean(p, q, r, ref):
    """Cosine between the normal of triangles (p, q, r) and ``ref``; -1 for no area."""
    n = _cross(q - p, r - p)
    ln = _norm(n)
    lr = _norm(ref)
    longest = np.maximum(np.maximum(_dot(q - p, q - p), _dot(r - q, r - q)), _dot(p - r, p - r))
    c = _dot(n, ref) / np.maximum(ln * lr, 1e-300)
    return np.where(ln > tol.ZERO_AREA * longest, c, -1.0)


def _relax(v, f, normal, grad, roles: _Roles, surface, box, size) -> tuple[int, int]:
    """One relaxation step (in place on ``v``, ``normal`` and ``grad``): returns (moved, undone)."""
    nv = len(v)
    p = v[f]
    cross = _cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    area = _norm(cross)
    flat = f.ravel()
    w = np.repeat(area, 3)
    total = np.bincount(flat, weights=w, minlength=nv)
    count = np.bincount(flat, minlength=nv)
    centre = p.mean(axis=1)
    target = np.stack([np.bincount(flat, weights=w * np.repeat(centre[:, k], 3), minlength=nv)
                       for k in range(3)], axis=1) / np.maximum(total, 1e-300)[:, None]
    # Local edge length: the side of an equilateral triangle of the mean area.
    h = np.sqrt(2.0 / np.sqrt(3.0) * total / np.maximum(count, 1))
    # Only vertices near a triangle with a small angle move: the rest are
    # well placed already, and Newton costs per point.
    small = _max_cos(p[:, 0], p[:, 1], p[:, 2]) > np.cos(np.radians(tol.IMPROVE_ACTIVE_ANGLE))
    near = np.zeros(nv, bool)
    near[f[small].ravel()] = True
    active = np.zeros(nv, bool)
    active[f[near[f].any(axis=1)].ravel()] = True
    idx_free = np.flatnonzero(roles.free & active & (total > 0))
    idx_face = np.flatnonzero(roles.face & active)
    step_free = target[idx_free] - v[idx_free]
    nf = normal[idx_free]
    step_free -= _dot(step_free, nf)[:, None] * nf
    # On a box face: to the middle of the two boundary neighbours, along
    # the boundary curve (tangent = face normal x grad F).
    ends = roles.ends[idx_face]
    step_face = 0.5 * (v[ends[:, 0]] + v[ends[:, 1]]) - v[idx_face]
    ax = np.zeros((len(idx_face), 3))
    ax[np.arange(len(idx_face)), roles.axis[idx_face]] = 1.0
    tangent, _ = _unit(_cross(ax, normal[idx_face]))
    step_face = _dot(step_face, tangent)[:, None] * tangent
    idx = np.concatenate([idx_free, idx_face])
    step = np.concatenate([step_free, step_face])
    length = _norm(step)
    limit = tol.IMPROVE_STEP * h[idx]
    step *= np.minimum(1.0, limit / np.maximum(length, 1e-300))[:, None]
    length = np.minimum(length, limit)
    go = length > 1e-6 * h[idx]
    idx, step, length = idx[go], step[go], length[go]
    if len(idx) == 0:
        return 0, 0
    free_axes = np.ones((len(idx), 3), bool)
    nfree = int(go[:len(idx_free)].sum())
    free_axes[np.arange(nfree, len(idx)), roles.axis[idx[nfree:]]] = False
    start = v[idx] + step
    q, g, res = _newton(surface, start, free_axes)
    new_normal, _ = _unit(g)
    ok = np.isfinite(q).all(axis=1) & (res <= tol.IMPROVE_RESIDUAL * size)
    ok &= _norm(q - start) <= tol.IMPROVE_PROJECTION * length + tol.IMPROVE_RESIDUAL * size
    ok &= _dot(new_normal, normal[idx]) >= tol.IMPROVE_NORMAL_TURN
    # Inside the box (a free vertex off its faces, a face vertex within its face).
    margin = 1e-9 * size
    inside = (q >= box[:, 0] + margin) & (q <= box[:, 1] - margin)
    ok &= (inside | ~free_axes).all(axis=1)
    rejected = int((~ok).sum())
    idx, q, new_normal, g = idx[ok], q[ok], new_normal[ok], g[ok]
    # Folds and lean: undo the moves of vertices of triangles that got worse.
    old_v, old_n, old_g = v.copy(), normal.copy(), grad.copy()
    v[idx] = q
    normal[idx] = new_normal
    grad[idx] = g
    moved = np.zeros(nv, bool)
    moved[idx] = True
    touched = np.flatnonzero(moved[f].any(axis=1))
    ft = f[touched]
    lean_old = _lean(old_v[ft[:, 0]], old_v[ft[:, 1]], old_v[ft[:, 2]], old_n[ft].sum(axis=1))
    bound = np.minimum(lean_old, tol.IMPROVE_LEAN)
    undone = 0
    for _ in range(8):
        lean_new = _lean(v[ft[:, 0]], v[ft[:, 1]], v[ft[:, 2]], normal[ft].sum(axis=1))
        bad = (lean_new < bound) | (lean_new <= 0)
        back = ft[bad].ravel()
        back = back[moved[back]]
        if len(back) == 0:
            break
        back = np.unique(back)
        v[back] = old_v[back]
        normal[back] = old_n[back]
        grad[back] = old_g[back]
        moved[back] = False
        undone += len(back)
    else:
        # Still not settled: undo every move of this step.
        v[:] = old_v
        normal[:] = old_n
        grad[:] = old_g
        return 0, rejected + int(moved.sum()) + undone
    return int(moved.sum()), rejected + undone


def _newton(surface, p, free_axes):
    """Newton steps along (the free part of) grad F: the points, grad F there and |F| / |grad F|."""
    for _ in range(tol.IMPROVE_NEWTON):
        val, g = surface.value_gradient(p)
        g = g * free_axes
        gg = _dot(g, g)
        s = np.where(gg > 0, val / np.where(gg > 0, gg, 1.0), 0.0)
        p = p - s[:, None] * g
    val, g = surface.value_gradient(p)
    gn = _norm(g * free_axes)
    res = np.where(gn > 0, np.abs(val) / np.where(gn > 0, gn, 1.0), np.inf)
    return p, g, res
