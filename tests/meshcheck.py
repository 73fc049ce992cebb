"""Mesh checks written independently of singmesh's own report.

Plain Python and numpy over the triangle list: edge incidences, Euler
characteristic, components (union-find), duplicates, degenerate triangles,
and the fans of triangles around a vertex.
"""

from __future__ import annotations

from collections import Counter, defaultdict

import numpy as np


def edge_counts(faces) -> Counter:
    c = Counter()
    for a, b, d in np.asarray(faces).tolist():
        for u, v in ((a, b), (b, d), (d, a)):
            c[(min(u, v), max(u, v))] += 1
    return c


def euler(vertices, faces) -> int:
    used = np.unique(np.asarray(faces))
    return len(used) - len(edge_counts(faces)) + len(faces)


def components(faces) -> int:
    parent = {}

    def find(a):
        while parent.setdefault(a, a) != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    for a, b, d in np.asarray(faces).tolist():
        ra, rb, rd = find(a), find(b), find(d)
        parent[rb] = ra
        parent[find(rd)] = ra
    return len({find(v) for v in np.unique(np.asarray(faces)).tolist()})


def boundary_edges(faces):
    return [e for e, n in edge_counts(faces).items() if n == 1]


def non_manifold_edges(faces):
    return [e for e, n in edge_counts(faces).items() if n > 2]


def on_box(points, box, rel=1e-9) -> np.ndarray:
    box = np.asarray(box, float)
    tol = rel * (box[:, 1] - box[:, 0])
    p = np.asarray(points)
    return ((np.abs(p - box[:, 0]) <= tol) | (np.abs(p - box[:, 1]) <= tol)).any(axis=-1)


def boundary_edges_off_box(vertices, faces, box):
    """Boundary edges whose two ends do not lie on one face of the box."""
    v = np.asarray(vertices)
    return [e for e in boundary_edges(faces) if not _same_box_face(v[e[0]], v[e[1]], box)]


def _same_box_face(p, q, box, rel=1e-9):
    box = np.asarray(box, float)
    tol = rel * (box[:, 1] - box[:, 0])
    for a in range(3):
        for s in range(2):
            if abs(p[a] - box[a, s]) <= tol[a] and abs(q[a] - box[a, s]) <= tol[a]:
                return True
    return False


def duplicate_vertices(vertices, rel=1e-12) -> int:
    v = np.asarray(vertices)
    scale = max(np.ptp(v, axis=0).max(), 1e-300) if len(v) else 1.0
    q = np.round(v / (rel * scale)).astype(np.int64)
    return len(q) - len(np.unique(q, axis=0))


def degenerate_triangles(vertices, faces, rel=1e-10) -> int:
    """Triangles with a repeated vertex or collinear vertices (zero area
    relative to their own longest edge: size alone is no defect)."""
    faces = np.asarray(faces)
    if len(faces) == 0:
        return 0
    p = np.asarray(vertices)[faces]
    area2 = np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    longest = np.max([np.sum((p[:, i] - p[:, (i + 1) % 3]) ** 2, axis=1) for i in range(3)], axis=0)
    repeated = (faces[:, 0] == faces[:, 1]) | (faces[:, 1] == faces[:, 2]) | (faces[:, 0] == faces[:, 2])
    return int(((area2 <= rel * longest) | repeated).sum())


