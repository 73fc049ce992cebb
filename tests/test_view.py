"""The interactive view (singmesh.view, Mesh._repr_html_) and the conversions to trimesh and pyvista.

The data the page embeds is decoded here and checked against the surface
itself (F and grad F evaluated by numpy from the formula, known nodes and
lines), not against the mesher's own records; the pages are opened in
headless Chromium (WebGL on SwiftShader) where it is installed: drawn, both
sides' colours on the canvas, no console error.
"""

from __future__ import annotations

import base64
import json
import re
import sys
from types import SimpleNamespace

import numpy as np
import pytest

import singmesh
from singmesh import view
from singmesh.convert import MissingExtraError

from browser import Browser, colour_facts, find_chromium, region

CAYLEY = "4(x^2+y^2+z^2) + 16 x y z - 1"
#: Cayley's four nodes: coordinates +-1/2 with product -1/8.
CAYLEY_NODES = 0.5 * np.array([[-1, -1, -1], [-1, 1, 1], [1, -1, 1], [1, 1, -1]], float)


def _rotation(seed: int) -> np.ndarray:
    q, r = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    return q * np.sign(np.diag(r))


def _rotated(template: str, rot: np.ndarray) -> str:
    """``template`` in u, v, w with (u, v, w) = rot @ (x, y, z), coefficients as 15-digit decimals."""
    rows = ["(" + " + ".join(f"{c:.15f} {name}" for c, name in zip(row, "xyz")) + ")" for row in rot]
    return template.format(u=rows[0], v=rows[1], w=rows[2])


def _decode(b64: str, dtype: str, width: int) -> np.ndarray:
    return np.frombuffer(base64.b64decode(b64), dtype=np.dtype(dtype).newbyteorder("<")).reshape(-1, width)


@pytest.fixture(scope="module")
def cayley():
    return singmesh.mesh(CAYLEY, box=[[-1.5, 1.5]] * 3, coarse=16, fine=64)


@pytest.fixture(scope="module")
def rotated_crosscap():
    """The cross-cap u^2 v - w^2 turned by a float rotation: its double line and isolated line lie along rot[1]."""
    rot = _rotation(7)
    m = singmesh.mesh(_rotated("{u}^2 {v} - {w}^2", rot), box=[[-1, 1.1], [-1.05, 1], [-1, 1.02]],
                      coarse=16, fine=64)
    return m, rot


# ---------------------------------------------------------------- the embedded data
def test_view_data_holds_the_mesh_and_its_nodes(cayley):
    data = json.loads(view.view_json(cayley))
    v = _decode(data["vertices"], "f4", 3)
    assert data["index"] == "u16" and data["triangles"] == len(cayley.faces)
    f = _decode(data["faces"], "u2", 3)
    n = _decode(data["normals"], "i1", 3).astype(float) / 127.0
    # The mesh's vertices, then copies at the nodes' corners: the same triangles in space.
    nv = len(cayley.vertices)
    assert data["mesh_vertices"] == nv and len(v) > nv
    assert np.array_equal(v[:nv], cayley.vertices.astype(np.float32))
    assert np.array_equal(v[f], cayley.vertices[cayley.faces].astype(np.float32))
    # The normals are grad F (from the formula) to int8 precision; at the nodes grad F
    # vanishes and every corner there has a unit normal on its triangle's side.
    x, y, z = v.astype(float).T
    grad = np.stack([8 * x + 16 * y * z, 8 * y + 16 * x * z, 8 * z + 16 * x * y], axis=1)
    size = np.linalg.norm(grad, axis=1)
    ok = size > 1e-3
    assert np.abs(n[ok] - grad[ok] / size[ok, None]).max() < 0.01
    used = np.unique(f)
    assert np.abs(np.linalg.norm(n[used], axis=1) - 1).max() < 0.02
    tri = v[f].astype(float)
    side = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    at_node = ~ok[f]
    assert at_node.any() and ((n[f] * side[:, None, :]).sum(axis=2)[at_node] > 0).all()
    # The singular points: Cayley's four nodes, drawn red (A type).
    at = np.array([p["at"] for p in data["points"]])
    assert len(at) == 4
    assert np.abs(np.sort(at, axis=0) - np.sort(CAYLEY_NODES, axis=0)).max() < 1e-9
    assert {p["colour"] for p in data["points"]} == {view.POINT_COLOURS["A"]}
    assert data["curves"] is None and data["isolated"] is None
    assert data["box"] == [[-1.5, 1.5]] * 3


