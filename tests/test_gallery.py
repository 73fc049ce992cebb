"""Tests of the gallery builder (gallery/generate.py) and its catalogue.

One small gallery is built per test module (a few real entries plus a
deliberately broken one appended to a copy of the catalogue, at a low
resolution, in two worker processes) and then checked: files, pictures,
links, the error shown for the broken entry, and the page in headless
Chromium when it is available.
"""

from __future__ import annotations

import html
import importlib.util
import json
import os
import shutil
import subprocess
import sys
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlparse

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
GALLERY = ROOT / "gallery"
CATALOGUE = GALLERY / "catalogue.toml"

#: Entries built by the fixture, as --only substrings, and the names they select.
ONLY = ["sphere", "cone", "cross-cap", "labelled", "broken"]
UNSUPPORTED_NAME = "Labelled unsupported"
UNSUPPORTED = f'''

[[entry]]
name = "{UNSUPPORTED_NAME}"
group = "curves"
equation = "x^2 - y^2"
box = [[-1.0, 1.0], [-1.0, 1.0], [-1.0, 1.0]]
description = "Marked unsupported for the test: the page must label it so, with the reason."
expected = []
status = "unsupported"
reason = "labelled unsupported on purpose"
'''
BROKEN_NAME = "Broken on purpose"
BROKEN = f'''

[[entry]]
name = "{BROKEN_NAME}"
group = "smooth"
equation = "x^2 + gamma(y) - 1"
box = [[-1.0, 1.0], [-1.0, 1.0], [-1.0, 1.0]]
description = "An unknown function: meshing must fail, and the page must say so."
expected = []
status = "supported"
'''
SIZE = 200


