"""Coarsening: the fine triangles of crease tubes on flat faces and straight creases, merged.

The tubes round creases are meshed on the fine lattice: along a straight
crease of a cube the strips and their margin are triangles a fine cell
across, where the faces elsewhere have triangles of the coarse lattice
(57k triangles for a cube, 44k of them within 12 cells of a crease).  Where
the mesh is flat (every triangle round a vertex in one plane) and a crease
is straight (a crease vertex on the line through its two neighbours on the
crease), a vertex can go without changing what the mesh represents: each
of its triangles is replaced by one in the same plane with the vertex
moved to a neighbour (a half-edge collapse).  This stage does such
collapses in rounds: the checks below for every vertex whose
neighbourhood changed (numpy over all of them at once), then as many of
the valid collapses as can be made together (shortest edge first, none
next to another's u or v), then flips of the diagonals of coplanar pairs
of triangles where that raises their smallest angle; up to an edge length
of the mesh size elsewhere.  Only the triangles at vertices on a flat
piece or a crease, and at their neighbours, take part.

A collapse of u onto its neighbour v is made only where

* u is not kept (singular points, ends and corners of curves, vertices of
  other curves, on the box's faces, on boundary or non-manifold edges);
* a crease vertex goes onto one of its two neighbours along the crease
  (the crease graph loses u, its two edges become one);
* every triangle of u that does not hold v stays in its plane with u
  moved to v (u within ``COARSEN_FLAT`` of the box's size from its new
  plane), keeps its orientation, has no edge longer than ``max_edge`` and
  no angle below ``COARSEN_ANGLE`` degrees or the smallest of u's triangles;
* u and v have exactly two common neighbours (the link condition: the
  surface keeps its topology).

Vertices stay where they are: every vertex left is a vertex of the mesh
before, on the surface as it was, and crease vertices stay on the crease.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy.sparse import coo_matrix

from singmesh import tolerances as tol
from singmesh.facets.records import vertex_of
from singmesh.topology import on_box_boundary


def coarsen_crease_mesh(vertices: np.ndarray, faces: np.ndarray, vkeys: np.ndarray, per_vertex: list, curves,
                        key0: int, singular_keys: np.ndarray, box: np.ndarray, max_edge: float):
    """The mesh of a surface with creases coarsened on its flat parts (:func:`coarsen_flat`), and its curves.

    ``curves`` (a CurveSet whose point i is the vertex keyed ``key0 + i``)
    loses the crease points that are no vertex any more; its keys are
    renumbered with it.  ``per_vertex``: arrays (V, ...) kept for the
    vertices left.  Returns (vertices, faces, vkeys, per_vertex, curves).
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
    keep |= np.isin(vkeys, singular_keys)
    size = float(np.max(box[:, 1] - box[:, 0]))
    keep |= on_box_boundary(vertices, box, 1e-9)
    faces, chain = coarsen_flat(vertices, faces, keep, chain, max_edge, tol.COARSEN_FLAT * size)
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


