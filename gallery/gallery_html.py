"""Static HTML for the singmesh gallery: ``index.html``, one page per entry, ``style.css``.

Everything is local (no fonts, scripts or styles from the network), so the
output directory can be opened from disk or copied anywhere.  The index has
a few lines of inline JavaScript for the filter buttons (without it every
entry is simply shown).  Each entry's page has the interactive 3-D view of
:mod:`singmesh.view`: its mesh data embedded in the page, three.js and the
viewer loaded by classic ``<script src>`` from the folder itself (copied
there by :func:`write_site`).

Marks and badges are small inline SVG icons, not characters: the symbols
they replace (U+29B8 in particular) are missing from common fonts.
"""

from __future__ import annotations

import html
from pathlib import Path
from typing import Any, Sequence

from gallery_lib import Group, type_summary
from singmesh.view import VIEW_CSS, copy_scripts, view_fragment

DASH = "\u2014"
DOT = " \u00b7 "

#: Icons as inline SVG paths (16 x 16, drawn in the text colour): a font
#: may lack a symbol (U+29B8, the circled slash, is in neither DejaVu nor
#: Liberation: fc-list ':charset=29b8'), an SVG is drawn the same everywhere.
_ICON_PATHS = {
    "check": '<path d="M3 8.6l3.2 3.2L13 4.6" fill="none" stroke-width="2.2"/>',
    "cross": '<path d="M4.2 4.2l7.6 7.6M11.8 4.2l-7.6 7.6" fill="none" stroke-width="2.2"/>',
    "circle-slash": '<circle cx="8" cy="8" r="5.9" fill="none" stroke-width="1.8"/>'
                    '<path d="M3.9 3.9l8.2 8.2" fill="none" stroke-width="1.8"/>',
    "circle": '<circle cx="8" cy="8" r="5.2" fill="none" stroke-width="1.8"/>',
    "circle-backslash": '<circle cx="8" cy="8" r="5.9" fill="none" stroke-width="1.8"/>'
                        '<path d="M12.1 3.9l-8.2 8.2" fill="none" stroke-width="1.8"/>',
    "warning": '<path d="M8 1.9L15 14.1H1z" fill="none" stroke-width="1.7"/>'
               '<path d="M8 6.2v3.9" fill="none" stroke-width="1.9"/>'
               '<circle cx="8" cy="12.1" r="1.05" fill="currentColor" stroke="none"/>',
}


def icon(name: str, title: str | None = None) -> str:
    """An inline SVG icon (``_ICON_PATHS``) in the text's colour; with ``title``, an image named so."""
    a11y = f' role="img"><title>{esc(title)}</title>' if title else ' aria-hidden="true">'
    return (f'<svg class="icon" viewBox="0 0 16 16" width="16" height="16" stroke="currentColor" '
            f'stroke-linecap="round" stroke-linejoin="round"{a11y}{_ICON_PATHS[name]}</svg>')


#: Badge text, CSS class and icon per verdict.  Shape and text carry the
#: meaning as well as colour, so the marks survive grey-scale printing.
VERDICTS = {
    "match": ("match", "ok", "check"),
    "mismatch": ("mismatch", "bad", "cross"),
    "unsupported": ("unsupported", "warn", "circle-slash"),
    "meshed": ("meshed, nothing to compare", "na", "circle"),
    "unread": ("does not read", "warn", "circle-backslash"),
    "error": ("error", "err", "warning"),
}


def verdict_label(verdict: str) -> str:
    """The verdict's icon and words, as HTML."""
    text, _, name = VERDICTS[verdict]
    return f"{icon(name)} {esc(text)}"


