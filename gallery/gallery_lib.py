"""Catalogue, per-entry work and comparisons for the singmesh gallery.

Kept apart from ``generate.py`` so that worker processes can import the
function they run by a plain module name (``gallery_lib.run_entry``), which
works under every multiprocessing start method, also when ``generate.py``
itself was started through ``runpy`` by ``singmesh gallery``.
"""

from __future__ import annotations

import re
import signal
import sys
import threading
import time
import traceback
import warnings
from collections import Counter
from contextlib import contextmanager
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Iterable, Sequence

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

import numpy as np

from singmesh.files import json_safe

HERE = Path(__file__).resolve().parent
DEFAULT_CATALOGUE = HERE / "catalogue.toml"
STATUSES = ("supported", "unsupported")
#: Used where a .defs file gives no box.
DEFAULT_BOX = ((-2.0, 2.0), (-2.0, 2.0), (-2.0, 2.0))

#: The leading ADE type of a classification name: "A1--" -> "A1", "E_6" -> "E6".
_ADE = re.compile(r"^([ADE])_?(\d+)")
#: An expected token that names a type only, not a real form.
_TYPE_ONLY = re.compile(r"^[ADE]\d+$")


#: The surface colourings of an entry's ``colour`` field: the Mesh array
#: and the label written in the picture.
COLOURINGS = {"gaussian": ("gaussian_curvature", "Gaussian curvature K"),
              "mean": ("mean_curvature", "mean curvature")}


class CatalogueError(ValueError):
    """The catalogue file is unreadable or an entry misses a field."""


class EntryTimeout(TimeoutError):
    """An entry took longer than the time limit (``--timeout``)."""


@contextmanager
def time_limit(seconds: float | None):
    """Raise :class:`EntryTimeout` in this thread after ``seconds``.

    A surface the mesher cannot handle may run for hours (a curve of
    singular points makes the singular-point search refine thousands of
    candidates); without a limit one such entry would hold up the whole
    gallery.  Uses SIGALRM, so it works in the main thread of a process
    (as in the worker processes) on POSIX systems; elsewhere it does nothing.
    """
    usable = (seconds and seconds > 0 and hasattr(signal, "setitimer")
              and threading.current_thread() is threading.main_thread())
    if not usable:
        yield
        return

    def _expired(signum, frame):
        raise EntryTimeout(f"gave up after {seconds:g} s (the gallery's --timeout)")

    previous = signal.signal(signal.SIGALRM, _expired)
    signal.setitimer(signal.ITIMER_REAL, float(seconds))
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, previous)


@dataclass(frozen=True)
class Group:
    """A section of the page."""

    id: str
    title: str
    description: str = ""


@dataclass(frozen=True)
class Entry:
    """One surface of the catalogue (see the header of ``catalogue.toml``)."""

    name: str
    slug: str
    group: str
    equation: str
    box: tuple[tuple[float, float], ...]
    description: str
    expected: tuple[str, ...] | None  # None: nothing known to compare with (a .defs file)
    status: str
    reason: str = ""
    params: dict[str, Any] = field(default_factory=dict)
    real_forms: tuple[str, ...] | None = None
    branches: tuple[int, ...] | None = None
    euler: int | None = None
    notes: str = ""
    coarse: int = 32
    fine: int = 256
    timeout: float | None = None
    colour: str = ""  # "" (by side), or a per-vertex curvature: a key of COLOURINGS
    defs: str = ""  # the SingSurf .defs file and the index of the definition in it, if from one
    defs_index: int = -1

    @property
    def supported(self) -> bool:
        return self.status == "supported"

    def surface(self):
        """The surface to mesh: read from its .defs file (errors placed in it) or from ``equation``."""
        import singmesh

        if self.defs:
            return singmesh.read_definitions(self.defs)[self.defs_index].surface(**self.params)
        return singmesh.Surface.parse(self.equation, **self.params)


def slugify(name: str) -> str:
    """A file-name-safe, lower-case slug; trailing sign pairs are spelled out.

    ``"A1+-"`` -> ``"a1_pm"`` (signs would otherwise collapse and A1+- and
    A1-+ would collide), ``"Cayley cubic"`` -> ``"cayley-cubic"``.
    """
    s = re.sub(r"([+-]+)$", lambda m: "_" + m.group(1).replace("+", "p").replace("-", "m"), name.strip())
    s = s.lower().replace("^", "")
    s = re.sub(r"[^a-z0-9_]+", "-", s).strip("-")
    return s or "entry"


