"""Build the singmesh gallery: mesh every catalogue entry, picture it, write a static site.

Usage::

    python gallery/generate.py [--out DIR] [--only NAME ...] [--jobs N] [--size PX]
                               [--catalogue PATH | --defs FILE] [--coarse N] [--fine N] [--timeout SECONDS]
                               [--strict] [--quiet] [--scheduler local|ADDRESS]

For each entry of ``catalogue.toml`` (or the entries whose names contain one
of the ``--only`` substrings, case-insensitive) this meshes the surface,
writes ``DIR/<slug>.ply``, ``.obj`` and ``.png``, and compares the singular
points and Euler characteristic found with the catalogue.  Then it writes
``DIR/index.html`` (thumbnail grid), ``DIR/<slug>.html`` (one page per
entry), ``DIR/style.css`` and ``DIR/report.json``.  A failing entry is
recorded with its error and does not stop the others.

With ``--defs FILE`` a SingSurf definition file is the catalogue: one page
per definition, grouped as the file groups them, each on its own box with
its parameters; a definition that does not read gets its line in the index
with the reason.

With ``--scheduler`` the entries are meshed on Dask (``local``: a
LocalCluster of ``--jobs`` worker processes on this machine; or a running
scheduler's address); the files are the same bytes as a local run's.  The
``--timeout`` limit needs the main thread of a process (SIGALRM): Dask
workers run the entries in their own threads and do not apply it.

Exit status: 0 when the site was written (even if entries failed or differ
from the catalogue; ``--strict`` makes failed entries exit 1), 2 for bad
arguments or an unreadable catalogue.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import json
import platform
import sys
import time
from functools import partial
from pathlib import Path
from typing import Any, Sequence

HERE = Path(__file__).resolve().parent
# The helper modules sit next to this script.  runpy (``singmesh gallery``)
# does not put the script's folder on sys.path, and spawned worker processes
# inherit sys.path from here, so both need this.
if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))

import gallery_lib  # noqa: E402
from gallery_lib import CatalogueError, load_catalogue, load_definitions, run_entry, select  # noqa: E402

from singmesh.errors import SurfaceError  # noqa: E402
from singmesh.extras import require  # noqa: E402
from singmesh.files import json_safe, writable_folder  # noqa: E402

DEFAULT_OUT = HERE / "out"


def check_extras(scheduler: str | None = None) -> None:
    """MissingExtraError naming the pip install when a package the gallery uses is missing."""
    require("the gallery", ["matplotlib", "tqdm"] + (["tomli"] if sys.version_info < (3, 11) else []),
            extra="gallery")
    if scheduler:
        require("--scheduler (Dask)", ["dask", "distributed"], extra="dask")


def _power_of_two(text: str) -> int:
    n = int(text)
    if n < 1 or n & (n - 1):
        raise argparse.ArgumentTypeError(f"{text} is not a power of two")
    return n


def _positive(text: str) -> int:
    n = int(text)
    if n < 1:
        raise argparse.ArgumentTypeError(f"{text} is not a positive integer")
    return n


def build_parser() -> argparse.ArgumentParser:
    """The command-line interface (also used by ``singmesh gallery``)."""
    p = argparse.ArgumentParser(
        description="Mesh the gallery catalogue and write a static HTML gallery.")
    p.add_argument("--out", default=str(DEFAULT_OUT), metavar="DIR",
                   help=f"output folder (default {DEFAULT_OUT})")
    p.add_argument("--only", nargs="+", metavar="NAME",
                   help="only entries whose names contain one of these (case-insensitive)")
    p.add_argument("--jobs", type=_positive, default=1, metavar="N",
                   help="mesh entries in N processes (default 1)")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="mesh the entries on Dask: 'local' (a LocalCluster of --jobs worker processes) or "
                        "the address of a running scheduler, e.g. tcp://10.0.0.5:8786 (pip install "
                        "'singmesh[dask]'; the results are the same bytes)")
    p.add_argument("--size", type=_positive, default=640, metavar="PX",
                   help="picture width and height in pixels (default 640)")
    p.add_argument("--catalogue", default=str(gallery_lib.DEFAULT_CATALOGUE), metavar="PATH",
                   help="catalogue TOML file (default gallery/catalogue.toml)")
    p.add_argument("--defs", metavar="FILE",
                   help="a SingSurf .defs file as the catalogue: one page per definition, grouped as "
                        "the file groups them (instead of --catalogue)")
    p.add_argument("--coarse", type=_power_of_two, metavar="N",
                   help="override every entry's coarse resolution (quick previews)")
    p.add_argument("--fine", type=_power_of_two, metavar="N",
                   help="override every entry's fine resolution")
    p.add_argument("--timeout", type=float, default=300.0, metavar="SECONDS",
                   help="give an entry up after this long and record it as failed "
                        "(default 300; 0: no limit; POSIX only)")
    p.add_argument("--strict", action="store_true", help="exit 1 if any entry failed")
    p.add_argument("--quiet", action="store_true", help="no progress bar and no summary")
    return p


def _failure(entry: gallery_lib.Entry, message: str) -> dict[str, Any]:
    """The record of an entry whose worker process never returned a result."""
    from dataclasses import asdict

    return json_safe({
        **asdict(entry), "ok": False, "error": message, "unread": None, "traceback": None, "stage": "worker",
        "time": None, "render_time": None, "report": None, "report_text": None,
        "singularities": [], "files": {}, "warnings": [],
        "comparison": {"types": None, "forms": None, "branches": None, "euler": None, "verdict": "error"},
    })


def run_all(entries: Sequence[gallery_lib.Entry], out: Path, *, jobs: int = 1, size: int = 640,
            coarse: int | None = None, fine: int | None = None, timeout: float | None = None,
            progress: bool = True, scheduler: str | None = None) -> list[dict]:
    """Run every entry, in parallel processes if ``jobs > 1``, or on Dask with ``scheduler``.

    ``scheduler``: ``"local"`` (a LocalCluster of ``jobs`` workers) or a
    Dask scheduler's address (:func:`singmesh.parallel.map_ordered`); the
    files written are the same bytes as without it.

    Returns
    -------
    list of dict
        One record per entry, in the order of ``entries`` whatever order
        the processes finish in.
    """
    from tqdm import tqdm

    from singmesh.parallel import map_ordered

    bar = tqdm(total=len(entries), desc="gallery", unit="surface", disable=not progress,
               dynamic_ncols=True)

    def done(i: int, result) -> None:
        bar.set_postfix_str(entries[i].name, refresh=False)
        bar.update()

    # An absolute folder: a Dask worker need not run in this one.
    work = partial(run_entry, out_dir=Path(out).resolve(), size=size, coarse=coarse, fine=fine, timeout=timeout)
    try:
        # Dask workers import the entries' function from gallery_lib, which
        # is not part of the installed package: it is sent to them.
        results = map_ordered(work, entries, jobs=jobs, scheduler=scheduler, on_done=done, capture=True,
                              upload=[HERE / "gallery_lib.py"] if scheduler else ())
    finally:
        bar.close()
    # An exception here is the worker's death (crash, out of memory):
    # run_entry records every failure of the entry itself.
    return [_failure(e, f"{type(r).__name__}: {r}") if isinstance(r, BaseException)
            else r if r is not None else _failure(e, "not run") for r, e in zip(results, entries)]


def _meta(jobs: int, total_time: float, catalogue: Path) -> dict[str, Any]:
    try:
        from importlib.metadata import version

        sm_version = version("singmesh")
    except Exception:  # not installed as a distribution: a source checkout
        sm_version = "(source)"
    return {
        "generated": _dt.datetime.now().astimezone().strftime("%Y-%m-%d %H:%M %Z").strip(),
        "singmesh_version": sm_version,
        "python": platform.python_version(),
        "platform": platform.platform(),
        "jobs": jobs,
        "total_time": total_time,
        "catalogue": str(catalogue),
    }


def main(argv: Sequence[str] | None = None) -> int:
    """Build the gallery.

    Parameters
    ----------
    argv : sequence of str, optional
        Arguments without the program name; ``sys.argv[1:]`` if None.

    Returns
    -------
    int
        Exit status (see the module docstring).
    """
    args = build_parser().parse_args(None if argv is None else list(argv))
    try:
        check_extras(args.scheduler)
    except SurfaceError as exc:
        print(f"gallery: error: {exc}", file=sys.stderr)
        return 2
    catalogue = Path(args.defs or args.catalogue)
    try:
        groups, entries = load_definitions(catalogue) if args.defs else load_catalogue(catalogue)
    except CatalogueError as exc:
        print(f"gallery: error: {exc}", file=sys.stderr)
        return 2
    chosen = select(entries, args.only)
    if not chosen:
        print(f"gallery: error: no catalogue entry matches {' '.join(args.only or [])!r}", file=sys.stderr)
        return 2
    try:
        out = writable_folder(args.out)  # before the entries are meshed, not after
    except SurfaceError as exc:
        print(f"gallery: error: {exc}", file=sys.stderr)
        return 2

    t0 = time.perf_counter()
    records = run_all(chosen, out, jobs=args.jobs, size=args.size, coarse=args.coarse,
                      fine=args.fine, timeout=args.timeout, progress=not args.quiet, scheduler=args.scheduler)
    total = time.perf_counter() - t0

    from gallery_html import counts, write_site

    meta = _meta(args.jobs, total, catalogue)
    meta["selection"] = args.only or []
    (out / "report.json").write_text(
        json.dumps(json_safe({"meta": meta, "entries": records}), indent=1, allow_nan=False),
        encoding="utf-8")
    index = write_site(out, records, groups, meta)

    c = counts(records)
    if not args.quiet:
        print(f"{len(records)} surfaces in {total:.1f} s: {c['match']} match, {c['mismatch']} mismatch, "
              f"{c['unsupported']} unsupported, {c['meshed']} meshed without reference, "
              f"{c['unread']} do not read, {c['error']} failed")
        for r in records:
            if r.get("error") and not r.get("unread"):
                print(f"  failed: {r['name']}: {r['error']}")
        print(f"open {index.resolve().as_uri()}")
    return 1 if args.strict and c["error"] else 0


if __name__ == "__main__":
    sys.exit(main())