CSS = """\
:root {
  --bg: #f4f5f7; --card: #ffffff; --ink: #1f2933; --muted: #66717d; --line: #e1e5ea;
  --ok: #1a7f37; --ok-bg: #dcf5e3; --bad: #b42318; --bad-bg: #fde4e1;
  --warn: #8a5a00; --warn-bg: #fdf0cc; --err: #ffffff; --err-bg: #b42318;
  --accent: #2c6ea3; --code-bg: #f1f3f6;
}
* { box-sizing: border-box; }
body { margin: 0; background: var(--bg); color: var(--ink);
  font: 15px/1.45 system-ui, -apple-system, "Segoe UI", Roboto, "Helvetica Neue", Arial, sans-serif; }
a { color: var(--accent); text-decoration: none; }
a:hover { text-decoration: underline; }
code, pre, .mono { font-family: ui-monospace, "SFMono-Regular", Menlo, Consolas, "DejaVu Sans Mono", monospace; }
header.top { background: #16202b; color: #f5f7fa; padding: 28px 32px 22px; }
header.top h1 { margin: 0 0 6px; font-size: 28px; font-weight: 650; letter-spacing: .2px; }
header.top p { margin: 4px 0; color: #b9c3cf; }
header.top a { color: #9cc9f0; }
.stats { display: flex; flex-wrap: wrap; gap: 8px; margin-top: 14px; }
.stats span { background: rgba(255,255,255,.08); border-radius: 999px; padding: 3px 12px; font-size: 14px; }
main { max-width: 1480px; margin: 0 auto; padding: 18px 24px 48px; }
.toolbar { display: flex; flex-wrap: wrap; gap: 8px; align-items: center; margin: 6px 0 10px; }
.toolbar button { border: 1px solid var(--line); background: var(--card); color: var(--ink);
  border-radius: 999px; padding: 5px 14px; font: inherit; font-size: 14px; cursor: pointer; }
.toolbar button.on { background: #16202b; color: #fff; border-color: #16202b; }
.legend { color: var(--muted); font-size: 13px; margin-left: auto; }
section.group { margin-top: 26px; }
section.group > h2 { font-size: 19px; margin: 0 0 2px; font-weight: 650; }
section.group > p.gdesc { margin: 0 0 12px; color: var(--muted); max-width: 920px; }
.grid { display: grid; grid-template-columns: repeat(auto-fill, minmax(270px, 1fr)); gap: 16px; }
.card { background: var(--card); border: 1px solid var(--line); border-radius: 12px; overflow: hidden;
  display: flex; flex-direction: column; box-shadow: 0 1px 2px rgba(16,24,40,.04); }
.card:hover { box-shadow: 0 4px 14px rgba(16,24,40,.10); }
.card.v-mismatch { border-top: 4px solid var(--bad); }
.card.v-match { border-top: 4px solid var(--ok); }
.card.v-unsupported { border-top: 4px solid #e0a800; }
.card.v-error { border-top: 4px solid var(--err-bg); }
.thumb { display: block; aspect-ratio: 1 / 1; background: #fbfbfc; border-bottom: 1px solid var(--line); }
.thumb img { width: 100%; height: 100%; object-fit: contain; display: block; }
.thumb.none { display: flex; align-items: center; justify-content: center; color: var(--bad);
  font-size: 14px; padding: 16px; text-align: center; }
.body { padding: 10px 14px 12px; display: flex; flex-direction: column; gap: 6px; flex: 1; }
.title { display: flex; justify-content: space-between; align-items: baseline; gap: 8px; }
.title h3 { margin: 0; font-size: 17px; font-weight: 650; }
.badge { border-radius: 999px; padding: 1px 9px; font-size: 12.5px; font-weight: 600; white-space: nowrap; }
svg.icon { width: 1em; height: 1em; vertical-align: -0.14em; overflow: visible; }
.badge.ok { color: var(--ok); background: var(--ok-bg); }
.badge.bad { color: var(--bad); background: var(--bad-bg); }
.badge.warn { color: var(--warn); background: var(--warn-bg); }
.badge.err { color: var(--err); background: var(--err-bg); }
.badge.na { color: var(--muted); background: var(--code-bg); }
ul.unread { margin: 12px 0 0; padding-left: 20px; color: var(--muted); font-size: 14px; }
ul.unread b { color: var(--ink); }
code.eq { white-space: pre-wrap; }
code.eq { display: block; background: var(--code-bg); border-radius: 6px; padding: 5px 8px; font-size: 12.5px;
  overflow-wrap: anywhere; max-height: 5.6em; overflow: auto; }
.desc { color: var(--muted); font-size: 13.5px; margin: 0; }
dl.facts { display: grid; grid-template-columns: auto 1fr; gap: 2px 10px; margin: 2px 0 0; font-size: 13.5px; }
dl.facts dt { color: var(--muted); }
dl.facts dd { margin: 0; }
.mark { font-weight: 700; }
.mark.ok { color: var(--ok); } .mark.bad { color: var(--bad); } .mark.na { color: var(--muted); font-weight: 400; }
.note { font-size: 13px; border-radius: 6px; padding: 5px 8px; margin: 0; }
.note.warn { background: var(--warn-bg); color: var(--warn); }
.note.err { background: var(--bad-bg); color: var(--bad); overflow-wrap: anywhere; }
.links { margin-top: auto; padding-top: 4px; font-size: 13.5px; display: flex; gap: 12px; }
.detail { max-width: 1180px; margin: 0 auto; padding: 18px 24px 48px; }
.detail nav { display: flex; justify-content: space-between; gap: 12px; margin-bottom: 10px; font-size: 14px; }
.detail h1 { margin: 4px 0; font-size: 26px; display: flex; gap: 12px; align-items: center; flex-wrap: wrap; }
.detail .cols { display: grid; grid-template-columns: minmax(0, 1.25fr) minmax(0, 1fr); gap: 22px; margin-top: 12px; }
@media (max-width: 900px) { .detail .cols { grid-template-columns: 1fr; } }
.detail img.big { width: 100%; height: auto; background: #fbfbfc; border: 1px solid var(--line); border-radius: 12px; }
.panel { background: var(--card); border: 1px solid var(--line); border-radius: 12px; padding: 12px 16px; margin-bottom: 16px; }
.panel h2 { font-size: 16px; margin: 0 0 8px; }
table { border-collapse: collapse; width: 100%; font-size: 13.5px; }
th, td { text-align: left; padding: 4px 8px 4px 0; border-bottom: 1px solid var(--line); vertical-align: top; }
th { color: var(--muted); font-weight: 600; }
pre { background: #16202b; color: #e6edf3; padding: 12px 14px; border-radius: 10px; overflow: auto; font-size: 12.5px; line-height: 1.4; }
pre.eq { background: var(--code-bg); color: var(--ink); white-space: pre-wrap; overflow-wrap: anywhere; }
footer { color: var(--muted); font-size: 13px; text-align: center; padding: 24px; }
details.still { margin-top: 10px; font-size: 14px; }
details.still summary { cursor: pointer; color: var(--accent); }
details.still img.big { margin-top: 8px; }
""" + VIEW_CSS