def _need(raw: dict, key: str, kind, where: str):
    if key not in raw:
        raise CatalogueError(f"{where}: missing field {key!r}")
    value = raw[key]
    if not isinstance(value, kind):
        raise CatalogueError(f"{where}: field {key!r} must be {getattr(kind, '__name__', kind)}, "
                             f"not {type(value).__name__}")
    return value


def _box(value, where: str) -> tuple[tuple[float, float], ...]:
    try:
        b = tuple((float(lo), float(hi)) for lo, hi in value)
    except (TypeError, ValueError):
        raise CatalogueError(f"{where}: box must be [[x0, x1], [y0, y1], [z0, z1]], not {value!r}") from None
    if len(b) != 3:
        raise CatalogueError(f"{where}: box must have three (lo, hi) pairs, not {len(b)}")
    return b


def load_catalogue(path: str | Path = DEFAULT_CATALOGUE) -> tuple[list[Group], list[Entry]]:
    """Read and check the catalogue.

    Parameters
    ----------
    path : str or Path
        A TOML file with ``[[group]]`` and ``[[entry]]`` tables.

    Returns
    -------
    groups : list of Group
        In file order; groups referred to by entries but not defined are
        appended with their id as title.
    entries : list of Entry
        In file order, with unique slugs.

    Raises
    ------
    CatalogueError
        Unreadable TOML, a missing or mistyped field, a duplicate name, or
        a status that is neither "supported" nor "unsupported".
    """
    path = Path(path)
    try:
        with open(path, "rb") as fh:
            data = tomllib.load(fh)
    except OSError as exc:
        raise CatalogueError(f"cannot read the catalogue {path}: {exc}") from None
    except tomllib.TOMLDecodeError as exc:
        raise CatalogueError(f"{path}: not valid TOML: {exc}") from None

    groups = []
    for i, raw in enumerate(data.get("group", [])):
        where = f"{path.name}: group {i + 1}"
        groups.append(Group(id=_need(raw, "id", str, where), title=_need(raw, "title", str, where),
                            description=raw.get("description", "")))
    known_groups = {g.id for g in groups}

    entries: list[Entry] = []
    names, slugs = set(), set()
    for i, raw in enumerate(data.get("entry", [])):
        where = f"{path.name}: entry {i + 1}"
        name = _need(raw, "name", str, where)
        where = f"{path.name}: entry {name!r}"
        if name in names:
            raise CatalogueError(f"{where}: the name is used twice")
        names.add(name)
        status = raw.get("status", "supported")
        if status not in STATUSES:
            raise CatalogueError(f"{where}: status must be one of {STATUSES}, not {status!r}")
        reason = raw.get("reason", "")
        if status == "unsupported" and not reason:
            raise CatalogueError(f"{where}: an unsupported entry needs a reason")
        expected = tuple(_need(raw, "expected", list, where))
        real_forms = raw.get("real_forms")
        if real_forms is not None and len(real_forms) != len(expected):
            raise CatalogueError(f"{where}: real_forms has {len(real_forms)} items, expected has {len(expected)}")
        group = raw.get("group", "other")
        if group not in known_groups:
            groups.append(Group(id=group, title=group))
            known_groups.add(group)
        slug = base = slugify(name)
        k = 2
        while slug in slugs:  # names differing only in punctuation
            slug, k = f"{base}-{k}", k + 1
        slugs.add(slug)
        euler = raw.get("euler")
        colour = raw.get("colour", "")
        if colour and colour not in COLOURINGS:
            raise CatalogueError(f"{where}: colour must be one of {sorted(COLOURINGS)}, not {colour!r}")
        entries.append(Entry(
            name=name, slug=slug, group=group,
            equation=_need(raw, "equation", str, where),
            box=_box(_need(raw, "box", list, where), where),
            description=raw.get("description", ""),
            expected=tuple(str(t) for t in expected),
            status=status, reason=reason,
            params=dict(raw.get("params", {})),
            real_forms=tuple(real_forms) if real_forms is not None else None,
            branches=tuple(raw["branches"]) if "branches" in raw else None,
            euler=int(euler) if euler is not None else None,
            notes=raw.get("notes", ""),
            coarse=int(raw.get("coarse", 32)), fine=int(raw.get("fine", 256)),
            timeout=float(raw["timeout"]) if "timeout" in raw else None,
            colour=colour,
        ))
    return groups, entries


