"""Interactive 3-D view of a mesh in a web page: rotate, zoom, both sides coloured, singular points and curves.

The page draws the mesh with three.js (r159, MIT licence, vendored in
``singmesh/viewer/`` with its licence) and a small viewer of ours
(``singmesh/viewer/singmesh-view.js``).  Everything works offline: the
mesh is embedded in the page as base64 arrays in a JSON block (a page
opened from disk may not ``fetch()`` files beside it), and the scripts are
either inlined (notebooks: :func:`notebook_html`, ``Mesh._repr_html_``) or
loaded with classic ``<script src>`` tags from the page's own folder (the
gallery: :func:`copy_scripts`; ES modules are not loaded from ``file://``).

Sizes: float32 positions (12 bytes per vertex), int8 unit normals (3),
16- or 32-bit triangle indices (6 or 12 bytes per triangle), times 4/3 for
base64: a mesh of 100k triangles and 50k vertices is about 1.8 MB (measured:
the tanglecube's 8898 triangles, 4441 vertices, 0.16 MB), and the inlined
scripts add about 0.7 MB.  Same mesh, same bytes.
"""

from __future__ import annotations

import base64
import html
import json
import shutil
from pathlib import Path
from typing import Any

import numpy as np

#: The folder of the vendored three.js and of our viewer script (package data).
VIEWER_DIR = Path(__file__).resolve().with_name("viewer")
#: three.js: the last release with a classic (UMD) build, which a page on file:// can load.
THREE_VERSION = "0.159.0"
THREE_FILE = "three.min.js"
THREE_LICENCE = "three.LICENSE"
VIEW_FILE = "singmesh-view.js"

#: Camera at the start: azimuth and elevation in degrees (those of the gallery's pictures).
AZIMUTH = -58.0
ELEVATION = 24.0

#: Colours as in the gallery's pictures: orange the side grad F points to, blue the other;
#: singular points by family of their type (A red, D purple, E green, others black); singular
#: curves red, isolated real lines violet (dashed).
COLOURS = {
    "front": "#f5b84d", "back": "#4d8fc7", "curve": "#b91c1c", "isolated": "#7c3aed",
    "box": "#9aa3ad", "background": "#fbfbfc",
}
POINT_COLOURS = {"A": "#d62728", "D": "#9467bd", "E": "#2ca02c"}
OTHER_POINT_COLOUR = "#222222"
#: Radius of a singular point's sphere, as a fraction of half the box's diagonal.
POINT_RADIUS = 0.028
#: Radius of the tubes drawn along singular curves, the same way (about two pixels in a 480-pixel view).
CURVE_RADIUS = 0.006

#: The message a page shows until the script has drawn (or instead, without JavaScript).
NO_SCRIPT = "The interactive view needs JavaScript and WebGL."


def point_colour(name: str | None) -> str:
    """The colour of a singular point's sphere from its type's name ("A1--", "D4+-", "rank 3" ...)."""
    if name and len(name) > 1 and name[0] in POINT_COLOURS and name[1].isdigit():
        return POINT_COLOURS[name[0]]
    return OTHER_POINT_COLOUR


def _b64(array: np.ndarray, dtype: str) -> str:
    """Base64 of the array's bytes as little-endian ``dtype`` (JavaScript's typed arrays read that)."""
    data = np.ascontiguousarray(array, dtype=np.dtype(dtype).newbyteorder("<"))
    return base64.b64encode(data.tobytes()).decode("ascii")