def _load_generate():
    """gallery/generate.py as a module (it puts gallery/ on sys.path itself)."""
    spec = importlib.util.spec_from_file_location("gallery_generate_under_test", GALLERY / "generate.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def generate():
    return _load_generate()


@pytest.fixture(scope="module")
def lib(generate):
    import gallery_lib

    return gallery_lib


@pytest.fixture(scope="module")
def built(generate, tmp_path_factory):
    """Build the small gallery once; returns (out dir, report dict, exit status)."""
    tmp = tmp_path_factory.mktemp("gallery")
    catalogue = tmp / "catalogue.toml"
    catalogue.write_text(CATALOGUE.read_text(encoding="utf-8") + UNSUPPORTED + BROKEN, encoding="utf-8")
    out = tmp / "out"
    status = generate.main(["--catalogue", str(catalogue), "--out", str(out), "--only", *ONLY,
                            "--jobs", "2", "--size", str(SIZE), "--coarse", "16", "--fine", "64",
                            "--quiet"])
    report = json.loads((out / "report.json").read_text(encoding="utf-8"))
    return out, report, status


class _Links(HTMLParser):
    """Collects href/src attributes and the text of a page."""

    def __init__(self):
        super().__init__()
        self.links: list[str] = []
        self.text: list[str] = []

    def handle_starttag(self, tag, attrs):
        for k, v in attrs:
            if k in ("href", "src") and v:
                self.links.append(v)

    def handle_data(self, data):
        self.text.append(data)


def _local_targets(page: Path) -> tuple[list[Path], str]:
    parser = _Links()
    parser.feed(page.read_text(encoding="utf-8"))
    targets = []
    for link in parser.links:
        u = urlparse(link)
        if u.scheme or link.startswith("#"):
            continue
        targets.append(page.parent / unquote(u.path))
    return targets, "".join(parser.text)


def _card(page: str, slug: str) -> str:
    """The <article> of one entry in index.html."""
    start = page.rindex("<article", 0, page.index(f'id="{slug}"'))
    return page[start:page.index("</article>", start)]


def _coloured(img: np.ndarray) -> float:
    """Fraction of saturated pixels: the shaded surface, not the white page or grey box lines."""
    rgb = img[..., :3].astype(float)
    if rgb.max() > 1.0:
        rgb = rgb / 255.0
    return float((rgb.max(axis=-1) - rgb.min(axis=-1) > 0.2).mean())


def _non_blank(img: np.ndarray) -> float:
    """Fraction of pixels that differ clearly from the most common (background) colour."""
    rgb = img[..., :3].astype(float)
    if rgb.max() > 1.0:
        rgb = rgb / 255.0
    flat = rgb.reshape(-1, 3)
    q = np.round(flat * 63).astype(np.int64)  # 64 levels per channel, packed into one code
    codes = (q[:, 0] << 12) | (q[:, 1] << 6) | q[:, 2]
    top = np.argmax(np.bincount(codes))
    background = np.array([top >> 12, (top >> 6) & 63, top & 63]) / 63.0
    return float((np.abs(flat - background).max(axis=1) > 0.1).mean())


# ---------------------------------------------------------------- catalogue
def test_catalogue_parses_and_is_complete(lib):
    import singmesh

    groups, entries = lib.load_catalogue(CATALOGUE)
    names = {e.name for e in entries}
    ade = [f"A{n}{s}" for n in range(1, 6) for s in ("++", "+-", "-+", "--")]
    ade += [f"D{n}{s}" for n in (4, 5, 6) for s in ("++", "+-", "-+", "--")]
    ade += [f"E{n}{s}" for n in (6, 7, 8) for s in ("++", "+-", "-+", "--")]
    assert not set(ade) - names, f"missing normal forms: {sorted(set(ade) - names)}"
    lowered = " ".join(n.lower() for n in names)
    for word in ("cone", "cayley", "kummer", "togliatti", "barth", "chubs", "tanglecube", "torus",
                 "sphere", "x^6", "decocube", "cross-cap", "whitney", "roman"):
        assert word in lowered, word
    assert len({e.slug for e in entries}) == len(entries)
    group_ids = [g.id for g in groups]
    assert len(set(group_ids)) == len(group_ids)
    for e in entries:
        assert e.group in group_ids
        assert e.status in ("supported", "unsupported")
        assert e.description
        if e.status == "unsupported":
            assert e.reason
        if e.real_forms is not None:
            assert len(e.real_forms) == len(e.expected)
        if e.branches is not None:
            assert len(e.branches) == len(e.expected)
        # every expected type agrees with the entry name for the normal forms
        if e.name in ade:
            assert list(e.expected) == [e.name[:2]]
        if e.supported:
            surface = singmesh.Surface.parse(e.equation, **e.params)
            assert surface.degree >= 1
    by_name = {e.name: e for e in entries}
    assert by_name["Cayley cubic"].expected == ("A1",) * 4
    assert len(by_name["Kummer quartic"].expected) == 16
    assert len(by_name["Togliatti quintic"].expected) == 31
    assert len(by_name["Barth sextic"].expected) == 50
    assert by_name["Cross-cap"].supported and not by_name["Crixxi"].supported


def test_catalogue_errors_are_reported(lib, generate, tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text('[[entry]]\nname = "no equation"\nbox = [[0, 1], [0, 1], [0, 1]]\nexpected = []\n')
    with pytest.raises(lib.CatalogueError, match="equation"):
        lib.load_catalogue(bad)
    assert generate.main(["--catalogue", str(bad), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    assert "equation" in capsys.readouterr().err
    assert generate.main(["--only", "no-such-surface-anywhere", "--out", str(tmp_path / "o"), "--quiet"]) == 2


def test_select_and_slugs(lib):
    _, entries = lib.load_catalogue(CATALOGUE)
    picked = [e.name for e in lib.select(entries, ["a1+", "CAYLEY"])]
    assert picked == ["A1+-", "A1++", "Cayley cubic"]
    assert lib.select(entries, None) == entries
    assert lib.slugify("A1+-") != lib.slugify("A1-+")
    assert lib.slugify("Steiner's Roman surface") == "steiner-s-roman-surface"


def test_compare(lib):
    _, entries = lib.load_catalogue(CATALOGUE)
    cayley = next(e for e in entries if e.name == "Cayley cubic")
    assert lib.compare(cayley, ["A1--"] * 4, 2, [2] * 4)["verdict"] == "match"
    assert lib.compare(cayley, ["A1--"] * 3, 2)["verdict"] == "mismatch"
    assert lib.compare(cayley, ["A1--"] * 4, 3)["verdict"] == "mismatch"
    assert lib.compare(cayley, ["A1++"] * 4, 2)["forms"] is False
    assert lib.compare(cayley, ["rank 3"] * 4, 2)["types"] is False
    assert lib.compare(cayley, ["A1--"] * 4, 2, [1, 2, 2, 2])["verdict"] == "mismatch"
    sphere = next(e for e in entries if e.name == "Sphere")
    assert lib.compare(sphere, [], 2)["verdict"] == "match"
    assert lib.compare(sphere, [], 0)["verdict"] == "mismatch"
    crosscap = next(e for e in entries if e.name == "Cross-cap")
    assert lib.compare(crosscap, [], 1)["verdict"] == "match"
    crixxi = next(e for e in entries if e.name == "Crixxi")
    assert lib.compare(crixxi, [], 1)["verdict"] == "unsupported"


@pytest.mark.skipif(not hasattr(__import__("signal"), "setitimer"), reason="time limit needs SIGALRM")
def test_an_entry_over_the_time_limit_is_recorded_not_waited_for(lib, tmp_path):
    _, entries = lib.load_catalogue(CATALOGUE)
    barth = next(e for e in entries if e.name == "Barth sextic")  # seconds of work
    rec = lib.run_entry(barth, tmp_path, size=64, timeout=0.05)
    assert not rec["ok"] and rec["stage"] == "mesh"
    assert "EntryTimeout" in rec["error"] and rec["comparison"]["verdict"] == "error"


# ---------------------------------------------------------------- the built gallery
def test_build_records_every_entry_in_order(built, lib):
    out, report, status = built
    assert status == 0
    names = [r["name"] for r in report["entries"]]
    # catalogue order, whatever order the two processes finished in
    assert names == ["Cone", "Sphere", "Cross-cap", UNSUPPORTED_NAME, BROKEN_NAME]
    for r in report["entries"]:
        assert r["slug"] and r["comparison"]["verdict"] in ("match", "mismatch", "unsupported", "error")
    good = [r for r in report["entries"] if r["name"] != BROKEN_NAME]
    for r in good:
        assert r["ok"], r["error"]
        assert r["report"]["faces"] > 0 and r["time"] > 0
        assert r["report_text"].startswith("surface")
    sphere = next(r for r in good if r["name"] == "Sphere")
    assert sphere["report"]["euler_characteristic"] == 2
    assert sphere["comparison"]["verdict"] == "match"
    assert report["meta"]["jobs"] == 2 and report["meta"]["total_time"] > 0


def test_files_exist_and_pictures_are_right(built):
    import matplotlib.image as mpimg

    out, report, _ = built
    for r in report["entries"]:
        if not r["ok"]:
            continue
        for kind in ("ply", "obj", "png"):
            f = out / r["files"][kind]
            assert f.is_file() and f.stat().st_size > 0, f
        img = mpimg.imread(out / r["files"]["png"])
        assert img.shape[:2] == (SIZE, SIZE)
        assert _non_blank(img) > 0.03, f"{r['name']}: the picture is (nearly) blank"
        assert _coloured(img) > 0.03, f"{r['name']}: no shaded surface in the picture"
    obj = (out / "cone.obj").read_text()
    assert sum(line.startswith("v ") for line in obj.splitlines()) == next(
        r for r in report["entries"] if r["name"] == "Cone")["report"]["vertices"]


def test_index_references_every_entry_and_links_resolve(built):
    out, report, _ = built
    index = out / "index.html"
    targets, text = _local_targets(index)
    for t in targets:
        assert t.exists(), f"index.html links to a missing file: {t.name}"
    page = index.read_text(encoding="utf-8")
    for r in report["entries"]:
        assert r["name"] in text
        assert html.escape(r["equation"]) in page
        detail = out / f"{r['slug']}.html"
        assert detail in targets
        for kind in ("ply", "obj", "png"):
            if kind in r["files"]:
                assert out / r["files"][kind] in targets, f"index.html does not link {kind} of {r['name']}"
        dtargets, dtext = _local_targets(detail)
        for t in dtargets:
            assert t.exists(), f"{detail.name} links to a missing file: {t.name}"
        assert r["name"] in dtext
        if r["report_text"]:
            assert html.escape(r["report_text"]) in detail.read_text(encoding="utf-8")
    assert (out / "style.css").is_file()


def test_broken_entry_is_shown_with_its_error(built):
    out, report, _ = built
    broken = next(r for r in report["entries"] if r["name"] == BROKEN_NAME)
    assert not broken["ok"]
    assert broken["stage"] == "mesh"
    assert "SurfaceError" in broken["error"]
    assert broken["comparison"]["verdict"] == "error"
    card = _card((out / "index.html").read_text(encoding="utf-8"), broken["slug"])
    assert 'data-verdict="error"' in card
    assert html.escape(broken["error"]) in card
    detail = (out / f"{broken['slug']}.html").read_text(encoding="utf-8")
    assert html.escape(broken["error"]) in detail and "Traceback" in detail


def test_curves_are_recorded_and_drawn(built):
    out, report, _ = built
    cc = next(r for r in report["entries"] if r["name"] == "Cross-cap")
    # x^2 y - z^2: the y-axis is a double line for y > 0, a pinch point at
    # the origin, an isolated line for y < 0.
    assert cc["ok"] and cc["comparison"]["verdict"] == "match"
    assert {c["type"] for c in cc["curves"]} == {"A1 double curve", "A1 isolated line"}
    pinch = [p["point"] for p in cc["special_points"] if p["kind"] == "pinch point"]
    assert len(pinch) == 1 and max(abs(c) for c in pinch[0]) <= 1e-9
    assert "A1 double curve" in cc["report_text"]


def test_unsupported_entry_is_labelled(built):
    out, report, _ = built
    cc = next(r for r in report["entries"] if r["name"] == UNSUPPORTED_NAME)
    assert cc["ok"] and cc["comparison"]["verdict"] == "unsupported"
    card = _card((out / "index.html").read_text(encoding="utf-8"), cc["slug"])
    assert 'data-verdict="unsupported"' in card and "unsupported" in card and html.escape(cc["reason"]) in card


def test_report_json_is_strict_json(built):
    out, _, _ = built
    # allow_nan=False on the way out: no NaN/Infinity tokens that strict readers reject
    text = (out / "report.json").read_text(encoding="utf-8")
    json.loads(text, parse_constant=lambda c: pytest.fail(f"non-standard JSON constant {c}"))


def test_cli_runs_the_gallery(tmp_path):
    out = tmp_path / "cli"
    proc = subprocess.run(
        [sys.executable, "-m", "singmesh.cli", "gallery", "--only", "sphere", "--out", str(out),
         "--coarse", "16", "--fine", "32", "--size", "120", "--quiet"],
        capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert (out / "index.html").is_file() and (out / "sphere.png").is_file()


# ---------------------------------------------------------------- headless browser
def _chromium() -> str | None:
    for name in ("chromium", "chromium-browser"):
        path = shutil.which(name)
        if path:
            return path
    return "/usr/bin/chromium" if os.path.exists("/usr/bin/chromium") else None


def _ensure_chromium() -> str:
    path = _chromium()
    if path:
        return path
    if hasattr(os, "geteuid") and os.geteuid() == 0 and shutil.which("apt-get"):
        env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
        try:
            subprocess.run(["apt-get", "update"], env=env, capture_output=True, timeout=600, check=True)
            subprocess.run(["apt-get", "install", "-y", "chromium"], env=env, capture_output=True,
                           timeout=900, check=True)
        except (subprocess.SubprocessError, OSError) as exc:
            pytest.skip(f"chromium is not installed and 'apt-get install -y chromium' failed: {exc}")
        path = _chromium()
        if path:
            return path
        pytest.skip("chromium is not installed, and installing it with apt-get did not provide it")
    pytest.skip("chromium is not installed (/usr/bin/chromium missing) and it cannot be installed "
                "here (needs root and apt-get): skipping the browser check")


def _chromium_args(binary: str, profile: Path) -> list[str]:
    return [binary, "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
            "--disable-component-update", "--disable-sync", "--no-first-run", "--disable-dev-shm-usage",
            f"--user-data-dir={profile}"]


def test_page_renders_in_headless_chromium(built, tmp_path):
    import matplotlib.image as mpimg

    binary = _ensure_chromium()
    out, report, _ = built
    url = (out / "index.html").resolve().as_uri()
    dom = subprocess.run(_chromium_args(binary, tmp_path / "profile") + ["--dump-dom", url],
                         capture_output=True, text=True, timeout=120)
    assert dom.returncode == 0, dom.stderr[-2000:]
    text = dom.stdout
    assert text.count("<article") == len(report["entries"])
    for r in report["entries"]:
        assert html.escape(r["name"]) in text, r["name"]
    assert 'data-verdict="error"' in text

    shot = tmp_path / "shot.png"
    proc = subprocess.run(_chromium_args(binary, tmp_path / "profile") +
                          ["--window-size=1280,1600", "--hide-scrollbars", f"--screenshot={shot}", url],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0 and shot.is_file(), proc.stderr[-2000:]
    img = mpimg.imread(shot)
    assert img.shape[0] > 500 and img.shape[1] > 500
    assert _non_blank(img) > 0.05
    # the thumbnails were drawn: the orange of the surfaces is on the screen
    rgb = img[..., :3]
    orange = (rgb[..., 0] > 0.55) & (rgb[..., 0] - rgb[..., 2] > 0.3) & (rgb[..., 1] > rgb[..., 2])
    assert orange.mean() > 0.005, "no surface thumbnails visible in the screenshot"


#: The characters outside ASCII the pages may use: each is in both DejaVu Sans and
#: Liberation Sans (fc-list ':charset=HEX'), the fonts a Linux browser falls back on.
#: The verdict marks are SVG icons, not characters (U+29B8 is in neither font).
PAGE_CHARACTERS = set("\u00b7\u00d7\u03c7\u2014\u2190\u2192")


def test_pages_use_only_characters_common_fonts_have(built):
    out, report, _ = built
    pages = [out / "index.html", out / "style.css"] + [out / f"{r['slug']}.html" for r in report["entries"]]
    for page in pages:
        text = page.read_text(encoding="utf-8")
        odd = {c for c in text if ord(c) > 127} - PAGE_CHARACTERS
        assert not odd, f"{page.name}: {sorted(odd)}"
    index = (out / "index.html").read_text(encoding="utf-8")
    for verdict in ("match", "error", "unsupported"):
        card = next(_card(index, r["slug"]) for r in report["entries"] if r["comparison"]["verdict"] == verdict)
        badge = card[card.index('<span class="badge'):]
        assert badge.index("<svg") < badge.index("</span>"), f"the {verdict} badge has no icon"


def test_entry_pages_embed_the_interactive_view(built):
    out, report, _ = built
    for name in ("three.min.js", "three.LICENSE", "singmesh-view.js"):
        assert (out / name).is_file(), name
    for r in report["entries"]:
        page = (out / f"{r['slug']}.html").read_text(encoding="utf-8")
        if not r["ok"]:
            assert "singmesh-view" not in page   # nothing to show: the failure is
            continue
        block = page[page.index('<script type="application/json"'):]
        data = json.loads(block[block.index(">") + 1:block.index("</script>")])
        assert data["triangles"] == r["report"]["faces"]
        assert len(data["points"]) == len(r["singularities"])
        assert '<script src="three.min.js"></script>' in page and '<script src="singmesh-view.js"></script>' in page
    cc = next(r for r in report["entries"] if r["name"] == "Cross-cap")
    page = (out / f"{cc['slug']}.html").read_text(encoding="utf-8")
    assert '"curves":"' in page and '"isolated":"' in page   # its double line and its isolated line


def test_entry_page_view_draws_in_chromium(built):
    from browser import Browser, colour_facts, find_chromium, region

    binary = find_chromium()
    if binary is None:
        pytest.skip("chromium is not installed (apt-get install chromium): the view is not opened")
    out, report, _ = built
    state = "(function () { var s = document.querySelector('.singmesh-view').getAttribute('data-state');" \
            " return s && s !== 'starting' ? s : null; })()"
    with Browser(binary, width=1100, height=800) as b:
        b.open((out / "cone.html").as_uri())
        assert b.wait_for(state, timeout=30) == "drawn", b.problems()
        assert b.problems() == [] and b.warnings() == []
        rect = b.evaluate("JSON.parse(JSON.stringify(document.querySelector('.singmesh-view').getBoundingClientRect()))")
        facts = colour_facts(region(b.screenshot(), rect))
        assert facts["distinct"] >= 100 and facts["orange"] > 0.002 and facts["blue"] > 0.002, facts
        b.open((out / "index.html").as_uri())
        assert b.evaluate("document.querySelectorAll('article').length") == len(report["entries"])
        assert b.problems() == []


DEFS = """\
<group name="Quadrics">
<group name="Round">
<definition name="Sphere" type="asurf">
// A round sphere of radius r
x^2 + y^2
  + z^2 - r^2;
<parameter name="r" value="0.8">
<variable name="x" min="-1.04" max="1.03">
<variable name="y" min="-1.03" max="1.04">
<variable name="z" min="-1.02" max="1.05"}, >
</definition>
</group>
<definition name="Cone" type="asurf">
X^2 - y^2 - z^2; X = x - c; c = 0;
</definition>
</group>
<definition name="Undefined parameter" type="asurf">
(x-x0)^2 + y^2 + z^2 - 1;
</definition>
<definition name="Curve" type="acurve">
x^2 - y^3;
</definition>
"""


def test_gallery_from_a_defs_file(generate, tmp_path):
    defs = tmp_path / "mine.defs"
    defs.write_text(DEFS, encoding="utf-8")
    out = tmp_path / "defs"
    status = generate.main(["--defs", str(defs), "--out", str(out), "--size", "120",
                            "--coarse", "8", "--fine", "32", "--quiet", "--strict"])
    assert status == 0   # definitions that do not read are not failures
    report = json.loads((out / "report.json").read_text(encoding="utf-8"))
    by_name = {r["name"]: r for r in report["entries"]}
    assert list(by_name) == ["Sphere", "Cone", "Undefined parameter", "Curve"]
    sphere, cone = by_name["Sphere"], by_name["Cone"]
    assert sphere["ok"] and sphere["box"] == [[-1.04, 1.03], [-1.03, 1.04], [-1.02, 1.05]]
    assert sphere["report"]["euler_characteristic"] == 2
    assert np.allclose(np.linalg.norm(_ply_vertices(out / sphere["files"]["ply"]), axis=1), 0.8)
    assert sphere["comparison"]["verdict"] == "meshed" and sphere["description"] == "A round sphere of radius r"
    assert cone["ok"] and [s["name"] for s in cone["singularities"]] == ["A1--"]
    index = (out / "index.html").read_text(encoding="utf-8")
    # Grouped as the file groups them.
    assert index.index("Quadrics / Round") < index.index("Sphere") < index.index(">Quadrics<")
    # The definitions that do not read: a line each in the index, with the reason and place.
    undefined = by_name["Undefined parameter"]
    assert not undefined["ok"] and "unknown symbol x0" in undefined["unread"]
    assert "mine.defs, line 18, column 4" in undefined["unread"]
    assert html.escape(undefined["unread"]) in index and 'data-verdict="unread"' in index
    assert "not an implicit surface" in by_name["Curve"]["unread"]
    assert f'id="{undefined["slug"]}"' not in index   # a line, not a card


def test_gallery_defs_file_errors(generate, tmp_path, capsys):
    bad = tmp_path / "bad.defs"
    bad.write_text('<definition name="a" type="asurf">\nx;\n', encoding="utf-8")
    assert generate.main(["--defs", str(bad), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    assert "not closed by </definition>" in capsys.readouterr().err


def _ply_vertices(path):
    import meshio

    return meshio.read(path).points


def test_an_entry_coloured_by_curvature(lib, tmp_path):
    """The torus coloured by K: blue (K < 0) on the inner side, red (K > 0) outside, in the picture."""
    import matplotlib.image as mpimg

    _, entries = lib.load_catalogue(CATALOGUE)
    torus = next(e for e in entries if e.name == "Torus coloured by Gaussian curvature")
    assert torus.colour == "gaussian"
    rec = lib.run_entry(torus, tmp_path, size=160, coarse=16, fine=16)
    assert rec["ok"], rec["error"]
    img = mpimg.imread(tmp_path / rec["files"]["png"])[..., :3].astype(float)
    red = img[..., 0] - img[..., 2] > 0.2
    blue = img[..., 2] - img[..., 0] > 0.2
    assert red.mean() > 0.02 and blue.mean() > 0.01
    # The torus is centred on the box: blue nearer the picture's centre of the surface.
    ys, xs = np.nonzero(red | blue)
    centre = np.array([ys.mean(), xs.mean()])
    dist = lambda mask: np.linalg.norm(np.argwhere(mask) - centre, axis=1).mean()  # noqa: E731
    assert dist(blue) < 0.8 * dist(red)
    bad = tmp_path / "bad.toml"
    bad.write_text('[[entry]]\nname = "x"\nequation = "x"\nbox = [[0, 1], [0, 1], [0, 1]]\nexpected = []\n'
                   'colour = "rainbow"\n')
    with pytest.raises(lib.CatalogueError, match="colour"):
        lib.load_catalogue(bad)