def load_definitions(path: str | Path) -> tuple[list[Group], list[Entry]]:
    """A SingSurf ``.defs`` file as a catalogue: one entry per definition.

    Groups follow the file's ``<group>`` nesting ("Cubics / Class II ...").
    Nothing is known to compare with, so entries have ``expected=None``.
    A definition that does not read (or is not an implicit surface) keeps
    its entry; :func:`run_entry` records the reason as ``unread``.

    Raises
    ------
    CatalogueError
        If the file cannot be read or is malformed.
    """
    import singmesh

    try:
        definitions = singmesh.read_definitions(path)
    except singmesh.SurfaceError as exc:
        raise CatalogueError(str(exc)) from None
    groups: list[Group] = []
    by_path: dict[tuple, str] = {}
    entries: list[Entry] = []
    names, slugs = set(), set()
    for i, d in enumerate(definitions):
        if d.group not in by_path:
            title = " / ".join(d.group) or "(no group)"
            gid = slugify(title) or "ungrouped"
            while gid in {g.id for g in groups}:
                gid += "-"
            by_path[d.group] = gid
            groups.append(Group(id=gid, title=title, description=f"from {Path(path).name}"))
        name, k = d.name, 2
        while name in names:  # the files repeat some names
            name, k = f"{d.name} ({k})", k + 1
        names.add(name)
        slug = base = slugify(name)
        k = 2
        while slug in slugs:
            slug, k = f"{base}-{k}", k + 1
        slugs.add(slug)
        entries.append(Entry(
            name=name, slug=slug, group=by_path[d.group], equation=d.equation,
            box=d.box or DEFAULT_BOX, description=d.description or d.where, expected=None,
            status="supported", params=dict(d.parameters), notes=d.where + ("" if d.box else "; no box in the file: the default box"),
            defs=str(path), defs_index=i))
    return groups, entries


def select(entries: Sequence[Entry], only: Iterable[str] | None) -> list[Entry]:
    """Entries whose name contains any of ``only`` (case-insensitive); all if none given."""
    only = [o.lower() for o in (only or []) if o]
    if not only:
        return list(entries)
    return [e for e in entries if any(o in e.name.lower() for o in only)]


# ---------------------------------------------------------------- comparison
def ade_type(name: str | None) -> str | None:
    """The ADE type at the start of a classification name, or None."""
    m = _ADE.match(name or "")
    return f"{m.group(1)}{m.group(2)}" if m else None


def compare(entry: Entry, found_names: Sequence[str], euler: int | None,
            found_branches: Sequence[int | None] | None = None) -> dict[str, Any]:
    """Found singular points and Euler characteristic against the catalogue.

    Returns
    -------
    dict
        ``types`` (bool): the multiset of ADE types found equals the expected
        one (an expected token with a sign pair, or a non-ADE token, must
        match a found name exactly); ``forms`` (bool or None): the real forms
        match ``real_forms``, None when the catalogue gives none; ``branches``
        (bool or None): the branch counts match ``branches`` as a multiset,
        None when either side does not give them; ``euler``
        (bool or None): None when the catalogue gives no value;
        ``verdict``: "match" or "mismatch" for supported entries,
        "unsupported" otherwise, "meshed" when nothing is expected (an entry
        of a .defs file).
    """
    if entry.expected is None:
        return {"types": None, "forms": None, "branches": None, "euler": None,
                "verdict": "meshed" if entry.supported else "unsupported"}

    def key(token: str, exact: bool) -> str:
        return token if exact else (ade_type(token) or token)

    exact = [not _TYPE_ONLY.match(t) for t in entry.expected]
    want = Counter(key(t, x) for t, x in zip(entry.expected, exact))
    # A found point is compared by type unless the catalogue asked for an
    # exact name that it carries.
    exact_names = {t for t, x in zip(entry.expected, exact) if x}
    got = Counter(n if n in exact_names else (ade_type(n) or n) for n in found_names)
    types_ok = want == got
    forms_ok = None if entry.real_forms is None else Counter(entry.real_forms) == Counter(found_names)
    fb = list(found_branches) if found_branches is not None else None
    if entry.branches is None or fb is None or any(b is None for b in fb):
        branches_ok = None
    else:
        branches_ok = Counter(int(b) for b in fb) == Counter(entry.branches)
    euler_ok = None if entry.euler is None or euler is None else entry.euler == euler
    checks = (forms_ok, branches_ok, euler_ok)
    if not entry.supported:
        verdict = "unsupported"
    else:
        verdict = "match" if types_ok and all(c is not False for c in checks) else "mismatch"
    return {"types": types_ok, "forms": forms_ok, "branches": branches_ok, "euler": euler_ok,
            "verdict": verdict}