def test_view_data_curves_lie_on_the_rotated_lines(rotated_crosscap):
    m, rot = rotated_crosscap
    data = json.loads(view.view_json(m))
    line = rot[1]   # (u, v, w) = rot p: the v axis is p = t rot[1]
    for key, sign in (("curves", 1.0), ("isolated", -1.0)):
        p = _decode(data[key], "f4", 3).astype(float)
        assert len(p) >= 8 and len(p) % 2 == 0, key
        t = p @ line
        off = np.linalg.norm(p - t[:, None] * line, axis=1)
        assert off.max() < 1e-5, (key, off.max())       # float32 of points on the line
        assert (sign * t > -1e-5).all(), key              # double line for v > 0, isolated for v < 0
        assert np.ptp(t) > 0.5, key


def test_view_json_is_deterministic_and_script_safe(cayley):
    again = singmesh.mesh(CAYLEY, box=[[-1.5, 1.5]] * 3, coarse=16, fine=64)
    assert view.view_json(cayley) == view.view_json(again)
    assert view.mesh_html(cayley) == view.mesh_html(again)
    # Names that would close the <script> element are escaped inside the JSON.
    fake = SimpleNamespace(vertices=np.zeros((0, 3)), faces=np.zeros((0, 3), int), normals=np.zeros((0, 3)),
                           box=np.array([[0, 1]] * 3, float), singular_curves=[],
                           singularities=[SimpleNamespace(point=np.zeros(3), name="</script><!--")])
    text = view.view_json(fake)
    assert "<" not in text and ">" not in text
    assert json.loads(text)["points"][0]["type"] == "</script><!--"
    assert json.loads(text)["vertices"] is None


def test_view_data_takes_32_bit_indices_beyond_65535_vertices():
    rng = np.random.default_rng(3)
    vertices = rng.uniform(-1, 1, size=(70000, 3))
    faces = np.array([[0, 65535, 69999], [69998, 1, 65536]])
    fake = SimpleNamespace(vertices=vertices, faces=faces, normals=np.tile([0.0, 0.0, 1.0], (70000, 1)),
                           box=np.array([[-1, 1]] * 3, float), singular_curves=[], singularities=[])
    data = view.view_data(fake)
    assert data["index"] == "u32"
    assert np.array_equal(_decode(data["faces"], "u4", 3), faces)


def test_point_colours_by_type():
    assert view.point_colour("A1--") == view.POINT_COLOURS["A"]
    assert view.point_colour("D4+-") == view.POINT_COLOURS["D"]
    assert view.point_colour("E6++") == view.POINT_COLOURS["E"]
    for other in ("rank 3", None, "", "Ax", "non-simple"):
        assert view.point_colour(other) == view.OTHER_POINT_COLOUR


def test_repr_html_is_one_self_contained_frame(cayley):
    frame = cayley._repr_html_()
    assert frame.startswith("<iframe srcdoc=") and frame.count("<iframe") == 1
    page = re.search(r'srcdoc="([^"]*)"', frame).group(1)
    import html as _html

    page = _html.unescape(page)
    # three.js and the viewer are inlined; nothing is loaded from elsewhere.
    assert "Three.js Authors" in page and "singmeshView" in page
    assert not re.search(r"<(script|link|img)[^>]+(src|href)=", page)
    assert view.view_json(cayley) in page


