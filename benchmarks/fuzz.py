"""A thousand random surfaces through an independent judge (``make fuzz``).

The cases and the judge are in ``tests/fuzzcases.py`` (the fast sample of
``tests/test_fuzz.py`` uses them too): random polynomials of degree 1 to 6
with rational or 15-digit decimal coefficients, products of two random
factors, sums with powers of the sphere; boxes symmetric about 0, [-1, 1]^3
and random.  This prints figures (cases, clean, empty and right, refused,
failures by class, time) and one line per failing case; it never asserts
on time.

Run from the repository root::

    .venv/bin/python benchmarks/fuzz.py [--n 1000] [--seed 1] [--jobs 2]
        [--coarse 8] [--fine 64] [--only NAME,...]

This is a benchmark that prints figures, not a test.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

import fuzzcases  # noqa: E402


def _run(args):
    seed, index, coarse, fine = args
    case = fuzzcases.make_case(seed, index)
    t0 = time.process_time()
    try:
        verdict = fuzzcases.judge(case, coarse, fine)
    except Exception as e:  # noqa: BLE001 - the judge's own failure is shown, not hidden
        verdict = fuzzcases.Verdict(case.name, "fail", ["judge-error"], f"{type(e).__name__}: {e}")
    return case, verdict, time.process_time() - t0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--coarse", type=int, default=8)
    ap.add_argument("--fine", type=int, default=64)
    ap.add_argument("--only", default="", help="comma-separated case names or indices")
    a = ap.parse_args(argv)
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    indices = range(a.n)
    if a.only:
        indices = [int(s.split("-")[1]) if s.startswith("s") else int(s) for s in a.only.split(",")]
    jobs = [(a.seed, i, a.coarse, a.fine) for i in indices]
    t0 = time.perf_counter()
    if a.jobs > 1:
        with ProcessPoolExecutor(a.jobs) as ex:
            results = list(ex.map(_run, jobs, chunksize=4))
    else:
        results = [_run(j) for j in jobs]
    wall = time.perf_counter() - t0
    status = Counter(v.status for _, v, _ in results)
    classes = Counter(c for _, v, _ in results for c in v.failures)
    by_kind = Counter((c.kind, v.status) for c, v, _ in results)
    mesh_cpu = sum(v.seconds for _, v, _ in results)
    cpu = sum(t for _, _, t in results)
    print(f"fuzz seed {a.seed}: {len(results)} cases, coarse {a.coarse}, fine {a.fine}")
    print(f"  clean {status['clean']}, empty and right {status['empty']}, refused {status['refused']}, "
          f"failed {status['fail']}")
    notes = Counter(n for _, v, _ in results for n in v.notes)
    for note, n in sorted(notes.items()):
        print(f"  {note}: {n} cases")
    for cls, n in sorted(classes.items(), key=lambda t: (-t[1], t[0])):
        print(f"  failure class {cls}: {n}")
    for kind in fuzzcases.KINDS:
        print(f"  {kind:9s} " + ", ".join(f"{s} {by_kind[(kind, s)]}" for s in ("clean", "empty", "refused", "fail")))
    print(f"  time: wall {wall:.1f} s on {a.jobs} jobs; meshing {mesh_cpu:.1f} s, meshing + judging "
          f"{cpu:.1f} s CPU (noisy on a shared machine)")
    for case, v, _ in results:
        if v.status in ("fail", "refused"):
            box = ", ".join(f"({lo:g}, {hi:g})" for lo, hi in case.box)
            print(f"{v.status.upper():7s} {case.name}: {case.text}  box [{box}]  -- {v.detail}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
