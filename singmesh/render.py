"""Headless pictures of meshes (matplotlib, Agg backend): the gallery's and the sweep's.

The picture is drawn with our own orthographic projection and one 2-D
``PolyCollection`` sorted back to front (painter's algorithm) rather than
with ``Poly3DCollection``: it is the same algorithm, but skipping mplot3d's
per-draw projection and sorting makes ~20k triangles render in about a
second, and it lets every picture use exactly the same camera and framing.
"""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

from .extras import require

# Without matplotlib, importing this module says which extra to install.
require("drawing pictures", ["matplotlib"])

import matplotlib  # noqa: E402

matplotlib.use("Agg")  # headless: no display on the build machines

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import LineCollection, PolyCollection  # noqa: E402

#: Camera: azimuth and elevation in degrees, looking at the box centre.
#: Off the axes and diagonals so that symmetric surfaces do not line up
#: their features and hide one another.
AZIMUTH = -58.0
ELEVATION = 24.0

#: Side of the surface that grad F points to, and the other side.  Two
#: colours make the orientation (and one-sided pieces) visible.
FRONT_COLOUR = np.array([0.96, 0.72, 0.30])
BACK_COLOUR = np.array([0.30, 0.56, 0.78])
BACKGROUND = "#fbfbfc"

#: Colour map of a surface coloured by a value per vertex (curvature):
#: diverging, white at zero.  Green where the value is undefined.
CURVATURE_MAP = "coolwarm"
UNDEFINED_COLOUR = np.array([0.45, 0.75, 0.35])

#: Colours of singular-point markers by family of the classification name.
POINT_COLOURS = {"A": "#d62728", "D": "#9467bd", "E": "#2ca02c"}
OTHER_POINT_COLOUR = "#222222"


def camera_basis(azimuth: float = AZIMUTH, elevation: float = ELEVATION) -> np.ndarray:
    """Rows: screen right, screen up, towards the viewer (unit vectors)."""
    az, el = np.radians(azimuth), np.radians(elevation)
    towards = np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
    right = np.cross([0.0, 0.0, 1.0], towards)
    right /= np.linalg.norm(right)
    up = np.cross(towards, right)
    return np.array([right, up, towards])


def face_normals(vertices: np.ndarray, faces: np.ndarray, normals: np.ndarray | None) -> np.ndarray:
    """Unit normal per face: mean of the vertex normals (grad F), else geometric.

    The vertex normals are exact gradients, so their mean shades more
    smoothly than the flat geometric normal; at singular vertices grad F
    is zero and the mean can vanish, and there the geometric normal
    (same orientation, since faces are ccw around grad F) is used.
    """
    tri = vertices[faces]
    geo = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    geo_len = np.linalg.norm(geo, axis=1, keepdims=True)
    geo = np.divide(geo, geo_len, out=np.zeros_like(geo), where=geo_len > 0)
    if normals is None or len(normals) != len(vertices):
        return geo
    avg = normals[faces].sum(axis=1)
    avg_len = np.linalg.norm(avg, axis=1, keepdims=True)
    good = avg_len[:, 0] > 1.5  # at least two of three vertex normals agree
    out = geo.copy()
    out[good] = avg[good] / avg_len[good]
    return out


def shade(normals: np.ndarray, basis: np.ndarray, base: np.ndarray | None = None) -> np.ndarray:
    """RGB per face: two-sided Lambert from a key and a fill light, plus a highlight.

    Lights are fixed relative to the camera so that every picture is lit
    the same way.  ``abs`` of the dot products makes both sides lit.
    ``base`` (m, 3): the faces' own colours (e.g. by curvature) instead
    of the front and back colours.
    """
    right, up, towards = basis
    key = -0.45 * right + 0.65 * up + 0.62 * towards
    key /= np.linalg.norm(key)
    fill = 0.55 * right - 0.25 * up + 0.80 * towards
    fill /= np.linalg.norm(fill)
    n_key = np.abs(normals @ key)
    n_fill = np.abs(normals @ fill)
    half = key + towards
    half /= np.linalg.norm(half)
    spec = np.abs(normals @ half) ** 40
    facing = normals @ towards >= 0
    if base is None:
        base = np.where(facing[:, None], FRONT_COLOUR, BACK_COLOUR)
    light = 0.20 + 0.62 * n_key + 0.22 * n_fill
    rgb = base * light[:, None] + 0.30 * spec[:, None]
    return np.clip(rgb, 0.0, 1.0)