def test_scripts_ship_with_the_package():
    for name in (view.THREE_FILE, view.THREE_LICENCE, view.VIEW_FILE):
        assert (view.VIEWER_DIR / name).is_file(), name
    head = (view.VIEWER_DIR / view.THREE_FILE).read_text(encoding="utf-8")[:400]
    assert "SPDX-License-Identifier: MIT" in head
    assert "MIT License" in (view.VIEWER_DIR / view.THREE_LICENCE).read_text(encoding="utf-8")
    from pathlib import Path

    try:
        import tomllib
    except ModuleNotFoundError:   # Python 3.10: the gallery extra's tomli
        import tomli as tomllib

    project = tomllib.loads((Path(view.__file__).parents[1] / "pyproject.toml").read_text())
    assert "singmesh.viewer" in project["tool"]["setuptools"]["packages"]
    data = project["tool"]["setuptools"]["package-data"]["singmesh.viewer"]
    assert "*.js" in data and "three.LICENSE" in data


def test_cli_writes_the_view_page(tmp_path, capsys):
    from singmesh.cli import main

    out = tmp_path / "umbrella.html"
    assert main(["mesh", "x^2 - y^2 z", "-o", str(out), "--box", "-1", "1", "-1", "1", "-1", "1",
                 "--coarse", "8", "--fine", "32"]) == 0
    printed = capsys.readouterr().out
    assert f"written              {out}" in printed and "curves written" not in printed
    page = out.read_text(encoding="utf-8")
    data = json.loads(page[page.index('<script type="application/json"'):].split(">", 1)[1].split("</script>")[0])
    # The umbrella's handle: the z axis, a double line for z > 0, an isolated line for z < 0.
    for key, sign in (("curves", 1.0), ("isolated", -1.0)):
        p = _decode(data[key], "f4", 3)
        assert np.abs(p[:, :2]).max() < 1e-6 and (sign * p[:, 2] > -1e-6).all() and np.ptp(p[:, 2]) > 0.5
    assert not list(tmp_path.glob("*.curves.vtk")) and "singmeshView" in page
    again = tmp_path / "again.html"
    assert main(["mesh", "x^2 - y^2 z", "-o", str(again), "--box", "-1", "1", "-1", "1", "-1", "1",
                 "--coarse", "8", "--fine", "32"]) == 0
    assert again.read_bytes() == out.read_bytes()


# ---------------------------------------------------------------- optional libraries
@pytest.mark.parametrize("module, method", [("trimesh", "to_trimesh"), ("pyvista", "to_pyvista")])
def test_missing_library_names_the_extra(cayley, monkeypatch, module, method):
    monkeypatch.setitem(sys.modules, module, None)   # import of the module fails
    with pytest.raises(ImportError) as info:
        getattr(cayley, method)()
    message = str(info.value)
    assert isinstance(info.value, MissingExtraError)
    assert "\n" not in message and f"pip install 'singmesh[{module}]'" in message and method in message


def test_to_trimesh_is_the_closed_sphere():
    trimesh = pytest.importorskip("trimesh")
    r = 0.8
    m = singmesh.mesh(f"x^2 + y^2 + z^2 - {r * r:.15f}", box=[[-1, 1.02], [-1.01, 1], [-1, 1.03]],
                      coarse=16, fine=64)
    t = m.to_trimesh()
    assert isinstance(t, trimesh.Trimesh)
    assert np.array_equal(t.vertices, m.vertices) and np.array_equal(t.faces, m.faces)
    assert t.is_watertight and t.euler_number == 2
    # Faces counter-clockwise around grad F (outwards): positive volume; both near the round sphere's.
    assert abs(t.area / (4 * np.pi * r * r) - 1) < 0.01
    assert abs(t.volume / (4 / 3 * np.pi * r ** 3) - 1) < 0.01
    assert np.allclose(t.vertex_normals, t.vertices / r, atol=1e-6)


