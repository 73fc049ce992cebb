"""How many of SingSurf's own definitions read, and mesh, in singmesh.

SingSurf's public repository (SingSurfGPL) ships its models as definition
files, ``defs/asurf.defs`` and ``defs/cubics.defs``.  They are not part of
singmesh; point this script at a copy::

    .venv/bin/python benchmarks/singsurf_defs.py PATH/asurf.defs PATH/cubics.defs [--mesh]
        [--timeout 60] [--jobs 2] [--coarse 32] [--fine 256] [--json OUT]

Definitions repeated within or across the files (same equation text and
parameters) are counted once.  For each distinct implicit surface it
reports whether it reads (``Definition.surface()``) and, with ``--mesh``,
whether ``Definition.mesh()`` finishes within the time limit, with the
mesh's open edges off the box, non-manifold edges and singular points.
The refusals are listed with their reasons.  Not a test: it prints figures.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import signal
import sys
import time
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path


def _alarm(signum, frame):
    raise TimeoutError


def _mesh_one(task):
    """Mesh one definition in a worker; a dict of figures (never raises)."""
    path, index, timeout, coarse, fine = task
    import singmesh

    d = singmesh.read_definitions(path)[index]
    signal.signal(signal.SIGALRM, _alarm)
    signal.setitimer(signal.ITIMER_REAL, timeout)
    t0 = time.perf_counter()
    try:
        m = d.mesh(coarse=coarse, fine=fine)
        r = m.report()
        return {"ok": True, "time": time.perf_counter() - t0, "faces": r["faces"],
                "open_off_box": r["boundary_edges_off_box"], "non_manifold": r["non_manifold_edges"],
                "singular_points": r["singular_points"],
                "not_isolated": bool(m.stats.get("singular_locus_not_isolated"))}
    except TimeoutError:
        return {"ok": False, "time": timeout, "error": f"no mesh within {timeout:g} s"}
    except Exception as exc:  # a benchmark records every failure and goes on
        return {"ok": False, "time": time.perf_counter() - t0, "error": f"{type(exc).__name__}: {exc}"}
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("files", nargs="+", help="SingSurf .defs files")
    p.add_argument("--mesh", action="store_true", help="also mesh every definition that reads")
    p.add_argument("--timeout", type=float, default=60.0, help="seconds per mesh (default 60)")
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument("--coarse", type=int, default=32)
    p.add_argument("--fine", type=int, default=256)
    p.add_argument("--json", help="write every record here")
    args = p.parse_args(argv)

    import singmesh

    total, records, seen = 0, [], set()
    for path in args.files:
        for index, d in enumerate(singmesh.read_definitions(path)):
            total += 1
            key = (d.type, d.equation, tuple(sorted(d.parameters.items())))
            if key in seen:
                continue
            seen.add(key)
            rec = {"file": Path(path).name, "index": index, "path": path, "name": d.name, "line": d.line}
            try:
                s = d.surface()
                rec.update(reads=True, degree=s.degree)
            except singmesh.SurfaceError as exc:
                rec.update(reads=False, reason=str(exc))
            records.append(rec)
    reads = [r for r in records if r["reads"]]
    print(f"{total} definitions in {len(args.files)} file(s), {len(records)} distinct: "
          f"{len(reads)} read, {len(records) - len(reads)} do not")
    degrees = Counter(r["degree"] for r in reads)
    print("degrees of those that read: " + ", ".join(f"{k}: {v}" for k, v in sorted(degrees.items())))
    for r in records:
        if not r["reads"]:
            print(f"  does not read: {r['reason']}")

    if args.mesh:
        tasks = [(r["path"], r["index"], args.timeout, args.coarse, args.fine) for r in reads]
        ctx = multiprocessing.get_context("spawn")
        t0 = time.perf_counter()
        with ProcessPoolExecutor(max_workers=args.jobs, mp_context=ctx) as pool:
            for r, res in zip(reads, pool.map(_mesh_one, tasks)):
                r["mesh"] = res
                print(f"  {'meshed' if res['ok'] else 'FAILED'} {res['time']:7.2f} s  {r['name']}"
                      + ("" if res["ok"] else f": {res['error'][:160]}"), file=sys.stderr)
        wall = time.perf_counter() - t0
        ok = [r for r in reads if r["mesh"]["ok"]]
        clean = [r for r in ok if not r["mesh"]["open_off_box"] and not r["mesh"]["non_manifold"]]
        curves = [r for r in ok if r["mesh"]["not_isolated"]]
        times = sorted(r["mesh"]["time"] for r in ok)
        print(f"meshed {len(ok)} of {len(reads)} within {args.timeout:g} s each "
              f"(wall {wall:.0f} s with {args.jobs} jobs); median {times[len(times) // 2]:.2f} s, "
              f"max {times[-1]:.1f} s" if times else "meshed none")
        print(f"  without open edges off the box or non-manifold edges: {len(clean)}; "
              f"with a curve of singular points reported: {len(curves)}")
        for r in reads:
            if not r["mesh"]["ok"]:
                print(f"  not meshed: {r['file']}, line {r['line']} ({r['name']!r}): {r['mesh']['error'][:200]}")
    if args.json:
        Path(args.json).write_text(json.dumps(records, indent=1), encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