def type_summary(names: Iterable[str]) -> str:
    """``["A1--", "A1--", "D4--"]`` -> ``"2 x A1--, D4--"`` (in first-seen order)."""
    counts = Counter(names)
    return ", ".join(n if c == 1 else f"{c} x {n}" for n, c in counts.items()) or "none"


# ---------------------------------------------------------------- the work
def _singularity(record) -> dict[str, Any]:
    """What the page shows of one singular-point record (any object with ``.point``)."""
    point = np.asarray(getattr(record, "point", [np.nan] * 3), dtype=float).reshape(-1)[:3]
    name = getattr(record, "name", None)
    if name is None:  # records without a name: fall back on the classification's
        name = getattr(getattr(record, "classification", None), "name", None)
    try:
        text = record.describe() if hasattr(record, "describe") else str(record)
    except Exception as exc:  # a broken describe() must not lose the entry
        text = f"(describe() failed: {type(exc).__name__}: {exc})"
    return {"point": point.tolist(), "name": None if name is None else str(name),
            "branches": getattr(record, "branches", None), "text": text}


def run_entry(entry: Entry, out_dir: str | Path, size: int = 640,
              coarse: int | None = None, fine: int | None = None,
              timeout: float | None = None) -> dict[str, Any]:
    """Mesh one entry, write its PLY, OBJ, PNG and view data, and collect its report.

    Never raises for a problem with the entry: any exception is recorded
    (``error``, ``traceback``, and the stage it happened in) so that one
    bad surface does not stop the gallery.

    Parameters
    ----------
    entry : Entry
    out_dir : str or Path
        Where ``<slug>.ply``, ``<slug>.obj``, ``<slug>.png`` and ``<slug>.view.json``
        (the interactive view's data, :func:`singmesh.view.view_json`) go.
    size : int
        Picture side in pixels.
    coarse, fine : int, optional
        Override the entry's resolution (quick previews, tests).
    timeout : float, optional
        Seconds after which the entry is given up and recorded as failed
        (POSIX only; None or 0: no limit).  The entry's own ``timeout``
        field, if it has one, takes its place.

    Returns
    -------
    dict
        JSON-safe record: the entry's catalogue data, ``ok``, ``error``,
        ``stage``, ``time`` (meshing), ``render_time``, ``report`` (the
        mesh's report dict), ``report_text``, ``singularities``,
        ``comparison`` and ``files`` (names relative to ``out_dir``).
    """
    # Imported here (importing this module stays cheap) and before the time
    # limit is armed: an alarm in the middle of an import would leave a
    # half-initialised module behind in sys.modules.
    import singmesh  # noqa: F401
    import singmesh.render  # noqa: F401

    out = Path(out_dir)
    record: dict[str, Any] = {
        **{k: v for k, v in asdict(entry).items()},
        "ok": False, "error": None, "unread": None, "traceback": None, "stage": "mesh",
        "time": None, "render_time": None, "report": None, "report_text": None,
        "singularities": [], "comparison": None, "files": {}, "warnings": [],
    }
    # Warnings are the entry's: kept with it (and shown on its page) rather
    # than printed through the progress bar.
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            with time_limit(entry.timeout if entry.timeout is not None else timeout):
                _mesh_and_draw(entry, out, size, coarse, fine, record)
            record["ok"] = True
            record["stage"] = None
        except Exception as exc:  # every failure is the entry's, recorded, never the gallery's
            _record_error(record, exc)
    seen: dict[str, int] = {}
    for w in caught:
        text = f"{w.category.__name__}: {w.message} ({Path(w.filename).name}:{w.lineno})"
        seen[text] = seen.get(text, 0) + 1
    record["warnings"] = [t if n == 1 else f"{t} [{n} times]" for t, n in list(seen.items())[:20]]
    return json_safe(record)