FILTER_JS = """\
document.querySelectorAll('.toolbar button').forEach(function (b) {
  b.addEventListener('click', function () {
    document.querySelectorAll('.toolbar button').forEach(function (o) { o.classList.remove('on'); });
    b.classList.add('on');
    var v = b.dataset.show;
    document.querySelectorAll('.card, ul.unread li').forEach(function (c) {
      c.style.display = (v === 'all' || c.dataset.verdict === v) ? '' : 'none';
    });
    document.querySelectorAll('section.group').forEach(function (s) {
      var any = Array.prototype.some.call(s.querySelectorAll('.card, ul.unread li'), function (c) { return c.style.display !== 'none'; });
      s.style.display = any ? '' : 'none';
    });
  });
});
"""


def esc(value: Any) -> str:
    """HTML-escaped text of any value."""
    return html.escape("" if value is None else str(value), quote=True)


def _mark(ok: bool | None) -> str:
    if ok is None:
        return '<span class="mark na" title="not checked">\u2014</span>'
    if ok:
        return f'<span class="mark ok" title="as expected">{icon("check", "as expected")}</span>'
    return f'<span class="mark bad" title="differs from the catalogue">{icon("cross", "differs")}</span>'


def verdict_of(rec: dict) -> str:
    """The entry's verdict, "unread" when its equation does not read, "error" when it failed."""
    if rec.get("unread"):
        return "unread"
    if rec.get("error"):
        return "error"
    return (rec.get("comparison") or {}).get("verdict") or "error"


