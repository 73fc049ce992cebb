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
creases and those within two edges of them with every edge at them (the
sheets meeting at a curve are close there), the vertices on two or more
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
from singmesh.sorting import search_sorted, stable_argsort
from singmesh.facets.triangulate import edge_keys

# Coordinates are kept as (3, n) arrays (one row per axis): gathers and
# products of rows cost a third of those of (n, 3) rows for the few
# thousand points of a mesh, and this stage must cost little next to the
# meshing itself.


def improve_mesh(vertices: np.ndarray, faces: np.ndarray, surface, box: np.ndarray,
                 apex: np.ndarray, curve: np.ndarray,
                 gradient: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, dict]:
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
        Vertices on singular curves and creases: they and the vertices
        ``IMPROVE_CURVE_RINGS`` edges from them stay, and no edge at those
        is flipped or made.
    gradient : (V, 3) float64, optional
        grad F at ``vertices`` where known already (evaluated here if not).

    Returns
    -------
    vertices : (V, 3) float64
        The same vertices in the same order, some moved on the surface.
    faces : (T, 3) int64
        As many triangles.
    info : dict
        Counts of flips, moves and moves undone.
    """
    v = np.array(vertices, dtype=float).reshape(-1, 3)
    f = np.array(faces, dtype=np.int64).reshape(-1, 3)
    info = {"flips": 0, "moves": 0, "undone": 0}
    g = surface.value_gradient(v)[1] if gradient is None else np.asarray(gradient, float).reshape(-1, 3)
    if len(f) == 0:
        return v, f, info
    box = np.asarray(box, float)
    size = float(np.max(box[:, 1] - box[:, 0]))
    state = _State(v, f, g, np.asarray(apex, bool), np.asarray(curve, bool), box, size)
    # The first pass looks at every edge; later ones only at the triangles
    # that changed since (flips left to look at, vertices moved): an edge
    # whose two triangles did not change stays as it was judged.
    dirty = None
    for last in [False] * tol.IMPROVE_ROUNDS + [True]:
        flips = 0
        for _ in range(tol.IMPROVE_FLIP_PASSES):
            n, dirty = state.flip_pass(dirty)
            flips += n
            if n == 0:
                break
        info["flips"] += flips
        if last:
            break
        moved, undone, touched = state.relax(surface)
        info["moves"] += moved
        info["undone"] += undone
        if (moved == 0 and (flips == 0 or state.calm)) or (moved and state.is_calm()):
            # Nothing changed, or no angle is below IMPROVE_ACTIVE_ANGLE: the
            # flips left to judge would only reshape triangles good enough.
            break
        mark = np.zeros(len(f), bool)
        mark[dirty] = True
        mark[touched] = True
        dirty = np.flatnonzero(mark)
    return state.p.T.copy(), state.f, info


def _cross(a, b):
    """Cross products of the columns of (3, n) arrays."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def _dot(a, b):
    """Dot products of the columns of (3, n) arrays.

    Each column's value does not depend on the others (nor on n): einsum
    takes a single column (n = 1) by another loop, rounded otherwise, so
    one column goes as two.  The relaxation keeps values computed in one
    call for use in another (the triangles' leans).
    """
    if a.shape[1] == 1:
        return np.einsum("ij,ij->j", np.repeat(a, 2, axis=1), np.repeat(b, 2, axis=1))[:1]
    return np.einsum("ij,ij->j", a, b)


def _unit(a):
    """Columns of a (3, n) array scaled to unit length (zero where 0 or not finite), and the lengths."""
    n = np.sqrt(_dot(a, a))
    ok = (n > 0) & np.isfinite(n)
    return np.where(ok, a / np.where(ok, n, 1.0), 0.0), np.where(ok, n, 0.0)


def _any_corner(flags, f):
    """Whether any corner of each triangle (rows of f) is flagged: ``flags[f].any(axis=1)``
    without a reduction along an axis of 3 (a call per row, ten times slower)."""
    return flags[f[:, 0]] | flags[f[:, 1]] | flags[f[:, 2]]


def _lean(p, q, r, ref):
    """Cosine between the normals of triangles (p, q, r) and ``ref``; -1 where no area."""
    return _lean_of(_geometry(p, q, r), ref)


