"""Facts about singular points computed without singmesh.

``branches_on_sphere`` counts the curves in which F = 0 meets a small
sphere around a point: k disjoint closed curves cut the sphere into k + 1
regions of constant sign, counted by connected-component labelling of the
sign of F on a latitude-longitude grid (longitude periodic, each pole row
one region).
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage


def branches_on_sphere(f, centre, radius, n_lat=720, n_lon=1440, box=None) -> int:
    """Number of curves of F = 0 on the sphere |x - centre| = radius.

    ``f`` is a vectorised function of (..., 3) points.  A definite F (no
    curve) gives 0.  With ``box`` (three (lo, hi) pairs) only the part of
    the sphere inside the box counts, the points outside left out of both
    signs: for a centre on a face, edge or corner of the box that part is a
    disc, and k arcs cut a disc into k + 1 regions as k curves cut the
    sphere.
    """
    theta = (np.arange(n_lat) + 0.5) * np.pi / n_lat
    phi = np.arange(n_lon) * 2 * np.pi / n_lon
    t, p = np.meshgrid(theta, phi, indexing="ij")
    pts = np.asarray(centre, float) + radius * np.stack(
        [np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1)
    sign = f(pts) > 0
    inside = np.ones(sign.shape, bool)
    if box is not None:
        lim = np.asarray(box, float)
        inside = ((pts >= lim[:, 0]) & (pts <= lim[:, 1])).all(axis=-1)
    regions = 0
    for s in (sign & inside, ~sign & inside):
        # Pad with the wrapped-around first column so labels join across 2 pi,
        # and with pole rows that join each pole's cap.
        grid = np.concatenate([s, s[:, :1]], axis=1)
        lab, n = ndimage.label(grid)
        parent = list(range(n + 1))

        def find(a):
            while parent[a] != a:
                parent[a] = parent[parent[a]]
                a = parent[a]
            return a

        for a, b in zip(lab[:, 0], lab[:, -1]):
            if a and b:
                parent[find(a)] = find(b)
        for row in (lab[0], lab[-1]):
            ids = [x for x in np.unique(row) if x]
            for x in ids[1:]:
                parent[find(x)] = find(ids[0])
        regions += len({find(x) for x in range(1, n + 1)})
    return regions - 1