def badge(rec: dict) -> str:
    """The coloured verdict badge of an entry (plus "unsupported" for a failed unsupported one)."""
    v = verdict_of(rec)
    out = f'<span class="badge {VERDICTS[v][1]}">{verdict_label(v)}</span>'
    if v == "error" and rec.get("status") == "unsupported":
        out += f' <span class="badge {VERDICTS["unsupported"][1]}">{verdict_label("unsupported")}</span>'
    return out


def _fmt_time(t: float | None) -> str:
    return "\u2014" if t is None else (f"{t:.2f} s" if t < 10 else f"{t:.1f} s")


def singular_summary(rec: dict) -> tuple[str, str]:
    """(count line, types line) for a card: found / expected with a mark."""
    found = [s.get("name") or "?" for s in rec.get("singularities") or []]
    if rec.get("expected") is None:  # an entry of a .defs file: nothing known
        count = "\u2014" if rec.get("report") is None else f"{len(found)} found"
        return count, f"found {esc(type_summary(found))}"
    expected = rec.get("expected") or []
    comp = rec.get("comparison") or {}
    if rec.get("report") is None:
        count = f"\u2014 found / {len(expected)} expected"
    else:
        count = f"{len(found)} found / {len(expected)} expected {_mark(comp.get('types'))}"
    want = rec.get("real_forms") or expected
    types = f"found {esc(type_summary(found))}; expected {esc(type_summary(want))}"
    return count, types


def euler_summary(rec: dict) -> str:
    """The Euler characteristic with the expected value and a mark."""
    rep = rec.get("report")
    exp = rec.get("euler")
    if rep is None:
        return "\u2014"
    chi = rep.get("euler_characteristic")
    if exp is None:
        return f'{esc(chi)} <span class="mark na">(expected value not known)</span>'
    return f"{esc(chi)} (expected {esc(exp)}) {_mark((rec.get('comparison') or {}).get('euler'))}"


def _quality_note(rec: dict) -> str:
    rep = rec.get("report") or {}
    bits = []
    if rep.get("boundary_edges_off_box"):
        bits.append(f"{rep['boundary_edges_off_box']} open edges off the box faces")
    if rep.get("non_manifold_edges"):
        bits.append(f"{rep['non_manifold_edges']} non-manifold edges")
    return f'<p class="note warn">{esc("; ".join(bits))}</p>' if bits else ""


