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


def flip_slivers(vertices: np.ndarray, faces: np.ndarray, fixed: np.ndarray | None = None) -> np.ndarray:
    """Flip the longest edge of near-flat triangles where that helps.

    Parameters
    ----------
    vertices : (V, 3)
    faces : (T, 3) int64, consistently oriented
    fixed : (V,) bool, optional
        Vertices on a singular curve: an edge joining two of them is never
        flipped away, nor made.

    Returns
    -------
    (T, 3) int64, the same number of triangles
    """
    faces = faces.copy()
    p = vertices[faces]
    area2 = np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    longest = np.max([np.sum((p[:, i] - p[:, (i + 1) % 3]) ** 2, axis=1) for i in range(3)], axis=0)
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