def _geometry(p, q, r):
    """Edge vectors and squared lengths of triangles (p, q, r), (3, n) each.

    Returns ``(u, v, w, l0, l1, l2)``: u = q - p, v = r - q, w = r - p and
    their squared lengths.  With the corners in a triangle's order these
    are its edges e0 = u, e1 = v, e2 = -w (negation is exact: the products
    and sums below give the bits of the same sums over e2).
    """
    u, v, w = q - p, r - q, r - p
    return u, v, w, _dot(u, u), _dot(v, v), _dot(w, w)


def _lean_of(geo, ref):
    """:func:`_lean` from :func:`_geometry`."""
    u, _, w, l0, l1, l2 = geo
    n = _cross(u, w)
    ln = _dot(n, n)
    longest = np.maximum(np.maximum(l0, l1), l2)
    c = _dot(n, ref) / np.sqrt(np.maximum(ln * _dot(ref, ref), 1e-300))
    return np.where(np.sqrt(ln) > tol.ZERO_AREA * longest, c, -1.0)


def _shape_of(geo):
    """The products the shape of a triangle needs, from :func:`_geometry`:
    (l0, l1, l2, d0, d1, d2), with d_i the dot product of the two edges at
    corner i, pointing away from it (``-e_prev . e_i``)."""
    u, v, w, l0, l1, l2 = geo
    return l0, l1, l2, _dot(u, w), -_dot(u, v), _dot(v, w)


def _big_of(l0, l1, l2, d0, d1, d2):
    """Largest cosine of a triangle's angles (its smallest angle's) from :func:`_shape_of`."""
    return np.maximum(np.maximum(d0 / np.sqrt(np.maximum(l0 * l2, 1e-300)),
                                 d1 / np.sqrt(np.maximum(l0 * l1, 1e-300))),
                      d2 / np.sqrt(np.maximum(l1 * l2, 1e-300)))