def test_to_pyvista_has_triangles_and_the_isolated_line(rotated_crosscap):
    pytest.importorskip("pyvista")
    m, rot = rotated_crosscap
    poly = m.to_pyvista()
    points, lines = m.curve_lines()
    assert poly.n_points == len(points) and len(lines) > 0
    assert poly.n_cells == len(m.faces) + len(lines)
    assert np.array_equal(poly.faces.reshape(-1, 4), np.hstack([np.full((len(m.faces), 1), 3), m.faces]))
    assert np.array_equal(np.asarray(poly.points)[:len(m.vertices)], m.vertices)
    # The line cells: the isolated line, v < 0 along rot[1].
    cells = poly.lines.reshape(-1, 3)
    assert (cells[:, 0] == 2).all()
    p = np.asarray(poly.points)[cells[:, 1:].ravel()]
    t = p @ rot[1]
    assert np.linalg.norm(p - t[:, None] * rot[1], axis=1).max() < 1e-6 and (t < 1e-6).all()
    assert poly.point_data["Normals"].shape == (len(points), 3)
    assert "gaussian_curvature" in poly.point_data


# ---------------------------------------------------------------- in the browser
@pytest.fixture(scope="module")
def browser():
    binary = find_chromium()
    if binary is None:
        pytest.skip("chromium is not installed (apt-get install chromium): the pages are not opened")
    with Browser(binary, width=900, height=640) as b:
        yield b


STATE = ("(function (d) { var e = d && d.querySelector('.singmesh-view'); var s = e && e.getAttribute('data-state');"
         " return s && s !== 'starting' ? s : null; })(DOC)")
RECT = "JSON.parse(JSON.stringify(EL.getBoundingClientRect()))"


def _drawn(b: Browser, doc: str = "document", timeout: float = 30.0) -> str | None:
    """The view's state once it has one ("drawn", "failed"), or None when the page had an error first."""
    import time

    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        state = b.evaluate(STATE.replace("DOC", doc))
        if state or b.problems():
            return state
        time.sleep(0.1)
    return None


def _check_canvas(img: np.ndarray, what: str) -> None:
    facts = colour_facts(img)
    assert facts["distinct"] >= 100, (what, facts)       # shaded, not a flat fill
    assert facts["orange"] > 0.002 and facts["blue"] > 0.002, (what, facts)   # both sides: 1000+ pixels each


def test_page_draws_the_mesh_in_chromium(browser, cayley, tmp_path):
    page = tmp_path / "cayley.html"
    page.write_text(view.mesh_html(cayley), encoding="utf-8")
    browser.open(page.as_uri())
    assert _drawn(browser) == "drawn", browser.problems()
    assert browser.problems() == []
    img = region(browser.screenshot(), browser.evaluate(RECT.replace("EL", "document.querySelector('.singmesh-view')")))
    _check_canvas(img, "mesh_html")
    rgb = img.reshape(-1, 3)
    red = (rgb[:, 0] > 0.6) & (rgb[:, 1] < 0.3) & (rgb[:, 2] < 0.3)
    assert red.sum() > 20   # the nodes' spheres


def _shot(b: Browser) -> np.ndarray:
    import time

    time.sleep(0.4)   # the view redraws on the next animation frame
    return region(b.screenshot(), b.evaluate(RECT.replace("EL", "document.querySelector('.singmesh-view')")))


def _surface_share(img: np.ndarray) -> float:
    facts = colour_facts(img)
    return facts["orange"] + facts["blue"]


