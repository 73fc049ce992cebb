"""Strips from the mesh's open edges next to an end of F's domain up to that end.

Where the surface runs out of F's domain with F finite there (sqrt(1 - x^2
- y^2) - z - 0.2 at x^2 + y^2 = 1: the root goes to 0), its boundary is the
curve C on which F with the root replaced by 0 (``G1``) and the root's
argument (``G2``) both vanish (asin, acos, acosh at the ends of their
domain the same way: F with the function replaced by its value there, and
the argument's distance to the end).  The boxes across that end have no cycles
(F is undefined on part of their faces), so the mesh stops up to a cell
short of C, open there.  The open edges next to it, chained as the mesh's
boundary runs, get a strip up to C: each chain vertex moved onto C by
minimum-norm Newton on (G1, G2) (a vertex on a face of the box stays in
that face; points of C closer than ``DOMAIN_STRIP_MERGE`` cells merged:
a staircase of lattice edges across C lands its ends side by side), and
the two polylines zipped by triangles, the shorter diagonal first,
oriented as the mesh.  The mesh's boundary is then on C (its vertices, to
rounding), as the surface's is.  A chain with a vertex that does not reach
C within ``DOMAIN_STRIP_REACH`` cells keeps its gap, as does a strip
triangle making an edge of three triangles (said by the mesh's note).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from singmesh import tolerances as tol
from singmesh.facets.tubes import faces_of


def _oriented_boundary(faces: np.ndarray) -> np.ndarray:
    """(k, 2) edges a -> b of one triangle each, as that triangle has them."""
    directed = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    key = np.sort(directed, axis=1).astype(np.int64)
    # One int64 per undirected edge: np.unique on rows (axis=0) cost a
    # second on the 200k-vertex meshes of asin's domain, now a domain edge.
    key = key[:, 0] * (int(faces.max()) + 1) + key[:, 1]
    _, inverse, count = np.unique(key, return_inverse=True, return_counts=True)
    return directed[count[inverse.reshape(-1)] == 1]


def _onto_edge(systems, points, box, reach):
    """Each point moved onto the nearest curve G1 = G2 = 0 of ``systems`` (in its box face if on one):
    (points, ok)."""
    out = np.array(points, float)
    best = np.full(len(points), np.inf)
    on_face = faces_of(points, box)
    extra = np.zeros((len(points), 4))
    face = np.argmax(on_face, axis=1)
    axis, side = face // 2, face % 2
    extra[np.arange(len(points)), axis] = 1.0
    extra[:, 3] = box[axis, side]
    faced = on_face.any(axis=1)
    for system in systems:
        for rows, ex in ((np.flatnonzero(~faced), None), (np.flatnonzero(faced), extra)):
            if not len(rows):
                continue
            q, ok = system.newton(points[rows], reach, None if ex is None else ex[rows])
            d = np.linalg.norm(q - points[rows], axis=1)
            inside = ((q >= box[:, 0] - 1e-12 * reach) & (q <= box[:, 1] + 1e-12 * reach)).all(axis=1)
            take = ok & inside & (d < best[rows])
            out[rows[take]] = np.clip(q[take], box[:, 0], box[:, 1])
            best[rows[take]] = d[take]
    return out, np.isfinite(best)


def reach_domain_edges(vertices: np.ndarray, faces: np.ndarray, surface, box: np.ndarray,
                       cell: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """The mesh with strips from its open edges next to an end of F's domain up to that end.

    Returns
    -------
    vertices, faces : the mesh, new vertices after the old ones
    source : (k,) int64  for each new vertex (after the old ones, on the domain's end: to be kept
                         where they are), the open edge's vertex it was moved from
    strips : int         triangles added
    """
    systems = surface.domain_edge_systems()
    none = np.zeros(0, np.int64)
    if not systems or not len(faces):
        return vertices, faces, none, 0
    box = np.asarray(box, float)
    edges = _oriented_boundary(faces)
    on = faces_of(vertices[edges[:, 0]], box) & faces_of(vertices[edges[:, 1]], box)
    edges = edges[~on.any(axis=1)]
    if not len(edges):
        return vertices, faces, none, 0
    mid = vertices[edges].mean(axis=1)
    edges = edges[surface.ends_near(mid, tol.DOMAIN_EDGE_REACH * cell)]
    if not len(edges):
        return vertices, faces, none, 0
    ends = np.unique(edges)
    w, ok = _onto_edge(systems, vertices[ends], box, tol.DOMAIN_STRIP_REACH * cell)
    # On C F is 0 + sqrt(0): the root's argument may be a rounding error
    # below 0 there (F NaN).  Such points go back towards their vertex until F is defined.
    v = vertices[ends]
    for k in range(tol.DOMAIN_STRIP_NUDGES):
        bad = np.flatnonzero(ok & ~np.isfinite(surface(w)))
        if not len(bad):
            break
        back = v[bad] - w[bad]
        back /= np.maximum(np.linalg.norm(back, axis=1), 1e-300)[:, None]
        w[bad] += 1e-15 * 4.0 ** k * np.maximum(np.abs(w[bad]).max(axis=1), 1.0)[:, None] * back
    ok &= np.isfinite(surface(w))
    # A vertex on C already (the lattice's end there) is its own end; a
    # point landing on another vertex is that vertex.
    size = float(np.max(box[:, 1] - box[:, 0]))
    d, near = cKDTree(vertices).query(w)
    same = ok & (d <= tol.DOMAIN_STRIP_SAME * size)
    target = np.full(len(vertices), -1, np.int64)      # vertex (old) it lands on, or -1
    target[ends[same]] = near[same]
    moved = np.zeros(len(vertices), bool)
    moved[ends[ok & ~same]] = True
    where = np.zeros((len(vertices), 3))
    where[ends[ok]] = w[ok]
    points, source, zips = [], [], []
    n_new = len(vertices)
    for chain, closed in _chains(edges):
        if not ((target[chain] >= 0) | moved[chain]).all():
            continue  # (some end does not reach C: the gap stays there, said by the note)
        # C's points along the chain, consecutive ones closer than a
        # fraction of a cell merged (a staircase of lattice edges across C
        # lands its ends next to each other).
        ids = np.empty(len(chain), np.int64)
        last = None
        for k, vtx in enumerate(chain.tolist()):
            if target[vtx] >= 0:
                ids[k], last = target[vtx], None
            elif last is not None and np.linalg.norm(where[vtx] - points[-1]) <= tol.DOMAIN_STRIP_MERGE * cell:
                ids[k] = n_new - 1
            else:
                points.append(where[vtx])
                source.append(vtx)
                ids[k], last, n_new = n_new, vtx, n_new + 1
        zips.append((chain, ids, closed))
    P = np.concatenate([vertices, np.array(points).reshape(-1, 3)])
    tris = [t for chain, ids, closed in zips for t in _zip(P, chain, ids, closed)]
    if not tris:
        return vertices, faces, none, 0
    tris = np.array(tris, np.int64)
    # (a strip triangle of no area: left out)
    good = np.linalg.norm(_normal(P, tris), axis=1) > 0
    tris = tris[good]
    # No edge with three triangles (a strip meeting a triangle it should not).
    for _ in range(3):
        allf = np.concatenate([faces, tris])
        und = np.sort(np.concatenate([allf[:, [0, 1]], allf[:, [1, 2]], allf[:, [2, 0]]]), axis=1)
        _, inv, count = np.unique(und, axis=0, return_inverse=True, return_counts=True)
        over = (count[inv.reshape(-1)] > 2).reshape(3, -1).any(axis=0)[len(faces):]
        if not over.any():
            break
        tris = tris[~over]
    used = np.unique(tris[tris >= len(vertices)]) if len(tris) else np.zeros(0, np.int64)
    keep = np.zeros(len(P), bool)
    keep[: len(vertices)] = True
    keep[used] = True
    renum = np.cumsum(keep) - 1
    src = np.concatenate([np.full(len(vertices), -1, np.int64), np.array(source, np.int64).reshape(-1)])
    return P[keep], np.concatenate([faces, renum[tris]]), src[used], len(tris)


def _chains(edges: np.ndarray):
    """The directed boundary edges a -> b as chains of vertices (open ones from a vertex no edge enters,
    then the loops): [(vertices, closed)], a loop's first vertex not repeated at its end."""
    nxt = {}
    into = set()
    for a, b in edges.tolist():
        if a in nxt:          # (a vertex where the boundary branches: no chain through it)
            nxt[a] = None
        else:
            nxt[a] = b
        into.add(b)
    seen = set()
    out = []
    starts = [a for a in sorted(nxt) if a not in into] + sorted(nxt)
    for s in starts:
        if s in seen or nxt.get(s) is None:
            continue
        chain = [s]
        seen.add(s)
        v = nxt[s]
        closed = False
        while v is not None:
            if v == s:
                closed = True
                break
            if v in seen:
                break
            chain.append(v)
            seen.add(v)
            v = nxt.get(v)
        out.append((np.array(chain, np.int64), closed))
    return out