class _State:
    """The mesh being shaped: positions, normals, triangles, half-edge twins and vertex roles.

    Half-edge ``h = 3 t + i`` runs from ``f[t, i]`` to ``f[t, (i + 1) % 3]``;
    ``twin[h]`` is the opposite half-edge in the triangle across, -1 on the
    boundary, at non-manifold edges and where the two triangles disagree in
    orientation (such edges are never flipped).

    Roles: ``free`` vertices move in their tangent plane; ``face`` vertices
    (on one face of the box, axis ``axis``) move along the boundary between
    their two boundary neighbours ``ends``; the others stay.
    """

    def __init__(self, v, f, g, apex, curve, box, size):
        nv = len(v)
        self.p = np.ascontiguousarray(v.T)
        self.n, gnorm = _unit(np.ascontiguousarray(g.T))
        self.f, self.nv, self.apex, self.curve, self.box, self.size = f, nv, apex, curve, box, size
        # Next to a curve the sheets meeting there are close (tangent ones
        # within ~ distance^2): the vertices a few edges from the curve stay
        # and their edges stay, as the tubes made them.
        near = curve.copy()
        for _ in range(tol.IMPROVE_CURVE_RINGS if curve.any() else 0):
            near[f[_any_corner(near, f)].ravel()] = True
        self.near_curve = near
        self.noflip = apex | near
        m = 3 * len(f)
        h = np.arange(m)
        self.next = h.reshape(-1, 3)[:, [1, 2, 0]].ravel()
        self.prev = h.reshape(-1, 3)[:, [2, 0, 1]].ravel()
        u = f.ravel()
        w = u[self.next]
        key = edge_keys(u, w, nv)
        order = stable_argsort(key)
        ks = key[order]
        start = np.flatnonzero(np.r_[True, ks[1:] != ks[:-1]])
        length = np.diff(np.r_[start, m])
        two = start[length == 2]
        h1, h2 = order[two], order[two + 1]
        ok = u[h1] == w[h2]
        self.twin = np.full(m, -1, np.int64)
        self.twin[h1[ok]] = h2[ok]
        self.twin[h2[ok]] = h1[ok]
        #: Sorted keys (:func:`edge_keys`) of the edges of the input (those
        #: still there: ``alive``) and of the edges flips made (``extra``,
        #: few: sorting them is cheap where re-sorting all keys is not).
        self.keys = ks[start]
        self.alive = np.ones(len(self.keys), bool)
        self.extra = np.zeros(0, np.int64)
        self._roles(self.keys // nv, self.keys % nv, length, gnorm)
        self._faces()
        #: Per triangle, its lean (:func:`_lean`, corners in ``f``'s order,
        #: against the sum of their normals) where ``has_lean``: kept from
        #: the step or flip that last computed it (the triangle and its
        #: corners' places and normals unchanged since), so that a step
        #: need not compute the lean before its moves again.
        self.lean = np.zeros(len(f))
        self.has_lean = np.zeros(len(f), bool)

    # ------------------------------------------------------------ roles
    def _roles(self, a, b, counts, gnorm):
        v, box, size, nv = self.p, self.box, self.size, self.nv
        eps = tol.IMPROVE_ON_BOX * size
        on = (np.abs(v - box[:, :1]) <= eps) | (np.abs(v - box[:, 1:]) <= eps)  # (3, V)
        faces_on = on.sum(axis=0)
        stay = self.apex | self.near_curve | (faces_on >= 2)
        # No tangent plane where grad F vanishes or is not finite.
        ok = gnorm > 0
        if ok.any():
            typical = np.partition(gnorm[ok], ok.sum() // 2)[ok.sum() // 2]  # the (upper) median
            stay |= ~ok | (gnorm < 1e-8 * typical)
        else:
            stay[:] = True
        border = counts == 1
        # A boundary edge must lie in one face of the box; the others (and
        # non-manifold edges) keep their vertices.
        ba, bb = a[border], b[border]
        same_face = np.zeros(len(a), bool)
        same_face[border] = (on[:, ba] & on[:, bb] & (np.abs(v[:, ba] - v[:, bb]) <= eps)).any(axis=0)
        bad = (counts > 2) | (border & ~same_face)
        stay[a[bad]] = True
        stay[b[bad]] = True
        # On one box face with exactly two boundary neighbours: slides between them.
        src = np.concatenate([a[border & ~bad], b[border & ~bad]])
        dst = np.concatenate([b[border & ~bad], a[border & ~bad]])
        nb = np.bincount(src, minlength=nv)
        face = (faces_on == 1) & ~stay & (nb == 2)
        stay |= faces_on == 1
        order = stable_argsort(src)
        src, dst = src[order], dst[order]
        first = np.r_[True, src[1:] != src[:-1]] if len(src) else np.zeros(0, bool)
        self.ends = np.full((2, nv), -1, np.int64)
        self.ends[0, src[first]] = dst[first]
        self.ends[1, src[~first]] = dst[~first]
        self.axis = np.argmax(on, axis=0)
        self.free = ~stay
        self.face = face
        #: Per vertex, the fraction of the full step (IMPROVE_STEP of its
        #: edge length) it may take: halved where a move was undone, so
        #: that the next round tries a shorter one, and back to 1 once a
        #: move stays.
        self.scale = np.ones(nv)

    # ------------------------------------------------------------ per triangle
    def _faces(self, which=None):
        """Per triangle: cotangents opposite the half-edges, largest cosine and doubled area (all or ``which``)."""
        if which is not None and 2 * len(which) > len(self.f):
            which = None  # most triangles: all at once costs less than gather and scatter
        f = self.f if which is None else self.f[which]
        q0, q1, q2 = (np.take(self.p, f[:, i], axis=1) for i in range(3))
        self._store(which, *_shape_of(_geometry(q0, q1, q2)))

    def _store(self, which, l0, l1, l2, d0, d1, d2):
        """:meth:`_faces` of triangles ``which`` (all if None) from :func:`_shape_of` of their corners in order."""
        # |e0 x e2|^2 = |e0|^2 |e2|^2 - (e0 . e2)^2 (Lagrange): no cross
        # product; the cancellation in slivers costs ~1e-16 / angle^2 relative.
        area2 = np.sqrt(np.maximum(l0 * l2 - d0 * d0, 0.0))
        a = np.maximum(area2, 1e-300)
        big = _big_of(l0, l1, l2, d0, d1, d2)
        if which is None:
            # Entry [t, i]: the cotangent opposite half-edge 3 t + i.
            self.cot = np.empty((len(self.f), 3))
            which = slice(None)
        cot = self.cot
        cot[which, 0], cot[which, 1], cot[which, 2] = d2 / a, d0 / a, d1 / a
        if isinstance(which, slice):
            self.big, self.area2 = big, area2
        else:
            self.big[which], self.area2[which] = big, area2

    # ------------------------------------------------------------ flips
    def flip_pass(self, dirty):
        """One pass of flips among the edges of triangles ``dirty`` (all if None).

        Returns the number of flips and the triangles to look at next.
        """
        f, nv, twin = self.f, self.nv, self.twin
        fl = f.ravel()
        if dirty is None:
            h = np.flatnonzero(twin > np.arange(len(twin)))
        else:
            h = (3 * dirty[:, None] + np.arange(3)).ravel()
            t = twin[h]
            mark = np.zeros(len(twin), bool)  # a mask, not np.unique: no sort
            mark[np.minimum(h, t)[t >= 0]] = True
            h = np.flatnonzero(mark)
        h2 = twin[h]
        # Locally Delaunay unless the angles opposite the edge sum over 180
        # degrees: cot(gamma) + cot(delta) < 0.
        cot = self.cot.ravel()
        want = cot[h] + cot[h2] < -1e-9
        h, h2 = h[want], h2[want]
        a, b, c, d = fl[h], fl[self.next[h]], fl[self.prev[h]], fl[self.prev[h2]]
        apex, curve = self.noflip, self.curve
        ok = (c != d) & ~apex[a] & ~apex[b] & ~apex[c] & ~apex[d]
        ok &= ~(curve[a] & curve[b]) & ~(curve[c] & curve[d])
        # The new edge c-d must not exist already.
        new = edge_keys(c, d, nv)
        ok &= ~self._exists(new)
        h, h2, a, b, c, d, new = h[ok], h2[ok], a[ok], b[ok], c[ok], d[ok], new[ok]
        if len(h) == 0:
            return 0, np.zeros(0, np.int64)
        t1, t2 = h // 3, h2 // 3
        P, N, k = self.p, self.n, len(h)
        # The four triangles in one array each (few calls on small arrays):
        # new (a, d, c), (b, c, d), old (a, b, c), (b, a, d).
        tp, tq, tr = np.concatenate([a, b, a, b]), np.concatenate([d, c, b, a]), np.concatenate([c, d, c, d])
        p, q, r = np.take(P, tp, axis=1), np.take(P, tq, axis=1), np.take(P, tr, axis=1)
        # The smallest of the six angles (largest cosine) must grow.
        old = np.maximum(self.big[t1], self.big[t2])
        geo = _geometry(p, q, r)
        # The new triangles' shape products (corners as stored below): their
        # smallest angles now, their cotangents and areas once flipped.
        shape = np.array(_shape_of(tuple(g[..., :2 * k] for g in geo)))  # (6, 2 k)
        cos_new = _big_of(*shape).reshape(2, k).max(axis=0)
        # No fold, no zero area, no more lean from the surface than before.
        lean = _lean_of(geo, np.take(N, tp, axis=1) + np.take(N, tq, axis=1) + np.take(N, tr, axis=1)).reshape(4, k)
        lean_new, lean_old = np.minimum(lean[0], lean[1]), np.minimum(lean[2], lean[3])
        ok = (cos_new < old - 1e-12) & (lean_new >= np.minimum(lean_old, tol.IMPROVE_LEAN)) & (lean_new > 0)
        if not ok.any():
            return 0, np.zeros(0, np.int64)
        # The leans of the new triangles (corners as they are stored below).
        lean_t1, lean_t2 = lean[0][ok], lean[1][ok]
        shape_t1, shape_t2 = shape[:, :k][:, ok], shape[:, k:][:, ok]
        h, h2, a, b, c, d, new, t1, t2 = (x[ok] for x in (h, h2, a, b, c, d, new, t1, t2))
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
        mark = np.zeros(len(f), bool)
        mark[t1] = True
        mark[t2] = True
        dirty = np.flatnonzero(mark)
        h, h2, a, b, c, d, new, t1, t2 = (x[take] for x in (h, h2, a, b, c, d, new, t1, t2))
        self.lean[t1], self.lean[t2] = lean_t1[take], lean_t2[take]
        self.has_lean[t1] = self.has_lean[t2] = True
        # New triangles t1 = (a, d, c), t2 = (b, c, d); the old half-edges
        # b->c, c->a, a->d, d->b move to their places in them.
        n1, p1, n2, p2 = self.next[h], self.prev[h], self.next[h2], self.prev[h2]
        src = np.concatenate([n1, p1, n2, p2])
        dst = np.concatenate([3 * t2, 3 * t1 + 2, 3 * t1, 3 * t2 + 2])
        remap = np.arange(len(twin))
        remap[src] = dst
        # Only the moved half-edges and their twins change (their twins may
        # have moved too: two flips can share an edge of the quads).
        tw = twin[src]
        tw = np.where(tw >= 0, remap[np.maximum(tw, 0)], -1)
        out = twin.copy()
        out[tw[tw >= 0]] = dst[tw >= 0]
        out[dst] = tw
        out[3 * t1 + 1], out[3 * t2 + 1] = 3 * t2 + 1, 3 * t1 + 1
        self.twin = out
        f[t1] = np.stack([a, d, c], axis=1)
        f[t2] = np.stack([b, c, d], axis=1)
        self._replace(edge_keys(a, b, nv), new)
        self._store(np.concatenate([t1, t2]), *np.concatenate([shape_t1[:, take], shape_t2[:, take]], axis=1))
        return len(h), dirty

    def _exists(self, new):
        """Whether the edges with keys ``new`` are in the mesh."""
        keys, extra = self.keys, self.extra
        k = np.minimum(search_sorted(keys, new), len(keys) - 1)
        out = (keys[k] == new) & self.alive[k]
        if len(extra):
            out |= extra[np.minimum(np.searchsorted(extra, new), len(extra) - 1)] == new
        return out

    def _replace(self, gone, new):
        """Edges ``gone`` (in the mesh) leave it, edges ``new`` (not in it, distinct) come."""
        keys, extra = self.keys, self.extra
        k = np.minimum(search_sorted(keys, gone), len(keys) - 1)
        base = (keys[k] == gone) & self.alive[k]
        self.alive[k[base]] = False
        if len(extra):
            extra = np.delete(extra, np.searchsorted(extra, gone[~base]))
        k = np.minimum(search_sorted(keys, new), len(keys) - 1)
        back = keys[k] == new  # an edge of the input that a flip removed, made again
        self.alive[k[back]] = True
        self.extra = np.sort(np.concatenate([extra, new[~back]]))

    # ------------------------------------------------------------ relaxation
    def is_calm(self) -> bool:
        """Whether no triangle has an angle below ``IMPROVE_ACTIVE_ANGLE``."""
        return not (self.big > np.cos(np.radians(tol.IMPROVE_ACTIVE_ANGLE))).any()

    def relax(self, surface) -> tuple[int, int, np.ndarray]:
        """One relaxation step: returns (moved, undone, the triangles at vertices that moved)."""
        nv, f, P, N = self.nv, self.f, self.p, self.n
        # Only vertices near a triangle with a small angle move: the rest
        # are well placed already, and Newton costs per point.
        small = self.big > np.cos(np.radians(tol.IMPROVE_ACTIVE_ANGLE))
        self.calm = not small.any()
        if self.calm:
            return 0, 0, np.zeros(0, np.int64)
        active = np.zeros(nv, bool)
        active[f[small].ravel()] = True
        for _ in range(tol.IMPROVE_ACTIVE_RINGS):
            active[f[_any_corner(active, f)].ravel()] = True
        # The triangles at active vertices: all their sums (the others add
        # nothing to them, and the order of the terms is the same).
        sub = np.flatnonzero(_any_corner(active, f))
        fs = f[sub]
        flat = fs.ravel()
        area2 = self.area2[sub]
        total = np.bincount(flat, weights=np.repeat(area2, 3), minlength=nv)
        wc = area2 * ((np.take(P, fs[:, 0], axis=1) + np.take(P, fs[:, 1], axis=1)
                       + np.take(P, fs[:, 2], axis=1)) / 3.0)
        idx_free = np.flatnonzero(self.free & active & (total > 0))
        idx_face = np.flatnonzero(self.face & active)
        # Local edge length: the side of an equilateral triangle of the mean area.
        count = np.bincount(flat, minlength=nv)
        h = np.sqrt(2.0 / np.sqrt(3.0) * total / np.maximum(count, 1))
        # Free vertices: towards the area-weighted mean of their triangles'
        # centroids, in the tangent plane.
        target = np.array([np.bincount(flat, weights=np.repeat(wc[k], 3), minlength=nv)[idx_free]
                           for k in range(3)]) / total[idx_free]
        step_free = target - P[:, idx_free]
        nf = N[:, idx_free]
        step_free -= _dot(step_free, nf) * nf
        # On a box face: to the middle of the two boundary neighbours, along
        # the boundary curve (tangent = face normal x grad F).
        e0, e1 = self.ends[0, idx_face], self.ends[1, idx_face]
        step_face = 0.5 * (P[:, e0] + P[:, e1]) - P[:, idx_face]
        ax = np.zeros((3, len(idx_face)))
        ax[self.axis[idx_face], np.arange(len(idx_face))] = 1.0
        tangent, _ = _unit(_cross(ax, N[:, idx_face]))
        step_face = _dot(step_face, tangent) * tangent
        idx = np.concatenate([idx_free, idx_face])
        step = np.concatenate([step_free, step_face], axis=1)
        length = np.sqrt(_dot(step, step))
        limit = tol.IMPROVE_STEP * h[idx] * self.scale[idx]
        step *= np.minimum(1.0, limit / np.maximum(length, 1e-300))
        length = np.minimum(length, limit)
        go = length > 1e-6 * h[idx]
        idx, step, length = idx[go], step[:, go], length[go]
        if len(idx) == 0:
            return 0, 0, np.zeros(0, np.int64)
        free_axes = np.ones((3, len(idx)), bool)
        nfree = int(go[:len(idx_free)].sum())
        free_axes[self.axis[idx[nfree:]], np.arange(nfree, len(idx))] = False
        start = P[:, idx] + step
        q, g, res = _newton(surface, start, free_axes, tol.IMPROVE_RESIDUAL * self.size)  # g: the normal to check, not kept
        new_normal, _ = _unit(g)
        size, box = self.size, self.box
        ok = np.isfinite(q).all(axis=0) & (res <= tol.IMPROVE_RESIDUAL * size)
        d = q - start
        ok &= np.sqrt(_dot(d, d)) <= tol.IMPROVE_PROJECTION * length + tol.IMPROVE_RESIDUAL * size
        ok &= _dot(new_normal, N[:, idx]) >= tol.IMPROVE_NORMAL_TURN
        # Inside the box (a free vertex off its faces, a face vertex within its face).
        margin = 1e-9 * size
        inside = (q >= box[:, :1] + margin) & (q <= box[:, 1:] - margin)
        ok &= (inside | ~free_axes).all(axis=0)
        rejected = int((~ok).sum())
        tried = idx.copy()
        keep = np.flatnonzero(ok)
        keep = keep[np.argsort(idx[keep])]  # sorted: undone vertices are found by bisection
        idx, q, new_normal = idx[keep], q[:, keep], new_normal[:, keep]
        # Folds and lean: undo the moves of vertices of triangles that got worse.
        moved = np.zeros(nv, bool)
        moved[idx] = True
        touched = sub[_any_corner(moved, fs)]
        ft = f[touched]
        # The leans before the moves: kept from earlier steps and flips
        # where known (the same values), computed for the others.
        before = self.lean[touched]
        unknown = np.flatnonzero(~self.has_lean[touched])
        if len(unknown):
            fu = ft[unknown]
            old = [np.take(P, fu[:, i], axis=1) for i in range(3)]
            ref = sum(np.take(N, fu[:, i], axis=1) for i in range(3))
            before[unknown] = _lean(*old, ref)
        bound = np.minimum(before, tol.IMPROVE_LEAN)
        old_p, old_n = P[:, idx], N[:, idx]
        P[:, idx], N[:, idx] = q, new_normal
        undone = 0
        # The lean of every touched triangle, then of those at the vertices
        # moved back alone (the others' did not change), until none is
        # worse.  Each round moves at least one vertex back, so this ends;
        # a move back can make a neighbour's triangle fold in turn, in a
        # chain a dozen vertices long among slivers (rotated D5+-: 12
        # rounds), and undoing every move of the step there instead froze
        # the whole mesh (no move kept in any round).
        redo = np.arange(len(ft))
        lean = np.empty(len(ft))
        # The shape products of each touched triangle as it is now (rows
        # redone with the lean): the triangles' cotangents, angles and
        # areas at the end without gathering their corners again.  Where
        # most triangles are touched all are computed again at the end
        # instead (no scatter of rows).
        every = 2 * len(touched) > len(f)
        shape = None
        while True:
            fr = ft[redo]
            now = [np.take(P, fr[:, i], axis=1) for i in range(3)]
            ref = sum(np.take(N, fr[:, i], axis=1) for i in range(3))
            geo = _geometry(*now)
            lean[redo] = _lean_of(geo, ref)
            if every:
                pass
            elif shape is None:
                shape = np.array(_shape_of(geo))
            else:
                shape[:, redo] = _shape_of(geo)
            back = ft[(lean < bound) | (lean <= 0)].ravel()
            back = back[moved[back]]
            if len(back) == 0:
                break
            # Distinct and sorted, as np.unique gives them, without a sort.
            was = np.zeros(nv, bool)
            was[back] = True
            back = np.flatnonzero(was)
            k = np.searchsorted(idx, back)
            P[:, back], N[:, back] = old_p[:, k], old_n[:, k]
            moved[back] = False
            undone += len(back)
            redo = np.flatnonzero(_any_corner(was, ft))
        # The triangles at the vertices that moved (and may be back).
        if every:
            self._faces()
        else:
            self._store(touched, *shape)
        self.lean[touched] = lean  # each as it is now (recomputed after every move back)
        self.has_lean[touched] = True
        # A vertex whose move was undone (by Newton's checks or a fold)
        # tries half the step next round: a whole step towards the centroid
        # can fold a neighbour where a shorter one is fine (Kummer: a 8.7
        # degree sliver whose three vertices were moved back in every round).
        stayed = tried[~moved[tried]]
        self.scale[stayed] = np.maximum(0.5 * self.scale[stayed], tol.IMPROVE_MIN_SCALE)
        self.scale[moved] = 1.0
        return int(moved.sum()), rejected + undone, touched


def _newton(surface, p, free_axes, target):
    """Newton steps along (the free part of) grad F from (3, K) points.

    Each step takes grad F where it starts; the residual |F| / |grad F| at
    the end divides by the last step's grad F (F alone costs less than F
    and grad F; from a point 1e-8 of an edge off the surface the two
    gradients agree to far better than the 1e-12 asked).  After
    ``IMPROVE_NEWTON - 1`` steps most points are within ``target``: only
    the others take the last step (one evaluation of F and grad F at all
    points fewer).

    Returns the points, grad F (the last evaluated) and the residual.
    """
    def steps(p, free_axes, n):
        for _ in range(n):
            val, g = surface.value_gradient(p.T)
            g = np.ascontiguousarray(g.T)
            gf = g * free_axes
            gg = _dot(gf, gf)
            inv = np.where(gg > 0, 1.0 / np.where(gg > 0, gg, 1.0), 0.0)
            p = p - val * inv * gf
        val = surface(p.T)
        return p, g, np.where(gg > 0, np.abs(val) * np.sqrt(inv), np.inf)

    p, g, res = steps(p, free_axes, max(tol.IMPROVE_NEWTON - 1, 1))
    # The last step wherever the residual is not yet at rounding level: a
    # point at 1e-12 of the box where grad F is large (sqrt(x) near x = 0)
    # still has |F| of 1e-12 and more.
    more = np.flatnonzero(~(res <= tol.IMPROVE_NEWTON_DONE * target))
    if len(more) and tol.IMPROVE_NEWTON > 1:
        p[:, more], g[:, more], res[more] = steps(p[:, more], free_axes[:, more], 1)
    return p, g, res