def fans_at(faces, vertex: int) -> int:
    """Number of edge-connected fans of triangles around ``vertex``.

    Two triangles at the vertex are in one fan when they share an edge
    through the vertex.  At a manifold vertex this is 1; at a node (two
    cones) 2.
    """
    tris = [t for t in np.asarray(faces).tolist() if vertex in t]
    by_edge = defaultdict(list)
    for i, t in enumerate(tris):
        for w in t:
            if w != vertex:
                by_edge[w].append(i)
    parent = list(range(len(tris)))

    def find(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    for ids in by_edge.values():
        for j in ids[1:]:
            parent[find(j)] = find(ids[0])
    return len({find(i) for i in range(len(tris))})


def fans_are_closed(faces, vertex: int) -> bool:
    """Every edge through ``vertex`` is used by exactly two of its triangles."""
    c = Counter()
    for t in np.asarray(faces).tolist():
        if vertex in t:
            for w in t:
                if w != vertex:
                    c[w] += 1
    return all(n == 2 for n in c.values())


def tiny_triangles(vertices, faces, box, rel=1e-14) -> int:
    """Triangles whose area is at most ``rel`` times the box's largest side squared.

    An absolute test (as viewers, slicers and FEM codes see it): a small
    but well-shaped triangle of 1e-8 of the box counts too.
    """
    faces = np.asarray(faces)
    if len(faces) == 0:
        return 0
    p = np.asarray(vertices)[faces]
    area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    size = np.ptp(np.asarray(box, float), axis=1).max()
    return int((area <= rel * size * size).sum())


def close_vertex_pairs(vertices, box, rel=1e-9) -> int:
    """Pairs of vertices closer than ``rel`` times the box's largest side."""
    from scipy.spatial import cKDTree

    v = np.asarray(vertices)
    if len(v) < 2:
        return 0
    size = np.ptp(np.asarray(box, float), axis=1).max()
    return len(cKDTree(v).query_pairs(rel * size))


def boundary_t_junctions(vertices, faces, rel=1e-9) -> int:
    """Boundary edges with another mesh vertex strictly inside them (within ``rel`` of the
    edge's length off its line): a crack between a chain of short edges on one side and one
    long edge on the other, also where the edges lie in a face of the box."""
    from scipy.spatial import cKDTree

    v = np.asarray(vertices, float)
    edges = boundary_edges(faces)
    if not edges:
        return 0
    tree = cKDTree(v)
    count = 0
    for a, b in edges:
        p, q = v[a], v[b]
        d = q - p
        length = float(np.linalg.norm(d))
        for k in tree.query_ball_point(0.5 * (p + q), 0.5 * length * (1 + 1e-9)):
            if k in (a, b):
                continue
            t = float(np.dot(v[k] - p, d)) / length ** 2
            if rel < t < 1 - rel and np.linalg.norm(p + t * d - v[k]) <= rel * length:
                count += 1
                break
    return count


def distance_to_mesh(points, vertices, faces, return_triangle: bool = False, exact: bool = True):
    """Distance of each point to the nearest triangle (not to vertices).

    With ``return_triangle`` also the index of that triangle (-1 for none).
    With ``exact=False`` only an upper bound: the distance to the nearest
    of the 8 triangles whose centroids are nearest (enough to show that a
    point is near the mesh; measure the others again exactly).
    """
    from scipy.spatial import cKDTree

    p = np.asarray(points, float).reshape(-1, 3)
    v = np.asarray(vertices, float)
    f = np.asarray(faces, np.int64)
    out = np.full(len(p), np.inf)
    nearest = np.full(len(p), -1)
    if len(f) == 0:
        return (out, nearest) if return_triangle else out
    tri = v[f]
    tree = cKDTree(tri.mean(axis=1))
    k = min(8, len(f))
    _, idx = tree.query(p, k=k)
    idx = idx.reshape(len(p), k)
    owner = np.repeat(np.arange(len(p)), k)
    _closest(out, nearest, owner, idx.ravel(), p, tri)
    # The nearest triangle has its centroid within (distance found) +
    # (longest edge) of the point.
    longest = float(np.linalg.norm(tri - np.roll(tri, 1, axis=1), axis=2).max())
    if exact:
        cand = tree.query_ball_point(p, out + longest)
        owner = np.repeat(np.arange(len(p)), [len(c) for c in cand])
        which = np.fromiter((t for c in cand for t in c), np.int64, count=len(owner))
        _closest(out, nearest, owner, which, p, tri)
    return (out, nearest) if return_triangle else out


def _closest(out, nearest, owner, which, p, tri) -> None:
    """Lower ``out`` / set ``nearest`` by the (point, triangle) pairs given."""
    d = _point_triangles(p[owner], tri[which])
    np.minimum.at(out, owner, d)
    best = d == out[owner]
    nearest[owner[best]] = which[best]


def _point_triangles(q, tri) -> np.ndarray:
    """Distance of each point of ``q`` (T, 3) to its triangle of ``tri`` (T, 3, 3)."""
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    n = np.cross(b - a, c - a)
    nn = np.linalg.norm(n, axis=1)
    flat = nn <= 1e-300
    n = n / np.where(flat, 1.0, nn)[:, None]
    h = ((q - a) * n).sum(axis=1)
    foot = q - h[:, None] * n
    # Inside when the foot is on the inner side of all three edges.
    inside = ~flat
    for x, y in ((a, b), (b, c), (c, a)):
        inside &= (np.cross(y - x, foot - x) * n).sum(axis=1) >= 0

    def seg(x, y):
        d = y - x
        t = np.clip(((q - x) * d).sum(axis=1) / np.maximum((d * d).sum(axis=1), 1e-300), 0.0, 1.0)
        return np.linalg.norm(q - x - t[:, None] * d, axis=1)

    edge = np.minimum(np.minimum(seg(a, b), seg(b, c)), seg(c, a))
    return np.where(inside, np.abs(h), edge)
