"""Coarsening: the fine triangles of crease tubes merged to the mesh size elsewhere.

The tubes round creases are meshed on the fine lattice: along a crease
the strips and their margin are triangles a fine cell across, where the
surface elsewhere has triangles of the coarse lattice (57k triangles for a
cube, 44k of them within 12 cells of a crease; 184k for a cube less a
ball).  A vertex of a tube can go where the mesh stays as near the
surface: each of its triangles is replaced by one with the vertex moved to
a neighbour (a half-edge collapse), vertices never move, so every vertex
left is on the surface as it was and crease vertices stay on the crease.
This stage does such collapses in rounds, numpy over all vertices at once:
each vertex of a tube proposes its shortest edge not found invalid; the
proposals that are each of least priority (shortest) among those they
conflict with are checked (a few passes, each adding proposals that
conflict with none taken), the valid ones made together; then flips of
the diagonals of pairs of triangles where that raises their smallest
angle; up to an edge length of the mesh size elsewhere.  A collapse found
invalid is not checked again until the star of its u or v changes.

A collapse of u onto its neighbour v is made only where

* u is in a tube (within ``COARSEN_REACH`` fine cells of a crease vertex)
  and not kept (singular points and their neighbours, ends and corners of
  curves, vertices of other curves, on the box's faces, on boundary or
  non-manifold edges);
* a crease vertex goes onto one of its two neighbours along the crease
  (the crease graph loses u, its two edges become one), where the new
  chord is as close to the crease as one of ``max_edge`` whose ends turn
  ``COARSEN_BEND`` degrees (its sagitta from the turn at u);
* every triangle of u that does not hold v, with u moved to v, keeps its
  orientation, turns at most ``COARSEN_BEND`` degrees from the normal of
  the fine triangle it descends from (the surface's normal there: on a
  flat face no turn at all, on a curved one the chord's), has no edge
  longer than ``max_edge`` and no angle below ``COARSEN_ANGLE`` degrees
  or about the smallest of u's triangles (a needle that the next
  collapse takes aside);
* u and v have exactly two common neighbours (the link condition: the
  surface keeps its topology).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy.spatial import cKDTree

from singmesh import tolerances as tol
from singmesh.facets.records import vertex_of
from singmesh.topology import on_box_boundary


def coarsen_crease_mesh(vertices: np.ndarray, faces: np.ndarray, vkeys: np.ndarray, per_vertex: list, curves,
                        key0: int, singular_keys: np.ndarray, box: np.ndarray, max_edge: float,
                        reach: float = np.inf):
    """The mesh of a surface with creases coarsened in the tubes along them (:func:`coarsen_faces`), and its curves.

    ``curves`` (a CurveSet whose point i is the vertex keyed ``key0 + i``)
    loses the crease points that are no vertex any more; its keys are
    renumbered with it.  ``per_vertex``: arrays (V, ...) kept for the
    vertices left.  Only vertices within ``reach`` of a crease vertex go.  Returns (vertices, faces, vkeys, per_vertex, curves).
    """
    n = len(vertices)
    npts = len(curves.points)
    cv = vertex_of(vkeys, key0 + np.arange(npts))
    crease = np.zeros(npts, bool)
    for c in curves.pieces:
        if c.type == "crease":
            crease[np.asarray(c.vertices)] = True
    e = curves.edges
    degree = np.bincount(e.ravel(), minlength=npts)
    special = np.zeros(npts, bool)
    special[curves.special_vertex] = True
    inner = crease & (degree == 2) & ~special & (cv >= 0)
    # The two graph neighbours of each inner crease point.
    ends = np.concatenate([e, e[:, ::-1]])
    ends = ends[np.argsort(ends[:, 0], kind="stable")]
    first = np.searchsorted(ends[:, 0], np.arange(npts))
    nb = np.full((npts, 2), -1, np.int64)
    idx = np.nonzero(inner)[0]
    nb[idx, 0], nb[idx, 1] = ends[first[idx], 1], ends[first[idx] + 1, 1]
    inner[idx] &= (cv[nb[idx, 0]] >= 0) & (cv[nb[idx, 1]] >= 0)
    chain = np.full((n, 2), -1, np.int64)
    idx = np.nonzero(inner)[0]
    chain[cv[idx]] = cv[nb[idx]]
    keep = np.zeros(n, bool)
    keep[cv[(cv >= 0) & ~inner]] = True
    # Singular points keep their stars (the fans there are meshed for them).
    singular = np.isin(vkeys, singular_keys)
    keep |= singular
    keep[faces[singular[faces].any(axis=1)].ravel()] = True
    keep |= on_box_boundary(vertices, box, 1e-9)
    size = float(np.max(box[:, 1] - box[:, 0]))
    # The vertices that can go: those of the tubes, and those on flat pieces
    # of the mesh (a flat face meshed on the fine lattice far from creases,
    # where bounds of F are loose).
    crease_v = cv[crease & (cv >= 0)]
    if np.isfinite(reach) and len(crease_v):
        dist, _ = cKDTree(vertices[crease_v]).query(vertices, distance_upper_bound=reach)
        active = np.isfinite(dist) | _flat_vertices(vertices, faces, tol.COARSEN_FLAT * size)
    else:
        active = None
    # The surface's normal at the vertices off the curves (at a crease
    # vertex grad F is one side's): the reference the new triangles keep to.
    normals = np.asarray(per_vertex[0], float).copy() if len(per_vertex) else _area_normals(vertices, faces)
    normals[cv[cv >= 0]] = np.nan
    faces, chain = coarsen_faces(vertices, faces, keep, chain, max_edge, active, normals)
    alive = np.zeros(n, bool)
    alive[faces.ravel()] = True
    # Curve points without a vertex (a line no triangle has) stay as they are.
    pt_alive = (cv < 0) | alive[np.maximum(cv, 0)]
    if pt_alive.all() and alive.all():
        return vertices, faces, vkeys, per_vertex, curves
    new_v = np.cumsum(alive) - 1
    new_p = np.cumsum(pt_alive) - 1
    # Curve edges: those between points left, and the crease's new ones.
    both = pt_alive[e].all(axis=1)
    wide = curves.wide if len(curves.wide) == len(e) else np.zeros(len(e), bool)
    point_of = np.full(n, -1, np.int64)
    point_of[cv[cv >= 0]] = np.nonzero(cv >= 0)[0]
    x = np.nonzero((chain >= 0).any(axis=1) & alive)[0]
    add = np.concatenate([np.stack([x, chain[x, 0]], 1), np.stack([x, chain[x, 1]], 1)])
    add = add[(add >= 0).all(axis=1)]
    add = point_of[add]
    add = np.unique(np.sort(add, axis=1), axis=0)
    old = np.sort(e[both], axis=1)
    fresh = add[~np.isin(add[:, 0] * npts + add[:, 1], old[:, 0] * npts + old[:, 1])]
    edges = new_p[np.concatenate([e[both], fresh])]
    wide = np.concatenate([wide[both], np.zeros(len(fresh), bool)])
    points = curves.points[pt_alive]
    pieces = []
    for c in curves.pieces:
        verts = np.asarray(c.vertices)
        verts = new_p[verts[pt_alive[verts]]]
        pieces.append(replace(c, points=points[verts], vertices=verts))
    out = replace(curves, points=points, edges=edges, pieces=pieces, special_vertex=new_p[curves.special_vertex],
                  wide=wide)
    vkeys = vkeys.copy()
    is_pt = point_of >= 0
    vkeys[is_pt] = key0 + new_p[point_of[is_pt]]
    return (vertices[alive], new_v[faces], vkeys[alive], [a[alive] for a in per_vertex], out)


def _flat_vertices(V: np.ndarray, T: np.ndarray, flat: float) -> np.ndarray:
    """Vertices whose neighbours all lie within ``flat`` of the plane of one of their triangles."""
    n = len(V)
    first_tri = np.full(n, -1, np.int64)
    first_tri[T[::-1].ravel()] = np.repeat(np.arange(len(T))[::-1], 3)
    nrm = _unit_normals(V, T)
    d = T[:, [0, 1, 1, 2, 2, 0, 1, 0, 2, 1, 0, 2]].reshape(-1, 2)
    dev = np.abs(_dot(nrm[first_tri[d[:, 0]]], V[d[:, 1]] - V[d[:, 0]]))
    out = np.ones(n, bool)
    out[d[~(dev <= flat), 0]] = False
    return out & (first_tri >= 0)


def _area_normals(V: np.ndarray, T: np.ndarray) -> np.ndarray:
    """Area-weighted normals of the triangles at each vertex (not unit)."""
    p = V[T]
    nrm = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    out = np.zeros((len(V), 3))
    for k in range(3):
        np.add.at(out, T[:, k], nrm)
    return out


def _reference_normals(V: np.ndarray, T: np.ndarray, normals: np.ndarray | None) -> np.ndarray:
    """Unit normals of the triangles from the surface's normals at their vertices (NaN: not known).

    A fine triangle's own normal is the surface's only where it is well
    shaped: a sliver's (a lattice crossing next to a lattice point) points
    anywhere.  The sum of the unit normals at its vertices, with the sign
    of the triangles' (the mesh is oriented one way); its own normal
    where no vertex has one (three curve vertices).
    """
    ref = _unit_normals(V, T)
    if normals is None:
        return ref
    with np.errstate(all="ignore"):
        unit = normals / np.linalg.norm(normals, axis=1, keepdims=True)
    unit[~np.isfinite(unit).all(axis=1)] = 0.0
    s = unit[T].sum(axis=1)
    length = np.linalg.norm(s, axis=1)
    ok = length > 0
    p = V[T]
    nrm = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    sign = 1.0 if _dot(nrm[ok], s[ok]).sum() >= 0 else -1.0
    ref[ok] = sign * s[ok] / length[ok, None]
    return ref


def coarsen_faces(vertices: np.ndarray, faces: np.ndarray, keep: np.ndarray, chain: np.ndarray,
                  max_edge: float, active: np.ndarray | None = None, normals: np.ndarray | None = None,
                  rounds: int = 60) -> tuple[np.ndarray, np.ndarray]:
    """Faces of the coarsened mesh (indices into the same ``vertices``; vertices no face uses are gone).

    Parameters
    ----------
    vertices : (V, 3) float64
    faces : (T, 3) int64, consistently oriented
    keep : (V,) bool
        Vertices never removed.
    chain : (V, 2) int64
        For a vertex inside a crease (on two crease edges), its two
        neighbours along it; -1 elsewhere.  A crease vertex only goes onto
        one of them.
    max_edge : float
        No edge made longer than this.
    active : (V,) bool, optional
        The vertices that may go (all but ``keep`` if not given).
    normals : (V, 3), optional
        The surface's normals at the vertices (NaN where not known): the
        reference of the new triangles' (the triangles' own if not given).

    Returns
    -------
    faces : (T', 3) int64
    chain : (V, 2) int64, the crease neighbours after the collapses
    """
    V = np.asarray(vertices, float)
    T = np.asarray(faces, np.int64).copy()
    n = len(V)
    keep = np.asarray(keep, bool).copy()
    chain = np.asarray(chain, np.int64).copy()
    if len(T) == 0:
        return T, chain
    # Vertices of boundary and non-manifold edges stay.
    e = np.sort(T[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    uk, cnt = np.unique(e[:, 0] * n + e[:, 1], return_counts=True)
    odd = uk[cnt != 2]
    keep[odd // n] = True
    keep[odd % n] = True
    active = ~keep if active is None else np.asarray(active, bool) & ~keep
    # The triangles that can change: those at the active vertices and at
    # their neighbours (the targets, whose neighbours the link condition
    # reads); every star of a vertex next to an active one is whole here.
    near = active.copy()
    near[T[active[T].any(axis=1)].ravel()] = True
    work = near[T].any(axis=1)
    rest, T = T[~work], T[work]
    # Each triangle's reference normal: the surface's at the fine triangle
    # it descends from; no triangle made turns further than COARSEN_BEND
    # from it.
    ref = _reference_normals(V, T, normals)
    cos_bend = np.cos(np.radians(tol.COARSEN_BEND))
    cos_floor = np.cos(np.radians(tol.COARSEN_ANGLE))
    # Then rounds for the triangles still thinner than COARSEN_ANGLE: only
    # their vertices go, no needle made.
    for cleanup in (False, True):
        failed = np.zeros(0, np.int64)  # keys u * n + v of collapses found invalid
        changed = np.ones(n, bool)
        pending = np.zeros(n, bool)
        for rnd in range(tol.COARSEN_CLEANUP if cleanup else rounds):
            movable = active
            if cleanup:
                thin = _max_cos(V[T]) > cos_floor
                movable = np.zeros(n, bool)
                movable[T[thin].ravel()] = True
                movable &= active
            # Collapses found invalid stay so until the star of u or v changes.
            failed = np.sort(failed[~(changed[failed // n] | changed[failed % n])])
            mesh = _Mesh(T, n)
            u, v = mesh.src, mesh.dst
            ok = movable[u]
            cu = chain[u]
            ok &= (cu[:, 0] < 0) | (cu[:, 0] == v) | (cu[:, 1] == v)
            if len(failed):
                key = u * n + v
                ok &= failed[np.minimum(np.searchsorted(failed, key), len(failed) - 1)] != key
            u, v = u[ok], v[ok]
            if not len(u):
                break
            d = V[u] - V[v]
            length = _dot(d, d)
            # (a crease vertex: the length of the chord made, so that the
            # chords along a crease grow evenly, not leaving short remainders
            # between long ones that could not go)
            cu = chain[u]
            on = cu[:, 0] >= 0
            o = np.where(cu[on, 0] == v[on], cu[on, 1], cu[on, 0])
            d = V[o] - V[v[on]]
            length[on] = _dot(d, d)
            # Each u's edges, shortest first.
            order = _order(u, (length * ((1 << 20) - 1) / length.max()).astype(np.int64), 20)
            u, v, length = u[order], v[order], length[order]
            # Priority: shorter first by factors of sqrt(2), and within those in
            # an order that is random-like in space (hashed vertex numbers: a
            # smooth order would have few collapses least of their
            # neighbourhood's), then u's edges in order; all in one integer.
            with np.errstate(divide="ignore"):
                scale = np.clip(np.floor(np.log2(length / (max_edge * max_edge))), -127, 0).astype(np.int64) + 127
            rank = np.arange(len(u)) - np.searchsorted(u, u)
            prio = (scale << 40) | (((u * 2654435761) & 0xFFFFFFFF) << 8) | np.minimum(rank, 255)
            lock_a = np.zeros(n, bool)  # a chosen u or v or a neighbour of one
            lock_b = np.zeros(n, bool)  # a chosen u or a neighbour of one
            cand = np.ones(len(u), bool)  # not found invalid this round
            known = np.zeros(len(u), bool)  # found valid
            acc_u, acc_v, bad = [], [], []
            eager = False
            for _pass in range(tol.COARSEN_PASSES):
                # The shortest edge of each u not found invalid, nor conflicting
                # with a collapse chosen.
                cand &= ~lock_a[u] & ~lock_b[v]
                idx = np.nonzero(cand)[0]
                if not len(idx):
                    break
                idx = idx[np.r_[True, u[idx][1:] != u[idx][:-1]]]
                if eager:
                    # Most collapses tried were invalid: check all, choose among
                    # the valid ones.
                    check = idx[~known[idx]]
                else:
                    # Most were valid: choose, then check only those chosen.
                    idx = idx[_local_minima(mesh, u[idx], v[idx], prio[idx], n)]
                    check = idx[~known[idx]]
                good = _valid(V, T, ref, mesh, u[check], v[check], chain, max_edge, cos_bend, cos_floor,
                              needles=not cleanup)
                known[check[good]] = True
                cand[check[~good]] = False
                bad.append(u[check[~good]] * n + v[check[~good]])
                eager = 2 * good.sum() < len(good)
                idx = idx[cand[idx]]
                if len(check) and not len(idx):
                    continue
                win = idx[_local_minima(mesh, u[idx], v[idx], prio[idx], n)]
                cand[win] = False
                acc_u.append(u[win])
                acc_v.append(v[win])
                lock_a[mesh.closed(u[win])] = True
                lock_a[mesh.closed(v[win])] = True
                lock_b[mesh.closed(u[win])] = True
            failed = np.concatenate([failed] + bad)
            cu = np.concatenate(acc_u) if acc_u else np.zeros(0, np.int64)
            cv = np.concatenate(acc_v) if acc_v else np.zeros(0, np.int64)
            changed = np.zeros(n, bool)
            changed[mesh.closed(cu)] = True
            if not len(cu):
                if not sum(len(b) for b in bad):
                    break
                continue
            T, ref, chain = _apply(T, ref, chain, cu, cv, n)
            pending |= changed
            if rnd % 2 or cleanup:
                T, ref, flipped = _flip(V, T, ref, chain, max_edge, cos_bend, pending)
                changed[flipped] = True
                pending[:] = False
    return np.concatenate([rest, T]), chain


def _order(major: np.ndarray, minor: np.ndarray | None = None, minor_bits: int = 0) -> np.ndarray:
    """The stable sorting permutation by (major, minor) of non-negative integers.

    One sort of int64 keys with the position in the low bits where they
    fit (numpy sorts int64 several times faster than it argsorts stably).
    """
    m = len(major)
    if not m:
        return np.zeros(0, np.int64)
    pos_bits = max(int(m).bit_length(), 1)
    if int(major.max()).bit_length() + minor_bits + pos_bits <= 62:
        key = major.astype(np.int64) << (minor_bits + pos_bits)
        if minor is not None:
            key |= minor << pos_bits
        key |= np.arange(m)
        return np.sort(key) & ((1 << pos_bits) - 1)
    if minor is None:
        return np.argsort(major, kind="stable")
    return np.lexsort((minor, major))


class _Mesh:
    """Neighbours and triangles of each vertex of a triangle list, as CSR arrays (numpy)."""

    def __init__(self, T: np.ndarray, n: int):
        self.T, self.n = T, n
        # Directed edges u -> v of the triangles: inside the mesh each
        # neighbour v of u once.  Neighbours from both directions (inside
        # the mesh each twice), for vertices on a boundary of the work set.
        a = T.ravel()
        b = T[:, [1, 2, 0]].ravel()
        self.src, self.dst = a, b
        self.keys = np.sort(np.concatenate([a * n + b, b * n + a]))
        self.nb = self.keys % n
        self.nb_ptr = np.concatenate([[0], np.cumsum(np.bincount(a, minlength=n) + np.bincount(b, minlength=n))])
        order = _order(a)
        self.tri_ptr = np.concatenate([[0], np.cumsum(np.bincount(a, minlength=n))])
        self.tri = order // 3

    def neighbours(self, w: np.ndarray):
        """(which, neighbour): the neighbours of each w[which] (each twice inside the mesh)."""
        return _ragged(self.nb_ptr, self.nb, w)

    def closed(self, w: np.ndarray) -> np.ndarray:
        """The vertices w and their neighbours (with repeats)."""
        return np.concatenate([w, self.neighbours(w)[1]])

    def triangles(self, w: np.ndarray):
        """(which, triangle): the triangles at each w[which]."""
        return _ragged(self.tri_ptr, self.tri, w)

    def has_edge(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        k = a * self.n + b
        i = np.minimum(np.searchsorted(self.keys, k), len(self.keys) - 1)
        return self.keys[i] == k


def _ragged(ptr: np.ndarray, data: np.ndarray, w: np.ndarray):
    k = ptr[w + 1] - ptr[w]
    which = np.repeat(np.arange(len(w)), k)
    return which, data[np.repeat(ptr[w] - np.cumsum(k) + k, k) + np.arange(k.sum())]


def _local_minima(mesh: _Mesh, u: np.ndarray, v: np.ndarray, prio: np.ndarray, n: int) -> np.ndarray:
    """The collapses u -> v that can be made together: each of least priority among those it conflicts with.

    Collapses i and j conflict where u_j is u_i, v_i or a neighbour of
    one, or v_j is u_i or a neighbour of it (and the same with i and j
    swapped): their stars would overlap, or a link condition change.
    Those left can all be made at once and make no edge twice.
    """
    big = np.iinfo(np.int64).max
    wa, na = mesh.neighbours(u)
    wb, nv = mesh.neighbours(v)
    low_a = np.full(n, big)  # least priority of a collapse with w its u, v or a neighbour
    np.minimum.at(low_a, np.concatenate([u, v, na, nv]), np.concatenate([prio, prio, prio[wa], prio[wb]]))
    low_b = np.full(n, big)  # least priority of a collapse with w its u or a neighbour
    np.minimum.at(low_b, np.concatenate([u, na]), np.concatenate([prio, prio[wa]]))
    return np.nonzero((low_a[u] >= prio) & (low_b[v] >= prio))[0]


def _unit_normals(V: np.ndarray, T: np.ndarray) -> np.ndarray:
    p = V[T]
    nrm = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    with np.errstate(all="ignore"):
        return nrm / np.linalg.norm(nrm, axis=1, keepdims=True)


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise dot products of (k, 3) arrays (a sum over axis 1 costs 6 times this)."""
    return a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1] + a[:, 2] * b[:, 2]