def card(rec: dict) -> str:
    """One thumbnail card of the index."""
    slug = esc(rec["slug"])
    v = verdict_of(rec)
    files = rec.get("files") or {}
    if "png" in files:
        thumb = (f'<a class="thumb" href="{slug}.html"><img src="{esc(files["png"])}" '
                 f'alt="{esc(rec["name"])}" loading="lazy"></a>')
    else:
        thumb = f'<a class="thumb none" href="{slug}.html">no picture: failed at {esc(rec.get("stage"))}</a>'
    count, types = singular_summary(rec)
    rep = rec.get("report") or {}
    size = (f'{rep.get("vertices", 0)} V \u00b7 {rep.get("faces", 0)} F \u00b7 {_fmt_time(rec.get("time"))}'
            if rep else "\u2014")
    notes = []
    if rec.get("status") == "unsupported":
        notes.append(f'<p class="note warn">Unsupported: {esc(rec.get("reason"))}</p>')
    if rec.get("error"):
        notes.append(f'<p class="note err mono">{esc(rec["error"])}</p>')
    notes.append(_quality_note(rec))
    links = [f'<a href="{slug}.html">details</a>']
    for kind in ("ply", "obj"):
        if kind in files:
            links.append(f'<a href="{esc(files[kind])}" download>{kind.upper()}</a>')
    return f"""<article class="card v-{v}" id="{slug}" data-verdict="{v}">
{thumb}
<div class="body">
<div class="title"><h3><a href="{slug}.html">{esc(rec["name"])}</a></h3>{badge(rec)}</div>
<code class="eq">{esc(rec["equation"])}</code>
<p class="desc">{esc(rec.get("description"))}</p>
<dl class="facts">
<dt>singular</dt><dd>{count}</dd>
<dt>types</dt><dd>{types}</dd>
<dt>\u03c7</dt><dd>{euler_summary(rec)}</dd>
<dt>mesh</dt><dd>{size}</dd>
</dl>
{''.join(notes)}
<div class="links">{DOT.join(links)}</div>
</div>
</article>"""


def _page(title: str, body: str) -> str:
    return f"""<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>{esc(title)}</title>
<link rel="stylesheet" href="style.css">
</head>
<body>
{body}
</body>
</html>
"""


def counts(records: Sequence[dict]) -> dict[str, int]:
    """How many entries have each verdict."""
    out = {k: 0 for k in VERDICTS}
    for r in records:
        out[verdict_of(r)] += 1
    return out


def index_page(records: Sequence[dict], groups: Sequence[Group], meta: dict) -> str:
    """The whole ``index.html``."""
    c = counts(records)
    by_group: dict[str, list[dict]] = {}
    for r in records:
        by_group.setdefault(r["group"], []).append(r)
    sections = []
    for g in groups:
        recs = by_group.get(g.id)
        if not recs:
            continue
        cards = "\n".join(card(r) for r in recs if not r.get("unread"))
        # Definitions that do not read: one line each, with the reason.
        unread = "".join(f'<li data-verdict="unread"><b>{esc(r["name"])}</b>: <span class="mono">'
                         f'{esc(r["unread"])}</span></li>' for r in recs if r.get("unread"))
        sections.append(f"""<section class="group" id="group-{esc(g.id)}">
<h2>{esc(g.title)}</h2>
<p class="gdesc">{esc(g.description)}</p>
<div class="grid">
{cards}
</div>
{f'<ul class="unread">{unread}</ul>' if unread else ''}
</section>""")
    buttons = "".join(
        f'<button type="button" data-show="{k}"{" class=on" if k == "all" else ""}>{label}</button>'
        for k, label in [("all", f"all {len(records)}")] + [(k, f"{verdict_label(k)} {c[k]}") for k in VERDICTS
                                                            if c[k] or k in ("match", "error")])
    body = f"""<header class="top">
<h1>singmesh gallery</h1>
<p>Real algebraic surfaces F(x, y, z) = 0 meshed by singmesh {esc(meta.get("singmesh_version"))}:
singular points found against what is known, Euler characteristic, and the meshes to download.</p>
<p>Built {esc(meta.get("generated"))} in {_fmt_time(meta.get("total_time"))}
({esc(meta.get("jobs"))} process{"es" if meta.get("jobs", 1) != 1 else ""}) \u00b7 <a href="report.json">report.json</a></p>
<div class="stats">
<span>{len(records)} surfaces</span>
{"".join(f'<span>{verdict_label(k)} {c[k]}</span>' for k in VERDICTS if c[k] or k in ("match", "error"))}
</div>
</header>
<main>
<div class="toolbar">{buttons}
<span class="legend">orange: the side grad F points to, blue: the other side \u00b7 dots: singular points found
(red A, purple D, green E, black other) \u00b7 <span class="mark ok">{icon("check")}</span> as expected,
<span class="mark bad">{icon("cross")}</span> differs, \u2014 not known \u00b7
each entry's page turns the surface in 3-D</span></div>
{chr(10).join(sections)}
</main>
<footer>Generated by gallery/generate.py from {esc(Path(meta.get("catalogue") or "gallery/catalogue.toml").name)}.</footer>
<script>
{FILTER_JS}</script>"""
    return _page("singmesh gallery", body)