def _record_error(record: dict[str, Any], exc: BaseException) -> None:
    """Put an exception (message, traceback, verdict "error") into an entry's record.

    An equation that does not read is the entry's input, not a failure of
    the mesher: its record gets ``unread`` with the reason, and no traceback.
    """
    import singmesh

    if record["stage"] == "read" and isinstance(exc, singmesh.SurfaceError):
        record["unread"] = str(exc)
    record["error"] = f"{type(exc).__name__}: {exc}"
    record["traceback"] = None if record.get("unread") else traceback.format_exc()
    if record["comparison"] is None:
        record["comparison"] = {"types": None, "forms": None, "branches": None, "euler": None,
                                "verdict": "error"}
    else:
        record["comparison"]["verdict"] = "error"


def _colouring(m, colour: str) -> dict[str, Any]:
    """``render_png``'s ``values`` and ``value_label`` for an entry's ``colour`` (none if empty)."""
    if not colour:
        return {}
    attribute, label = COLOURINGS[colour]
    return {"values": getattr(m, attribute), "value_label": label}


def _mesh_and_draw(entry: Entry, out: Path, size: int, coarse: int | None, fine: int | None,
                   record: dict[str, Any]) -> None:
    """The work of :func:`run_entry`; fills ``record`` as it goes, ``stage`` says how far."""
    import singmesh
    from singmesh.render import render_png
    from singmesh.view import view_json

    # A definition of a .defs file that does not read is the file's, not a failure.
    record["stage"] = "read" if entry.defs else "mesh"
    surface = entry.surface()
    record["stage"] = "mesh"
    t0 = time.perf_counter()
    m = singmesh.mesh(surface, box=entry.box, coarse=coarse or entry.coarse, fine=fine or entry.fine)
    record["time"] = float(m.stats.get("time", time.perf_counter() - t0))
    record["stage"] = "report"
    report = m.report()
    record["report"] = report
    record["report_text"] = m.report_text()
    sings = [_singularity(s) for s in (m.singularities or [])]
    record["singularities"] = sings
    record["comparison"] = compare(entry, [s["name"] or "?" for s in sings],
                                   report.get("euler_characteristic"), [s["branches"] for s in sings])
    record["stage"] = "write"
    for suffix in ("ply", "obj"):
        m.write(out / f"{entry.slug}.{suffix}")
        record["files"][suffix] = f"{entry.slug}.{suffix}"
    # The interactive view's data (singmesh.view), embedded in the entry's page by gallery_html.
    (out / f"{entry.slug}.view.json").write_text(view_json(m), encoding="utf-8")
    record["files"]["view"] = f"{entry.slug}.view.json"
    record["stage"] = "render"
    t1 = time.perf_counter()
    note = None
    if not len(m.faces):
        note = "empty mesh" + (" (singular points only)" if sings else "")
    if not len(m.faces) and m.singular_curves:
        note = "no triangle: the real surface is only a curve here"
    points = np.array([s["point"] for s in sings], dtype=float).reshape(-1, 3)
    record["curves"] = [{"type": c.type, "sheets": c.sheets, "vertices": len(c.points), "length": c.length}
                        for c in m.singular_curves]
    record["special_points"] = [{"kind": sp.kind, "point": sp.point.tolist()} for sp in m.special_points]
    render_png(out / f"{entry.slug}.png", m.vertices, m.faces, m.box, normals=m.normals,
               points=points, point_names=[s["name"] for s in sings], size=size, note=note,
               curves=[c.points for c in m.singular_curves], curve_names=[c.type for c in m.singular_curves],
               **_colouring(m, entry.colour))
    record["files"]["png"] = f"{entry.slug}.png"
    record["render_time"] = time.perf_counter() - t1