def display_geometry(vertices: np.ndarray, faces: np.ndarray,
                     normals: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vertices, faces and unit normals to shade: grad F, with the corners where it vanishes split off.

    At singular points and on singular curves grad F is zero, and the
    vertex is shared by sheets that meet at an angle: no one normal suits
    all its triangles (an average across the sheets shades them in dark
    streaks).  So each triangle corner at such a vertex gets a vertex of
    its own (same position), whose normal is the mean of the triangle's
    other corners' normals, or the triangle's own normal where it has no
    corner with one (both oriented like grad F, the faces being
    counter-clockwise around it).

    Returns
    -------
    vertices : (n + k, 3)
        The mesh's vertices, then the k split corners' copies.
    faces : (m, 3)
        The triangles, the split corners pointing at their copies.
    normals : (n + k, 3)
        Unit normals (zero only at a vertex no triangle has).
    """
    vertices = np.asarray(vertices, dtype=float).reshape(-1, 3)
    faces = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    out = np.array(normals, dtype=float).reshape(-1, 3)
    missing = np.linalg.norm(out, axis=1) == 0
    if not missing.any() or not len(faces):
        return vertices, faces, out
    corner_missing = missing[faces]                                   # (m, 3)
    face_i, corner = np.nonzero(corner_missing)
    # The triangle's other corners that have a normal, summed; else its own normal.
    have = ~corner_missing[face_i]                                    # (k, 3)
    mean = (out[faces[face_i]] * have[:, :, None]).sum(axis=1)
    tri = vertices[faces[face_i]]
    own = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    split = np.where(have.any(axis=1)[:, None], mean, own)
    length = np.linalg.norm(split, axis=1, keepdims=True)
    split = np.divide(split, length, out=np.zeros_like(split), where=length > 0)
    faces = faces.copy()
    copies = len(vertices) + np.arange(len(face_i))
    source = faces[face_i, corner]
    faces[face_i, corner] = copies
    return np.vstack([vertices, vertices[source]]), faces, np.vstack([out, split])


def _curve_segments(curves) -> tuple[np.ndarray, np.ndarray]:
    """The curves' edges as (2k, 3) point pairs: the curves of singular points and creases, and the isolated lines."""
    solid, isolated = [], []
    for c in curves:
        p = np.asarray(c.points, dtype=float).reshape(-1, 3)
        if len(p) < 2:
            continue
        ends = np.vstack([p, p[:1]]) if getattr(c, "closed", False) else p
        pairs = np.stack([ends[:-1], ends[1:]], axis=1).reshape(-1, 3)
        (isolated if "isolated" in str(c.type) else solid).append(pairs)
    stack = lambda parts: np.concatenate(parts) if parts else np.zeros((0, 3))  # noqa: E731
    return stack(solid), stack(isolated)


def view_data(mesh) -> dict[str, Any]:
    """What the viewer draws, as JSON-ready data (arrays as base64 strings).

    Parameters
    ----------
    mesh : Mesh
        Its vertices, faces, normals, box, singular points (``singularities``)
        and curves (``singular_curves``) are used.

    Returns
    -------
    dict
        ``vertices`` (float32; the mesh's, then copies at the corners
        :func:`display_geometry` splits off), ``normals`` (int8, unit normal
        times 127), ``faces`` (uint16 or uint32, as ``index`` says), ``curves`` and
        ``isolated`` (float32 point pairs), ``points`` (position, type,
        colour per singular point), ``box``, the start camera and colours.
        Absent arrays (no triangle, no curve) are None.
    """
    vertices, faces, normals = display_geometry(mesh.vertices, mesh.faces, mesh.normals)
    index = "u16" if len(vertices) <= 0xFFFF else "u32"
    solid, isolated = _curve_segments(mesh.singular_curves or [])
    points = []
    for s in mesh.singularities or []:
        name = getattr(s, "name", None) or getattr(getattr(s, "classification", None), "name", None)
        points.append({"at": [float(v) for v in np.asarray(s.point, dtype=float).reshape(3)],
                       "type": None if name is None else str(name), "colour": point_colour(name)})
    has_faces = len(faces) > 0
    return {
        "format": 1,
        "box": np.asarray(mesh.box, dtype=float).reshape(3, 2).tolist(),
        "vertices": _b64(vertices, "f4") if has_faces else None,
        "normals": _b64(np.round(normals * 127.0), "i1") if has_faces else None,
        "faces": _b64(faces, "u2" if index == "u16" else "u4") if has_faces else None,
        "index": index,
        "triangles": int(len(faces)),
        "mesh_vertices": int(len(mesh.vertices)),
        "curves": _b64(solid, "f4") if len(solid) else None,
        "isolated": _b64(isolated, "f4") if len(isolated) else None,
        "points": points,
        "point_radius": POINT_RADIUS,
        "curve_radius": CURVE_RADIUS,
        "azimuth": AZIMUTH,
        "elevation": ELEVATION,
        "colours": {**COLOURS},
    }


def view_json(mesh) -> str:
    """:func:`view_data` as compact JSON, safe inside a ``<script>`` block (same mesh, same text)."""
    text = json.dumps(view_data(mesh), sort_keys=True, separators=(",", ":"), allow_nan=False)
    return _script_safe(text)


def _script_safe(text: str) -> str:
    """JSON text that cannot end or comment out the ``<script>`` element holding it."""
    return text.replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026")


def script_text(name: str) -> str:
    """The text of a script in ``singmesh/viewer`` (``THREE_FILE`` or ``VIEW_FILE``)."""
    text = (VIEWER_DIR / name).read_text(encoding="utf-8")
    if "</script" in text.lower() or "<!--" in text:
        # Inlined, such a sequence would end the <script> element early.
        raise ValueError(f"{name} cannot be inlined in a <script> element")
    return text


def copy_scripts(folder: str | Path) -> list[Path]:
    """Copy three.js (with its licence) and the viewer script into ``folder``.

    For pages that load them by ``<script src>`` from their own folder.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    out = []
    for name in (THREE_FILE, THREE_LICENCE, VIEW_FILE):
        target = folder / name
        shutil.copyfile(VIEWER_DIR / name, target)
        out.append(target)
    return out


#: Style of the view's box; the canvas fills it.
VIEW_CSS = """\
.singmesh-view { position: relative; width: 100%; height: var(--singmesh-view-height, 480px);
  background: #fbfbfc; border: 1px solid #e1e5ea; border-radius: 12px; overflow: hidden; }
.singmesh-view canvas { display: block; width: 100%; height: 100%; cursor: grab; }
.singmesh-view canvas:active { cursor: grabbing; }
.singmesh-view .singmesh-view-message { margin: 0; padding: 16px; color: #66717d;
  font: 14px/1.4 system-ui, sans-serif; }
.singmesh-view-help { margin: 4px 2px 0; color: #66717d; font: 12.5px/1.4 system-ui, sans-serif; }
"""

#: The line under the view: what the colours are and how to move it.
HELP = ("drag: turn \u00b7 wheel or pinch: zoom \u00b7 shift-drag or right-drag: pan \u00b7 double-click: "
        "start view \u00b7 orange: the side grad F points to, blue: the other side \u00b7 spheres: singular "
        "points (red A, purple D, green E, black other) \u00b7 red lines: singular curves, dashed violet: "
        "isolated lines")


def view_fragment(data_json: str, *, inline_script: bool = True, script_src: str | None = None,
                  element_id: str = "singmesh-view", height: int = 480, scripts: bool = True) -> str:
    """The HTML of one view (box, data, scripts) to put into a page's ``<body>``.

    Parameters
    ----------
    data_json : str
        :func:`view_json` of the mesh.
    inline_script : bool
        Put three.js and the viewer into the page (a notebook, a single
        file).  Otherwise they are loaded from ``script_src``.
    script_src : str, optional
        Folder (relative URL, "" for the page's own) holding the files of
        :func:`copy_scripts`, when ``inline_script`` is False.
    element_id : str
        The view's element id (unique in the page).
    height : int
        Height of the view in CSS pixels (its width is the page's).
    scripts : bool
        Include the script tags (False for a second view on a page that
        has them already).
    """
    if not inline_script and script_src is None:
        raise ValueError("view_fragment: give script_src when the scripts are not inlined")
    data_id = f"{element_id}-data"
    parts = [
        f'<div class="singmesh-view" id="{html.escape(element_id)}" data-view="{html.escape(data_id)}" '
        f'style="--singmesh-view-height: {int(height)}px"><noscript><p class="singmesh-view-message">'
        f"{NO_SCRIPT}</p></noscript></div>",
        f'<p class="singmesh-view-help">{html.escape(HELP)}</p>',
        f'<script type="application/json" id="{html.escape(data_id)}">{data_json}</script>',
    ]
    if scripts:
        if inline_script:
            parts.append(f"<script>\n{_quiet_three(script_text(THREE_FILE))}\n</script>")
            parts.append(f"<script>\n{script_text(VIEW_FILE)}\n</script>")
        else:
            prefix = html.escape(script_src.rstrip("/") + "/" if script_src else "")
            parts.append(f"<script>{_MUTE}</script>")
            parts.append(f'<script src="{prefix}{THREE_FILE}"></script>')
            parts.append(f"<script>{_UNMUTE}</script>")
            parts.append(f'<script src="{prefix}{VIEW_FILE}"></script>')
    parts.append("<script>if (window.singmeshViewStartAll) singmeshViewStartAll();</script>")
    return "\n".join(parts)


#: three.js r159's classic build warns on load that it is deprecated (the classic build is
#: what a page on file:// can load; the warning is for the library's own users): that one
#: message is dropped, every other warning goes through.
_MUTE = ("window.__singmeshWarn = console.warn; console.warn = function (m) { "
         "if (typeof m === 'string' && m.indexOf('Scripts \"build/three') === 0) return; "
         "return window.__singmeshWarn.apply(console, arguments); };")
_UNMUTE = "console.warn = window.__singmeshWarn;"


def _quiet_three(text: str) -> str:
    return f"{_MUTE}\n{text}\n{_UNMUTE}"


def mesh_html(mesh, *, inline_script: bool = True, script_src: str | None = None, height: int = 480,
              title: str | None = None) -> str:
    """A whole HTML page with the interactive view of ``mesh``.

    Parameters
    ----------
    mesh : Mesh
    inline_script : bool
        Inline three.js and the viewer (a single self-contained file, about
        0.7 MB plus the mesh); otherwise load them from ``script_src``.
    script_src : str, optional
        Folder of the scripts (:func:`copy_scripts`) relative to the page.
    height : int
        Height of the view in CSS pixels.
    title : str, optional
        The page's title (default: the surface's equation).

    Returns
    -------
    str
        The page; opened from disk it needs no network.
    """
    title = title if title is not None else f"singmesh: {mesh.surface}"
    body = view_fragment(view_json(mesh), inline_script=inline_script, script_src=script_src, height=height)
    return f"""<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>{html.escape(title)}</title>
<style>
body {{ margin: 8px; background: #ffffff; }}
{VIEW_CSS}</style>
</head>
<body>
{body}
</body>
</html>
"""


def notebook_html(mesh, height: int = 480) -> str:
    """The view for a notebook cell: the whole page of :func:`mesh_html` in an ``<iframe srcdoc>``.

    The frame keeps three.js and the page's style apart from the
    notebook's and from other cells' views.
    """
    page = mesh_html(mesh, inline_script=True, height=height)
    return (f'<iframe srcdoc="{html.escape(page, quote=True)}" title="singmesh view" '
            f'style="width: 100%; height: {int(height) + 60}px; border: 0;"></iframe>')