def value_colours(values: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, float]:
    """RGB per face from a value per vertex, and the value at the ends of the colour scale.

    A diverging map centred on zero (blue negative, white zero, red
    positive), symmetric, saturating at the 95th percentile of |value|:
    values near singular points grow without bound and would wash the
    rest out.  Faces with an undefined (NaN) vertex value are green.
    """
    v = np.asarray(values, float)[faces]
    defined = np.isfinite(v).all(axis=1)
    face = np.where(defined, np.where(np.isfinite(v), v, 0.0).mean(axis=1), 0.0)
    scale = float(np.percentile(np.abs(face[defined]), 95)) if defined.any() else 0.0
    scale = scale if scale > 0 else 1.0
    rgb = plt.get_cmap(CURVATURE_MAP)(0.5 + 0.5 * np.clip(face / scale, -1.0, 1.0))[:, :3]
    rgb[~defined] = UNDEFINED_COLOUR
    return rgb, scale


def _box_edges(box: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The 12 edges of the box as (12, 2, 3) and its 8 corners."""
    corners = np.array([[box[0, i], box[1, j], box[2, k]]
                        for i in (0, 1) for j in (0, 1) for k in (0, 1)], dtype=float)
    edges = [(a, b) for a in range(8) for b in range(a + 1, 8) if bin(a ^ b).count("1") == 1]
    return corners[np.array(edges)], corners


def point_colour(name: str | None) -> str:
    """Marker colour for a singular point from the first letter of its name."""
    if name and name[0] in POINT_COLOURS and len(name) > 1 and name[1].isdigit():
        return POINT_COLOURS[name[0]]
    return OTHER_POINT_COLOUR


def render_png(path: str | Path, vertices: np.ndarray, faces: np.ndarray, box,
               normals: np.ndarray | None = None, points: np.ndarray | None = None,
               point_names: Sequence[str] | None = None, size: int = 640,
               note: str | None = None, curves: Sequence[np.ndarray] | None = None,
               curve_names: Sequence[str] | None = None, values: np.ndarray | None = None,
               value_label: str | None = None) -> Path:
    """Render a shaded picture of a triangle mesh to a PNG file.

    Parameters
    ----------
    path : str or Path
        The PNG written.
    vertices : (n, 3) array
    faces : (m, 3) int array
        Triangles, counter-clockwise around the normal side.
    box : (3, 2) array-like
        The meshed box: drawn faintly and used for the framing, so that
        every picture of the same box has the same scale.
    normals : (n, 3) array, optional
        Vertex normals for smoother shading.
    points : (k, 3) array, optional
        Singular points, drawn as coloured dots on top.
    point_names : sequence of str, optional
        Their classification names (they choose the dot colours).
    size : int
        Width and height in pixels.
    note : str, optional
        A line of text written in the picture (e.g. "empty mesh").
    curves : sequence of (k, 3) arrays, optional
        Curves of singular points, drawn as polylines on top (an isolated
        real line is then visible at all).
    curve_names : sequence of str, optional
        Their transversal types (isolated lines are drawn dashed).
    values : (n,) array, optional
        A value per vertex (e.g. the Gaussian curvature) colouring the
        faces (:func:`value_colours`) instead of the two side colours.
    value_label : str, optional
        What ``values`` are, written in a corner with the scale's ends.

    Returns
    -------
    Path
        ``path``.
    """
    path = Path(path)
    box = np.asarray(box, dtype=float).reshape(3, 2)
    vertices = np.asarray(vertices, dtype=float).reshape(-1, 3)
    faces = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    basis = camera_basis()
    centre = box.mean(axis=1)

    dpi = 100
    fig = plt.figure(figsize=(size / dpi, size / dpi), dpi=dpi, facecolor=BACKGROUND)
    ax = fig.add_axes((0, 0, 1, 1))
    ax.set_axis_off()
    ax.set_facecolor(BACKGROUND)

    edges, corners = _box_edges(box)
    corner_screen = (corners - centre) @ basis[:2].T
    lo, hi = corner_screen.min(axis=0), corner_screen.max(axis=0)
    half = 0.5 * (hi - lo).max() * 1.06
    mid = 0.5 * (lo + hi)
    ax.set_xlim(mid[0] - half, mid[0] + half)
    ax.set_ylim(mid[1] - half, mid[1] + half)
    ax.set_aspect("equal")

    # Box edges: the three at the far corner go under the surface, the
    # others over it, all faint so that they frame without competing.
    far = np.argmin((corners - centre) @ basis[2])
    is_back = np.array([np.any(np.all(e == corners[far], axis=1)) for e in edges])
    edges_screen = (edges - centre) @ basis[:2].T
    ax.add_collection(LineCollection(edges_screen[is_back], colors="#9aa3ad", linewidths=0.8,
                                     linestyles=(0, (3, 3)), alpha=0.6, zorder=1))
    ax.add_collection(LineCollection(edges_screen[~is_back], colors="#9aa3ad", linewidths=0.8,
                                     alpha=0.55, zorder=3))

    if len(faces):
        tri = vertices[faces] - centre
        screen = tri @ basis[:2].T
        depth = (tri @ basis[2]).mean(axis=1)
        order = np.argsort(depth, kind="stable")  # far first: painter's algorithm
        base = None
        if values is not None:
            base, scale = value_colours(values, faces)
            ax.text(0.03, 0.97, f"{value_label or 'value'}: blue -{scale:.3g}, white 0, red +{scale:.3g}",
                    transform=ax.transAxes, ha="left", va="top", fontsize=max(7, size // 60),
                    color="#374151", zorder=6)
        colours = shade(face_normals(vertices, faces, normals), basis, base)[order]
        # Edges in the face colour close the hairline cracks that
        # antialiasing leaves between neighbouring triangles.
        ax.add_collection(PolyCollection(screen[order], facecolors=colours, edgecolors=colours,
                                         linewidths=0.35, antialiaseds=True, zorder=2))

    for k, c in enumerate(curves or []):
        xy = (np.asarray(c, dtype=float).reshape(-1, 3) - centre) @ basis[:2].T
        name = (curve_names or [""] * len(curves))[k] or ""
        alone = "isolated" in name
        ax.plot(xy[:, 0], xy[:, 1], color="#b91c1c" if not alone else "#7c3aed",
                linewidth=max(1.2, size / 400.0), linestyle=(0, (4, 2)) if alone else "-",
                solid_capstyle="round", zorder=4)

    if points is not None and len(points):
        pts = (np.asarray(points, dtype=float).reshape(-1, 3) - centre) @ basis[:2].T
        names = list(point_names) if point_names is not None else [None] * len(pts)
        colours = [point_colour(n) for n in names]
        dot = max(24.0, (size / 640.0) ** 2 * 85.0)
        ax.scatter(pts[:, 0], pts[:, 1], s=dot, c=colours, edgecolors="white",
                   linewidths=1.5, zorder=5)

    if note:
        ax.text(0.5, 0.04, note, transform=ax.transAxes, ha="center", va="bottom",
                fontsize=max(8, size // 45), color="#6b7280", zorder=6)

    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi, facecolor=BACKGROUND)
    plt.close(fig)
    return path