def _fmt_point(p) -> str:
    try:
        return "(" + ", ".join(f"{float(v):.6g}" for v in p) + ")"
    except (TypeError, ValueError):
        return esc(p)


#: Height of the interactive view on an entry's page, in CSS pixels.
VIEW_HEIGHT = 560


def detail_page(rec: dict, prev: dict | None, nxt: dict | None, group: Group | None,
                view: str | None = None) -> str:
    """The page of one entry: interactive view (or picture), comparison, singular points, full report.

    ``view``: the entry's :func:`singmesh.view.view_json` text, drawn by
    the scripts :func:`write_site` copies beside the page; without it the
    page shows the PNG picture alone.
    """
    slug = esc(rec["slug"])
    files = rec.get("files") or {}
    nav_prev = f'<a href="{esc(prev["slug"])}.html">\u2190 {esc(prev["name"])}</a>' if prev else "<span></span>"
    nav_next = f'<a href="{esc(nxt["slug"])}.html">{esc(nxt["name"])} \u2192</a>' if nxt else "<span></span>"
    picture = (f'<img class="big" src="{esc(files["png"])}" alt="{esc(rec["name"])}">' if "png" in files
               else f'<div class="panel"><p class="note err">No picture: the entry failed at the '
                    f'{esc(rec.get("stage"))} stage.</p></div>')
    if view is not None:
        still = (f'<details class="still"><summary>static picture</summary>{picture}</details>'
                 if "png" in files else "")
        picture = view_fragment(view, inline_script=False, script_src="", height=VIEW_HEIGHT) + still
    comp = rec.get("comparison") or {}
    count, types = singular_summary(rec)
    box = " \u00d7 ".join(f"[{lo:g}, {hi:g}]" for lo, hi in rec["box"])
    params = ", ".join(f"{esc(k)} = {esc(v)}" for k, v in (rec.get("params") or {}).items()) or "\u2014"
    info_rows = [
        ("group", esc(group.title if group else rec["group"])),
        ("box", esc(box)),
        ("parameters", params),
        ("resolution", f'coarse {esc(rec.get("coarse"))}, fine {esc(rec.get("fine"))}'),
        ("colour", f'by {esc(rec.get("colour"))} curvature (blue negative, white zero, red positive; '
                   'green where undefined)' if rec.get("colour") else "by side"),
        ("status", esc(rec.get("status")) + (f' \u2014 {esc(rec.get("reason"))}' if rec.get("reason") else "")),
    ]
    found_forms = [s.get("name") or "?" for s in rec.get("singularities") or []]
    branches_found = [s.get("branches") for s in rec.get("singularities") or []]
    cmp_rows = [
        ("singular points", count),
        ("types", types),
        ("real forms", f'{esc(type_summary(found_forms))} / {esc(type_summary(rec.get("real_forms") or []))} '
                       f'{_mark(comp.get("forms"))}' if rec.get("real_forms") is not None else "\u2014"),
        ("branches", f'found {esc(branches_found or DASH)}; expected '
                     + (f'{esc(list(rec["branches"]))} {_mark(comp.get("branches"))}'
                        if rec.get("branches") is not None else DASH)),
        ("Euler characteristic", euler_summary(rec)),
    ]
    rep = rec.get("report") or {}
    if rep:
        cmp_rows.append(("open / non-manifold edges",
                         f'{esc(rep.get("boundary_edges_off_box"))} off the box / {esc(rep.get("non_manifold_edges"))} '
                         f'{_mark(not rep.get("boundary_edges_off_box") and not rep.get("non_manifold_edges"))}'))
    sing_rows = "".join(
        f'<tr><td>{i + 1}</td><td class="mono">{esc(s.get("name"))}</td><td class="mono">{_fmt_point(s.get("point"))}</td>'
        f'<td>{esc(s.get("branches"))}</td><td class="mono">{esc(s.get("text"))}</td></tr>'
        for i, s in enumerate(rec.get("singularities") or []))
    sing_table = (f'<table><tr><th>#</th><th>name</th><th>point</th><th>branches</th><th>describe()</th></tr>{sing_rows}</table>'
                  if sing_rows else '<p class="desc">No singular points reported.</p>')
    downloads = " \u00b7 ".join(f'<a href="{esc(files[k])}" download>{k.upper()}</a>' for k in ("ply", "obj", "png") if k in files)
    error = ""
    if rec.get("error"):
        error = (f'<div class="panel"><h2>Error ({esc(rec.get("stage"))} stage)</h2>'
                 f'<p class="note err mono">{esc(rec["error"])}</p><pre>{esc(rec.get("traceback"))}</pre></div>')
    unsupported = ""
    if rec.get("status") == "unsupported":
        unsupported = (f'<p class="note warn">Unsupported by singmesh: {esc(rec.get("reason"))}. '
                       "It was meshed anyway; what you see is what comes out, not a correct mesh.</p>")
    notes = f'<p class="desc">{esc(rec["notes"])}</p>' if rec.get("notes") else ""
    report_text = (f'<div class="panel"><h2>Report</h2><pre>{esc(rec["report_text"])}</pre></div>'
                   if rec.get("report_text") else "")
    if rec.get("warnings"):
        items = "".join(f"<li class=\"mono\">{esc(w)}</li>" for w in rec["warnings"])
        report_text += f'<div class="panel"><h2>Warnings</h2><ul class="desc">{items}</ul></div>'

    body = f"""<div class="detail">
<nav>{nav_prev}<a href="index.html#{slug}">gallery</a>{nav_next}</nav>
<h1>{esc(rec["name"])} {badge(rec)}</h1>
<p class="desc">{esc(rec.get("description"))}</p>
{unsupported}
<div class="cols">
<div>{picture}
<p>{downloads}</p></div>
<div>
<div class="panel"><h2>Equation</h2><pre class="eq">{esc(rec["equation"])}</pre>
<table>{''.join(f'<tr><th>{k}</th><td>{v}</td></tr>' for k, v in info_rows)}</table>{notes}</div>
<div class="panel"><h2>Found against expected</h2>
<table>{''.join(f'<tr><th>{k}</th><td>{v}</td></tr>' for k, v in cmp_rows)}</table></div>
</div>
</div>
{error}
<div class="panel"><h2>Singular points</h2>{sing_table}</div>
{report_text}
</div>"""
    return _page(f"{rec['name']} \u2014 singmesh gallery", body)


def write_site(out_dir: str | Path, records: Sequence[dict], groups: Sequence[Group], meta: dict) -> Path:
    """Write ``style.css``, ``index.html``, ``<slug>.html`` for every record, and the view's scripts.

    Returns
    -------
    Path
        The index page.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    (out / "style.css").write_text(CSS, encoding="utf-8")
    copy_scripts(out)  # three.js, its licence and the viewer, loaded by the entries' pages
    by_id = {g.id: g for g in groups}
    for i, rec in enumerate(records):
        prev = records[i - 1] if i > 0 else None
        nxt = records[i + 1] if i + 1 < len(records) else None
        data = out / (rec.get("files") or {}).get("view", "-")
        view = data.read_text(encoding="utf-8") if data.is_file() else None
        (out / f"{rec['slug']}.html").write_text(detail_page(rec, prev, nxt, by_id.get(rec["group"]), view),
                                                encoding="utf-8")
    index = out / "index.html"
    index.write_text(index_page(records, groups, meta), encoding="utf-8")
    return index