def _max_cos(p: np.ndarray) -> np.ndarray:
    """Cosine of the smallest angle of triangles p (k, 3, 3); 1 for degenerate ones.

    The smallest angle is the one opposite the shortest edge c: by the law
    of cosines (a^2 + b^2 - c^2) / 2ab.
    """
    sq = np.stack([_dot(x, x) for x in (p[:, 1] - p[:, 0], p[:, 2] - p[:, 1], p[:, 0] - p[:, 2])])
    c2 = sq.min(axis=0)
    total = sq.sum(axis=0)
    with np.errstate(all="ignore"):
        out = (total - 2 * c2) / (2 * np.sqrt((sq[0] * sq[1] * sq[2]) / c2))
    out[~(out <= 1.0)] = 1.0
    return out


def _valid(V, T, ref, mesh, u, v, chain, max_edge, cos_bend, cos_floor, needles=True) -> np.ndarray:
    """Which collapses u -> v keep the mesh right (see the module's docstring)."""
    n = len(V)
    good = np.ones(len(u), bool)
    if not len(u):
        return good
    # Link condition: exactly two common neighbours (u is inside the
    # mesh: its neighbours are listed twice, one for each direction).
    which, w = mesh.neighbours(u)
    common = np.bincount(which, weights=mesh.has_edge(v[which], w), minlength=len(u))
    good &= common == 4
    # Along a crease: v is one of u's two neighbours on it, and the new
    # chord v-o is as close to the crease as a chord of ``max_edge`` that
    # turns COARSEN_BEND at its ends: through v, u, o on a circle the chord
    # spans an arc of twice the turn at u, its sagitta is |v-o| tan(turn/2)/2
    # (a straight crease: none).  Short chords may turn more (a remainder
    # between two long ones), up to twice COARSEN_BEND.
    cu = chain[u]
    crease = cu[:, 0] >= 0
    if crease.any():
        other = np.where(cu[:, 0] == v, cu[:, 1], cu[:, 0])
        a, b = V[u] - V[v], V[np.maximum(other, 0)] - V[u]
        with np.errstate(all="ignore"):
            turn = np.arccos(np.clip(_dot(a, b) / np.sqrt(_dot(a, a) * _dot(b, b)), -1.0, 1.0))
        chord = np.sqrt(_dot(a + b, a + b))
        bend = np.radians(tol.COARSEN_BEND)
        good &= ~crease | ((chord * np.tan(turn / 2) <= max_edge * np.tan(bend / 2)) & (turn <= 2 * bend))
    # The triangles of u, each collapse with each of them.
    cand, tid = mesh.triangles(u)
    tri = T[tid]
    p_old = V[tri]
    n_old = np.cross(p_old[:, 1] - p_old[:, 0], p_old[:, 2] - p_old[:, 0])
    # The new triangles' smallest angle: at least COARSEN_ANGLE, or about
    # the smallest of u's triangles (COARSEN_ANGLE_SLACK of it: in a cluster
    # of slivers, one going leaves the next a hair thinner, and the next
    # collapse takes it).
    ceiling = np.full(len(u), -1.0)
    np.maximum.at(ceiling, cand, _max_cos(p_old))
    smallest = np.arccos(np.clip(ceiling, -1.0, 1.0))
    floor = np.arccos(cos_floor)
    ceiling = np.cos(np.where(smallest >= floor, floor, tol.COARSEN_ANGLE_SLACK * smallest))
    # (edges up to max_edge, a little longer where a triangle thinner than
    # COARSEN_ANGLE goes, or an edge a quarter of max_edge: a sliver, or
    # the remainder of a crease, among triangles of the full size)
    d = V[u] - V[v]
    short = _dot(d, d) <= (max_edge / 4) ** 2
    longest = np.where((smallest >= floor) & ~short, max_edge, tol.COARSEN_EDGE_SLIVER * max_edge)
    cu, cv = u[cand], v[cand]
    has_v = (tri == cv[:, None]).any(axis=1)
    # Each collapse removes the two triangles of the edge: exactly two hold v.
    good &= np.bincount(cand, weights=has_v, minlength=len(u)) == 2
    rows = np.nonzero(~has_v)[0]
    tri, cu, cv, cand, tid = tri[rows], cu[rows], cv[rows], cand[rows], tid[rows]
    p_new = V[np.where(tri == cu[:, None], cv[:, None], tri)]
    n_new = np.cross(p_new[:, 1] - p_new[:, 0], p_new[:, 2] - p_new[:, 0])
    len_new = np.sqrt(_dot(n_new, n_new))
    sq = np.sort(np.stack([_dot(a, a) for a in (p_new[:, 1] - p_new[:, 0], p_new[:, 2] - p_new[:, 1],
                                                 p_new[:, 0] - p_new[:, 2])], axis=1), axis=1)
    with np.errstate(all="ignore"):
        bend = _dot(n_new, ref[tid]) / len_new
    # Thinner than the ceiling only as a needle (an edge much shorter than
    # the others, that a collapse takes next: the second of a cluster of
    # three vertices much closer than a cell), never below COARSEN_NEEDLE.
    max_cos = _max_cos(p_new)
    needle = (sq[:, 0] <= tol.COARSEN_NEEDLE_EDGE ** 2 * sq[:, 1]) & (max_cos <= np.cos(np.radians(tol.COARSEN_NEEDLE)))
    # (or of any shape with an edge of no length next to the mesh's: a
    # cluster of lattice crossings at one point goes one by one)
    needle |= sq[:, 0] <= (tol.COARSEN_TINY * max_edge) ** 2
    needle &= needles
    row_ok = ((len_new > 0) & (_dot(n_new, n_old[rows]) > 0) & (bend >= cos_bend)
              & (sq[:, 2] <= longest[cand] ** 2) & ((max_cos <= ceiling[cand]) | needle))
    bad = np.zeros(len(u), bool)
    np.logical_or.at(bad, cand, ~row_ok)
    return good & ~bad