def _zip(P: np.ndarray, chain: np.ndarray, ids: np.ndarray, closed: bool) -> list:
    """Triangles between a boundary chain v_0 -> v_1 -> ... (its triangles on their left) and its points on C
    (``ids``: index in P of each vertex's, consecutive repeats merged), oriented as the mesh: each step
    advances along the chain (v_{i+1}, v_i, w_j) or along C (v_i, w_j, w_{j+1}), the shorter diagonal first."""
    V = chain.tolist()
    W = [ids[0]]
    for k in ids[1:].tolist():
        if k != W[-1]:
            W.append(k)
    if closed:
        V = V + [V[0]]
        if W[-1] != ids[0] or len(W) == 1:
            W = W + [ids[0]]
    out = []
    i = j = 0
    while i < len(V) - 1 or j < len(W) - 1:
        if i == len(V) - 1 or (V[i] == W[j] and j < len(W) - 1):
            # (at a chain vertex on C, along C first: the chain's edge from it then has its triangle)
            step_v = False
        elif j == len(W) - 1:
            step_v = True
        else:
            step_v = np.linalg.norm(P[V[i + 1]] - P[W[j]]) <= np.linalg.norm(P[V[i]] - P[W[j + 1]])
        # (a chain vertex on C is its own point there: no triangle of no area)
        t = (V[i + 1], V[i], W[j]) if step_v else (V[i], W[j], W[j + 1])
        if len(set(t)) == 3:
            out.append(t)
        i, j = (i + 1, j) if step_v else (i, j + 1)
    return out


def _normal(P: np.ndarray, tris: np.ndarray) -> np.ndarray:
    return np.cross(P[tris[:, 1]] - P[tris[:, 0]], P[tris[:, 2]] - P[tris[:, 0]])


def on_domain_end(surface, points: np.ndarray, size: float) -> np.ndarray:
    """(k,) bool: the points lie on an end of F's domain where the surface ends (G1 = G2 = 0 of one of
    ``surface.domain_edge_systems()`` to ``DOMAIN_STRIP_ON`` of the box ``size``, first order)."""
    out = np.zeros(len(points), bool)
    for system in surface.domain_edge_systems():
        with np.errstate(all="ignore"):
            v, g = system.values(points)
            d = np.abs(v) / np.linalg.norm(g, axis=2)
        out |= (d <= tol.DOMAIN_STRIP_ON * size).all(axis=1)
    return out