def coarsen_flat(vertices: np.ndarray, faces: np.ndarray, keep: np.ndarray, chain: np.ndarray,
                 max_edge: float, flat: float, rounds: int = 60) -> tuple[np.ndarray, np.ndarray]:
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
    flat : float
        Distance (absolute) from a plane that counts as in it.

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
    key = e[:, 0] * n + e[:, 1]
    uk, cnt = np.unique(key, return_counts=True)
    odd = uk[cnt != 2]
    keep[odd // n] = True
    keep[odd % n] = True
    # Only vertices on a flat piece of the mesh (all their neighbours in
    # the plane of one of their triangles) and crease vertices can go;
    # collapses keep that so.  The triangles that can change are those at
    # them and at their neighbours (the stars of the targets, whose
    # neighbours the link condition reads): the rest (a sphere's sheet)
    # is left out of the rounds.
    first_tri = np.full(n, -1, np.int64)
    first_tri[T[::-1].ravel()] = np.repeat(np.arange(len(T))[::-1], 3)
    p = V[T]
    nrm = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    with np.errstate(all="ignore"):
        nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    d = T[:, [0, 1, 1, 2, 2, 0, 1, 0, 2, 1, 0, 2]].reshape(-1, 2)
    dev = np.abs(np.einsum("ij,ij->i", nrm[first_tri[d[:, 0]]], V[d[:, 1]] - V[d[:, 0]]))
    off_plane = np.zeros(n, bool)
    off_plane[d[~(dev <= flat), 0]] = True
    active = (~off_plane | (chain[:, 0] >= 0)) & ~keep
    near = active.copy()
    near[d[active[d[:, 0]], 1]] = True
    work = near[T].any(axis=1)
    rest, T = T[~work], T[work]
    cos_floor = np.cos(np.radians(tol.COARSEN_ANGLE))
    best_v = np.full(n, -1, np.int64)
    best_len = np.full(n, np.inf)
    dirty = active
    for _ in range(rounds):
        adj = _adjacency(T, n)
        todo = np.nonzero(dirty & active)[0]
        if len(todo):
            bv, bl = _best_collapses(V, T, adj, todo, chain, max_edge, flat, cos_floor)
            best_v[todo], best_len[todo] = bv, bl
        u = np.nonzero(best_v >= 0)[0]
        u, v = _independent(adj, u, best_v[u], best_len[u], n)
        if not len(u):
            break
        # What the collapses change: the stars of v and of u's neighbours,
        # and the neighbours of those (whose link condition they change).
        changed = np.zeros(n, bool)
        changed[v] = True
        changed[_neighbours(adj, u)] = True
        T, chain = _apply(T, chain, u, v, n)
        T, flipped = _flip_flat(V, T, chain, flat, max_edge, cos_floor, changed)
        changed[flipped] = True
        adj = _adjacency(T, n)
        dirty = changed.copy()
        dirty[_neighbours(adj, np.nonzero(changed)[0])] = True
        best_v[u] = -1
        best_v[dirty] = -1
        best_len[dirty] = np.inf
    return np.concatenate([rest, T]), chain


def _adjacency(T: np.ndarray, n: int):
    """The vertex adjacency of the triangles as a CSR matrix (entries 1)."""
    d = T[:, [0, 1, 1, 2, 2, 0, 1, 0, 2, 1, 0, 2]].reshape(-1, 2)
    adj = coo_matrix((np.ones(len(d), np.int8), (d[:, 0], d[:, 1])), shape=(n, n)).tocsr()
    adj.data[:] = 1
    return adj


def _neighbours(adj, w: np.ndarray) -> np.ndarray:
    """All neighbours of the vertices w (with repeats)."""
    ptr, idx = adj.indptr, adj.indices
    k = ptr[w + 1] - ptr[w]
    return idx[np.repeat(ptr[w], k) + (np.arange(k.sum()) - np.repeat(np.cumsum(k) - k, k))]


def _max_cos(p: np.ndarray) -> np.ndarray:
    """Cosine of the smallest angle of triangles p (k, 3, 3); 1 for degenerate ones."""
    e = [p[:, (i + 1) % 3] - p[:, i] for i in range(3)]
    sq = [np.einsum("ij,ij->i", x, x) for x in e]
    out = np.full(len(p), -1.0)
    with np.errstate(all="ignore"):
        for i in range(3):
            c = -np.einsum("ij,ij->i", e[i], e[(i + 2) % 3]) / np.sqrt(sq[i] * sq[(i + 2) % 3])
            out = np.maximum(out, np.nan_to_num(c, nan=1.0))
    return out


def _best_collapses(V, T, adj, todo, chain, max_edge, flat, cos_floor):
    """For each vertex u of ``todo``: the neighbour v it can collapse onto by the shortest edge (-1: none), and that length."""
    n = len(V)
    out_v = np.full(len(todo), -1, np.int64)
    out_l = np.full(len(todo), np.inf)
    ptr, idx = adj.indptr, adj.indices
    k = ptr[todo + 1] - ptr[todo]
    which = np.repeat(np.arange(len(todo)), k)
    u = todo[which]
    v = _neighbours(adj, todo)
    in_chain = chain[u, 0] >= 0
    ok = ~in_chain | (chain[u, 0] == v) | (chain[u, 1] == v)
    which, u, v = which[ok], u[ok], v[ok]
    if not len(u):
        return out_v, out_l
    # Only the COARSEN_TRIES shortest edges of each u are tried (the
    # shortest valid one is taken): a third of the work of trying all.
    length = np.einsum("ij,ij->i", V[u] - V[v], V[u] - V[v])
    order = np.lexsort((v, length, which))
    which, u, v = which[order], u[order], v[order]
    rank = np.arange(len(which)) - np.searchsorted(which, which)
    near = rank < tol.COARSEN_TRIES
    which, u, v = which[near], u[near], v[near]
    # Link condition: exactly two common neighbours.
    common = np.asarray(adj[u].multiply(adj[v]).sum(axis=1)).ravel()
    link = common == 2
    which, u, v = which[link], u[link], v[link]
    if not len(u):
        return out_v, out_l
    # The triangles of u, each candidate with each of them.
    start, tris = _incidence(T, n)
    deg = start[u + 1] - start[u]
    cand = np.repeat(np.arange(len(u)), deg)
    tid = tris[np.repeat(start[u], deg) + (np.arange(deg.sum()) - np.repeat(np.cumsum(deg) - deg, deg))]
    tri = T[tid]
    # The new triangles' smallest angle: at least COARSEN_ANGLE, or the
    # smallest of u's triangles.
    p_old = V[tri]
    n_old = np.cross(p_old[:, 1] - p_old[:, 0], p_old[:, 2] - p_old[:, 0])
    ceiling = np.full(len(u), -1.0)
    np.maximum.at(ceiling, cand, _max_cos(p_old))
    ceiling = np.maximum(ceiling, cos_floor)
    cu, cv = u[cand], v[cand]
    has_v = (tri == cv[:, None]).any(axis=1)
    # Each collapse removes the two triangles of the edge: exactly two hold v.
    two = np.bincount(cand, weights=has_v, minlength=len(u)) == 2
    rows = np.nonzero(~has_v)[0]
    tri, cu, cv = tri[rows], cu[rows], cv[rows]
    p_new = V[np.where(tri == cu[:, None], cv[:, None], tri)]
    n_new = np.cross(p_new[:, 1] - p_new[:, 0], p_new[:, 2] - p_new[:, 0])
    len_new = np.sqrt(np.einsum("ij,ij->i", n_new, n_new))
    with np.errstate(all="ignore"):
        off = np.abs(np.einsum("ij,ij->i", n_new, V[cu] - V[cv])) / len_new
    edge_new = np.sqrt(np.max([np.einsum("ij,ij->i", a, a) for a in
                               (p_new[:, 1] - p_new[:, 0], p_new[:, 2] - p_new[:, 1], p_new[:, 0] - p_new[:, 2])], axis=0))
    cand = cand[rows]
    row_ok = ((len_new > 0) & (off <= flat) & (np.einsum("ij,ij->i", n_new, n_old[rows]) > 0)
              & (edge_new <= max_edge) & (_max_cos(p_new) <= ceiling[cand]))
    bad = np.zeros(len(u), bool)
    np.logical_or.at(bad, cand, ~row_ok)
    good = ~bad & two
    which, u, v = which[good], u[good], v[good]
    length = np.linalg.norm(V[u] - V[v], axis=1)
    order = np.lexsort((v, length, which))
    which, v, length = which[order], v[order], length[order]
    first = np.r_[True, which[1:] != which[:-1]] if len(which) else np.zeros(0, bool)
    out_v[which[first]] = v[first]
    out_l[which[first]] = length[first]
    return out_v, out_l


def _incidence(T: np.ndarray, n: int):
    """CSR of vertex -> triangles: (start (n + 1,), triangle ids)."""
    v = T.ravel()
    order = np.argsort(v, kind="stable")
    start = np.concatenate([[0], np.cumsum(np.bincount(v, minlength=n))])
    return start, order // 3


def _independent(adj, u: np.ndarray, v: np.ndarray, length: np.ndarray, n: int):
    """As many collapses u -> v as can be made at once, shortest first.

    No u next to another's u or v (their stars would overlap, or u's
    link condition change), and no v next to another's u (v's would):
    then each collapse's checks still hold when all are made, and no two
    make the same edge.
    """
    ptr, nbr = adj.indptr, adj.indices
    lock = np.zeros(n, bool)
    taken = np.zeros(n, bool)  # a chosen u or a neighbour of one
    pick = []
    for i in np.lexsort((u, length)).tolist():
        uu, vv = int(u[i]), int(v[i])
        if lock[uu] or taken[vv]:
            continue
        nu, nv = nbr[ptr[uu]:ptr[uu + 1]], nbr[ptr[vv]:ptr[vv + 1]]
        pick.append(i)
        lock[uu] = lock[nu] = lock[nv] = True
        taken[uu] = taken[nu] = True
    pick = np.array(pick, np.int64)
    return u[pick], v[pick]


def _apply(T, chain, u, v, n):
    """The faces and crease neighbours after the collapses u -> v."""
    to = np.arange(n)
    to[u] = v
    T = to[T]
    T = T[(T[:, 0] != T[:, 1]) & (T[:, 1] != T[:, 2]) & (T[:, 2] != T[:, 0])]
    # Along a crease: v's neighbour u is replaced by u's other neighbour.
    chain = chain.copy()
    cu = chain[u]
    other = np.where(cu[:, 0] == v, cu[:, 1], cu[:, 0])
    moved = cu[:, 0] >= 0
    for uu, vv, oo in zip(u[moved].tolist(), v[moved].tolist(), other[moved].tolist()):
        chain[vv][chain[vv] == uu] = oo
        chain[oo][chain[oo] == uu] = vv
    chain[u] = -1
    return T, chain


def _flip_flat(V, T, chain, flat, max_edge, cos_floor, at=None, only=None):
    """Diagonals of coplanar pairs of triangles flipped where that raises their smallest angle (not crease edges)."""
    none = np.zeros(0, np.int64)
    if at is not None:
        # Only the edges at these vertices (where collapses changed the
        # mesh): both triangles of each hold one of them.  With every
        # triangle at their vertices, which holds every edge a flip could
        # make that exists already.
        ring = np.zeros(len(at), bool)
        ring[T[at[T].any(axis=1)].ravel()] = True
        sel = np.nonzero(ring[T].any(axis=1))[0]
        sub, changed = _flip_flat(V, T[sel], chain, flat, max_edge, cos_floor, only=at)
        if not len(changed):
            return T, none
        T = T.copy()
        T[sel] = sub
        return T, changed
    m = len(T)
    if m < 2:
        return T, none
    n = len(V)
    half = T[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    key = np.minimum(half[:, 0], half[:, 1]) * n + np.maximum(half[:, 0], half[:, 1])
    order = np.argsort(key, kind="stable")
    ks = key[order]
    same = np.nonzero(ks[1:] == ks[:-1])[0]
    # Edges with exactly two triangles.
    two = same[((same == 0) | (ks[same - 1] != ks[same])) & ((same + 2 >= len(ks)) | (ks[np.minimum(same + 2, len(ks) - 1)] != ks[same]))]
    h1, h2 = order[two], order[two + 1]
    t1, t2 = h1 // 3, h2 // 3
    a, b = half[h1, 0], half[h1, 1]
    c = T[t1, (h1 % 3 + 2) % 3]
    dd = T[t2, (h2 % 3 + 2) % 3]
    if only is not None:
        # (edges at these vertices: the triangles round c and d are all here)
        near = only[a] | only[b]
        h1, h2, t1, t2, a, b, c, dd = (x[near] for x in (h1, h2, t1, t2, a, b, c, dd))
    # Not a crease edge.
    crease = ((chain[a] == b[:, None]).any(axis=1)) | ((chain[b] == a[:, None]).any(axis=1))
    ok = ~crease & (c != dd)
    # Coplanar: d in t1's plane.
    p = V[T[t1]]
    nrm = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    with np.errstate(all="ignore"):
        unit = nrm / np.linalg.norm(nrm, axis=1, keepdims=True)
        ok &= np.abs(np.einsum("ij,ij->i", unit, V[dd] - V[a])) <= flat
    new1 = np.stack([c, a, dd], 1)
    new2 = np.stack([dd, b, c], 1)
    q1, q2 = V[new1], V[new2]
    n1 = np.cross(q1[:, 1] - q1[:, 0], q1[:, 2] - q1[:, 0])
    n2 = np.cross(q2[:, 1] - q2[:, 0], q2[:, 2] - q2[:, 0])
    ok &= (np.einsum("ij,ij->i", n1, nrm) > 0) & (np.einsum("ij,ij->i", n2, nrm) > 0)
    ok &= np.linalg.norm(V[c] - V[dd], axis=1) <= max_edge
    # (cosines of the smallest angles: smaller is better)
    before = np.maximum(_max_cos(V[T[t1]]), _max_cos(V[T[t2]]))
    after = np.maximum(_max_cos(q1), _max_cos(q2))
    ok &= after < before - 1e-12
    # The new edge must not exist already.
    newkey = np.minimum(c, dd) * n + np.maximum(c, dd)
    ok &= ~np.isin(newkey, ks)
    idx = np.nonzero(ok)[0]
    if not len(idx):
        return T, none
    # Flips sharing no triangle: the best gain wins at each triangle.
    gain = (before - after)[idx]
    best = np.full(m, -np.inf)
    np.maximum.at(best, t1[idx], gain)
    np.maximum.at(best, t2[idx], gain)
    win = (gain >= best[t1[idx]]) & (gain >= best[t2[idx]])
    idx = idx[win]
    # (ties: one flip per triangle)
    # (and no two making the same edge, across two quads with the same
    # opposite vertices)
    seen = np.zeros(m, bool)
    made = set()
    pick = []
    for i in idx.tolist():
        if seen[t1[i]] or seen[t2[i]] or int(newkey[i]) in made:
            continue
        seen[t1[i]] = seen[t2[i]] = True
        made.add(int(newkey[i]))
        pick.append(i)
    pick = np.array(pick, np.int64)
    T = T.copy()
    T[t1[pick]] = new1[pick]
    T[t2[pick]] = new2[pick]
    return T, np.concatenate([a[pick], b[pick], c[pick], dd[pick]])