def _apply(T, ref, chain, u, v, n):
    """The faces, their reference normals and the crease neighbours after the collapses u -> v."""
    to = np.arange(n)
    to[u] = v
    T = to[T]
    live = (T[:, 0] != T[:, 1]) & (T[:, 1] != T[:, 2]) & (T[:, 2] != T[:, 0])
    T, ref = T[live], ref[live]
    # Along a crease: v's neighbour u is replaced by u's other neighbour o
    # and o's by v (no two collapses share a v or an o with another's v).
    chain = chain.copy()
    cu = chain[u]
    moved = cu[:, 0] >= 0
    u, v, cu = u[moved], v[moved], cu[moved]
    o = np.where(cu[:, 0] == v, cu[:, 1], cu[:, 0])
    for x, y in ((v, o), (o, v)):
        r, c = np.nonzero(chain[x] == u[:, None])
        chain[x[r], c] = y[r]
    chain[u] = -1
    return T, ref, chain


def _flip(V, T, ref, chain, max_edge, cos_bend, at):
    """Diagonals of pairs of triangles flipped where that raises their smallest angle (not crease edges).

    Only the edges of triangles at the vertices ``at`` (where collapses
    changed the mesh) with an angle below COARSEN_FLIP_BELOW; the new triangles turn no further than COARSEN_BEND from the
    reference normals of the two they replace.  Returns the faces, their
    reference normals and the vertices of the flipped pairs.
    """
    none = np.zeros(0, np.int64)
    # Pairs with a triangle at ``at`` whose smallest angle is below
    # COARSEN_FLIP_BELOW: both triangles of each of its edges have two
    # vertices of such triangles, as has any triangle with an edge a flip
    # could make (which must not exist already).
    low = np.nonzero(at[T].any(axis=1))[0]
    low = low[_max_cos(V[T[low]]) > np.cos(np.radians(tol.COARSEN_FLIP_BELOW))]
    ring = np.zeros(len(at), bool)
    ring[T[low].ravel()] = True
    sel = np.nonzero(ring[T].sum(axis=1) >= 2)[0]
    S = T[sel]
    m = len(S)
    if m < 2:
        return T, ref, none
    n = len(V)
    half = S[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    key = np.minimum(half[:, 0], half[:, 1]) * n + np.maximum(half[:, 0], half[:, 1])
    order = _order(key)
    ks = key[order]
    same = np.nonzero(ks[1:] == ks[:-1])[0]
    # Edges with exactly two triangles.
    two = same[((same == 0) | (ks[same - 1] != ks[same])) & ((same + 2 >= len(ks)) | (ks[np.minimum(same + 2, len(ks) - 1)] != ks[same]))]
    h1, h2 = order[two], order[two + 1]
    t1, t2 = h1 // 3, h2 // 3
    a, b = half[h1, 0], half[h1, 1]
    c = S[t1, (h1 % 3 + 2) % 3]
    dd = S[t2, (h2 % 3 + 2) % 3]
    lowt = np.zeros(m, bool)
    lowt[np.searchsorted(sel, low)] = True
    near = lowt[t1] | lowt[t2]
    h1, h2, t1, t2, a, b, c, dd = (x[near] for x in (h1, h2, t1, t2, a, b, c, dd))
    # Not a crease edge.
    crease = ((chain[a] == b[:, None]).any(axis=1)) | ((chain[b] == a[:, None]).any(axis=1))
    ok = ~crease & (c != dd)
    new1 = np.stack([c, a, dd], 1)
    new2 = np.stack([dd, b, c], 1)
    q1, q2 = V[new1], V[new2]
    n1 = np.cross(q1[:, 1] - q1[:, 0], q1[:, 2] - q1[:, 0])
    n2 = np.cross(q2[:, 1] - q2[:, 0], q2[:, 2] - q2[:, 0])
    with np.errstate(all="ignore"):
        n1 /= np.linalg.norm(n1, axis=1, keepdims=True)
        n2 /= np.linalg.norm(n2, axis=1, keepdims=True)
    r1, r2 = ref[sel[t1]], ref[sel[t2]]
    ok &= ((_dot(n1, r1) >= cos_bend) & (_dot(n1, r2) >= cos_bend)
           & (_dot(n2, r1) >= cos_bend) & (_dot(n2, r2) >= cos_bend))
    ok &= _dot(V[c] - V[dd], V[c] - V[dd]) <= max_edge * max_edge
    # (cosines of the smallest angles: smaller is better)
    before = np.maximum(_max_cos(V[S[t1]]), _max_cos(V[S[t2]]))
    after = np.maximum(_max_cos(q1), _max_cos(q2))
    ok &= after < before - 1e-12
    # The new edge must not exist already.
    newkey = np.minimum(c, dd) * n + np.maximum(c, dd)
    ok &= ks[np.minimum(np.searchsorted(ks, newkey), len(ks) - 1)] != newkey
    idx = np.nonzero(ok)[0]
    if not len(idx):
        return T, ref, none
    # Flips sharing no triangle: the best gain wins at each triangle (ties:
    # the first in edge order).
    rank = np.empty(len(idx), np.int64)
    rank[np.lexsort((idx, -(before - after)[idx]))] = np.arange(len(idx), 0, -1)
    best = np.zeros(m, np.int64)
    np.maximum.at(best, t1[idx], rank)
    np.maximum.at(best, t2[idx], rank)
    idx = idx[(rank == best[t1[idx]]) & (rank == best[t2[idx]])]
    # (and no two making the same edge, across two quads with the same
    # opposite vertices)
    _, first = np.unique(newkey[idx], return_index=True)
    idx = idx[np.sort(first)]
    T = T.copy()
    T[sel[t1[idx]]] = new1[idx]
    T[sel[t2[idx]]] = new2[idx]
    return T, ref, np.concatenate([a[idx], b[idx], c[idx], dd[idx]])