def test_view_turns_and_zooms_with_the_mouse(browser, cayley, tmp_path):
    page = tmp_path / "controls.html"
    page.write_text(view.mesh_html(cayley), encoding="utf-8")
    browser.open(page.as_uri())
    assert _drawn(browser) == "drawn", browser.problems()
    rect = browser.evaluate(RECT.replace("EL", "document.querySelector('.singmesh-view')"))
    cx, cy = rect["x"] + rect["width"] / 2, rect["y"] + rect["height"] / 2
    mouse = lambda kind, x, **kw: browser.send("Input.dispatchMouseEvent", {  # noqa: E731
        "type": kind, "x": x, "y": cy, "button": "left", **kw})
    start = _shot(browser)
    for _ in range(2):
        mouse("mouseWheel", cx, deltaX=0, deltaY=-300)
    zoomed = _shot(browser)
    assert _surface_share(zoomed) > 1.5 * _surface_share(start)   # closer: the surface fills more
    mouse("mousePressed", cx, buttons=1, clickCount=1)
    for dx in (30, 60, 90):
        mouse("mouseMoved", cx + dx, buttons=1)
    mouse("mouseReleased", cx + 90, buttons=0, clickCount=1)
    turned = _shot(browser)
    assert np.abs(turned - zoomed).max(axis=2).mean() > 0.05     # a drag turns it
    mouse("mousePressed", cx, buttons=1, clickCount=2)
    mouse("mouseReleased", cx, buttons=0, clickCount=2)
    again = _shot(browser)
    assert np.abs(again - start).max(axis=2).mean() < 0.01       # a double-click goes back to the start
    assert browser.problems() == []


def test_notebook_view_draws_in_chromium(browser, rotated_crosscap, tmp_path):
    m, _ = rotated_crosscap
    page = tmp_path / "notebook.html"
    page.write_text(f"<!DOCTYPE html><html><body><p>cell output</p>{m._repr_html_()}</body></html>", encoding="utf-8")
    browser.open(page.as_uri())
    assert _drawn(browser, "document.querySelector('iframe').contentDocument") == "drawn", browser.problems()
    assert browser.problems() == []
    img = region(browser.screenshot(), browser.evaluate(RECT.replace("EL", "document.querySelector('iframe')")))
    _check_canvas(img, "_repr_html_")
    rgb = img.reshape(-1, 3)
    violet = (rgb[:, 2] > 0.6) & (rgb[:, 0] > 0.3) & (rgb[:, 1] < 0.35)   # the isolated line's tubes
    assert violet.sum() > 10


def test_scripts_beside_the_page_and_broken_ones_are_caught(browser, cayley, tmp_path):
    html_text = view.mesh_html(cayley, inline_script=False, script_src="")
    good = tmp_path / "good"
    view.copy_scripts(good)
    (good / "page.html").write_text(html_text, encoding="utf-8")
    browser.open((good / "page.html").as_uri())
    assert _drawn(browser) == "drawn", browser.problems()
    assert browser.problems() == [] and browser.warnings() == []   # three's deprecation notice is dropped
    _check_canvas(_shot(browser), "script_src")
    # A syntax error in the viewer: caught as an exception, nothing drawn.
    broken = tmp_path / "broken"
    view.copy_scripts(broken)
    js = broken / view.VIEW_FILE
    text = js.read_text(encoding="utf-8")
    js.write_text(text.replace("function pieces(p, period) {", "function pieces(p, period) {{"), encoding="utf-8")
    (broken / "page.html").write_text(html_text, encoding="utf-8")
    browser.open((broken / "page.html").as_uri())
    assert _drawn(browser) is None
    assert any("SyntaxError" in p for p in browser.problems()), browser.problems()
    # three.js missing: the failed load is reported, and the view says so in words.
    missing = tmp_path / "missing"
    view.copy_scripts(missing)
    (missing / view.THREE_FILE).unlink()
    (missing / "page.html").write_text(html_text, encoding="utf-8")
    browser.open((missing / "page.html").as_uri())
    assert browser.wait_for(STATE.replace("DOC", "document"), timeout=30) == "failed"
    assert browser.problems(), "the missing three.min.js was not reported"
    assert "three.js" in browser.evaluate("document.querySelector('.singmesh-view').textContent")
