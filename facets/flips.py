"""Edge flips for near-flat triangles.

A facet whose three crossings are nearly collinear (the surface cutting a
box close along one face) gives a triangle of almost no area.  Flipping its
longest edge with the triangle across it removes the sliver without moving
any vertex.  Only near-flat triangles are touched, so the rest of the mesh
keeps the triangulation chosen per facet.
"""

from __future__ import annotations

import numpy as np

from singmesh import tolerances as tol


def _min_angle(p: np.ndarray) -> float:
    ang = []
    for i in range(3):
        a = p[(i + 1) % 3] - p[i]
        b = p[(i + 2) % 3] - p[i]
        c = np.dot(a, b) / max(np.linalg.norm(a) * np.linalg.norm(b), 1e-300)
        ang.append(np.arccos(np.clip(c, -1, 1)))
    return min(ang)


def area_and_longest(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Doubled areas and squared longest sides of triangles.

    Parameters
    ----------
    vertices : (V, 3)
    faces : (T, 3) int64

    Returns
    -------
    area2 : (T,) ``|(p1 - p0) x (p2 - p0)|``
    longest : (T,) the largest ``|p_(i+1) - p_i|^2``

    Written per coordinate, with the sums of ``np.linalg.norm`` and
    ``np.sum`` over an axis of 3 in their order (the same bits, without a
    reduction call per triangle row).
    """
    q = [[np.ascontiguousarray(vertices[:, a])[faces[:, i]] for a in range(3)] for i in range(3)]
    u = [q[1][a] - q[0][a] for a in range(3)]
    w = [q[2][a] - q[0][a] for a in range(3)]
    c = (u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0])
    area2 = np.sqrt((c[0] * c[0] + c[1] * c[1]) + c[2] * c[2])
    longest = None
    for i in range(3):
        d = [q[i][a] - q[(i + 1) % 3][a] for a in range(3)]
        side = (d[0] * d[0] + d[1] * d[1]) + d[2] * d[2]
        longest = side if longest is None else np.maximum(longest, side)
    return area2, longest


def flip_slivers(vertices: np.ndarray, faces: np.ndarray, fixed: np.ndarray | None = None,
                 measures: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """Flip the longest edge of near-flat triangles where that helps.

    Parameters
    ----------
    vertices : (V, 3)
    faces : (T, 3) int64, consistently oriented
    fixed : (V,) bool, optional
        Vertices on a singular curve: an edge joining two of them is never
        flipped away, nor made.
    measures : (area2, longest), optional
        :func:`area_and_longest` of ``faces`` where known already.

    Returns
    -------
    (T, 3) int64, the same number of triangles
    """
    faces = faces.copy()
    area2, longest = area_and_longest(vertices, faces) if measures is None else measures
    slivers = np.nonzero(area2 <= tol.SLIVER_AREA * longest)[0]
    if len(slivers) == 0:
        return faces
    # Directed edge -> triangle, only for the triangles touching a sliver's
    # vertices (the triangle across an edge and any edge a flip could meet
    # are among them): no Python loop over the whole mesh.
    near_verts = np.unique(faces[slivers])
    near = np.unique(np.nonzero(np.isin(faces, near_verts).any(axis=1))[0])
    edge_of = {}
    for t in near.tolist():
        a, b, c = faces[t].tolist()
        edge_of[(a, b)] = t
        edge_of[(b, c)] = t
        edge_of[(c, a)] = t
    for t in slivers.tolist():
        tri = faces[t].tolist()
        q = vertices[tri]
        k = int(np.argmax([np.sum((q[i] - q[(i + 1) % 3]) ** 2) for i in range(3)]))
        a, b, c = tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]
        u = edge_of.get((b, a))
        if u is None:
            continue
        d = [x for x in faces[u].tolist() if x not in (a, b)]
        if len(d) != 1 or (c, d[0]) in edge_of or (d[0], c) in edge_of:
            continue
        d = d[0]
        if fixed is not None and ((fixed[a] and fixed[b]) or (fixed[c] and fixed[d])):
            continue
        new1, new2 = [c, a, d], [d, b, c]
        old_n = np.cross(q[1] - q[0], q[2] - q[0]) + np.cross(*(vertices[faces[u]][1:] - vertices[faces[u]][0]))
        ok = True
        for tri_new in (new1, new2):
            r = vertices[tri_new]
            if np.dot(np.cross(r[1] - r[0], r[2] - r[0]), old_n) <= 0:
                ok = False
        before = min(_min_angle(q), _min_angle(vertices[faces[u]]))
        if not ok or min(_min_angle(vertices[new1]), _min_angle(vertices[new2])) <= before:
            continue
        for e in ((a, b), (b, c), (c, a)):
            edge_of.pop(e, None)
        for e in ((b, a), (a, d), (d, b)):
            edge_of.pop(e, None)
        faces[t], faces[u] = new1, new2
        for tt, (x, y, z) in ((t, new1), (u, new2)):
            edge_of[(x, y)] = tt
            edge_of[(y, z)] = tt
            edge_of[(z, x)] = tt
    return faces
