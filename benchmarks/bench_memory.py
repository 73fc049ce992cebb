"""Peak memory of ``singmesh.mesh`` against coarse / fine, and the budget's estimate.

Each case runs in a fresh process (``ru_maxrss`` is a high-water mark of
the whole process): the resident size after the imports, the peak during
``mesh()``, the leaves of the octree, and what :mod:`singmesh.memory`'s
model says of the same run (its estimate from the boxes counted level by
level, the way the check in ``mesh()`` sees them).  The Barth sextic is run
at the defaults (coarse 32, fine 256) and at coarse 64 / fine 512, with a
few other points; the sphere, Cayley's cubic, the Whitney umbrella (fine
boxes along its singular curve) and the gyroid (not a polynomial) for
comparison.

Usage::

    .venv/bin/python benchmarks/bench_memory.py [--only barth] [--points 32/256 64/512]

Timings and sizes vary with the machine's load and its allocator; the
peak is what the operating system reports (Linux: kilobytes).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import nodes  # noqa: E402

SURFACES = {
    "sphere": ("x^2 + y^2 + z^2 - 1", ((-1.2, 1.2),) * 3),
    "cayley": (nodes.SURFACES["cayley"].text, nodes.SURFACES["cayley"].box),
    "barth": (nodes.SURFACES["barth"].text, nodes.SURFACES["barth"].box),
    "umbrella": ("x^2 - y^2 z", ((-1.0, 1.0),) * 3),
    "gyroid": ("sin(x) cos(y) + sin(y) cos(z) + sin(z) cos(x)", ((-3.0, 3.3),) * 3),
}
POINTS = {
    "sphere": ["32/256", "64/512", "128/1024"],
    "cayley": ["32/256", "64/512"],
    "barth": ["16/128", "32/256", "64/256", "64/512", "128/512"],
    "umbrella": ["32/256", "32/1024"],
    "gyroid": ["32/256", "64/512"],
}

CHILD = r"""
import json, resource, sys, time
import singmesh
from singmesh import memory
text, box, coarse, fine = json.loads(sys.argv[1])
before = memory.resident_bytes()
t0 = time.perf_counter()
m = singmesh.mesh(text, box, coarse=coarse, fine=fine)
elapsed = time.perf_counter() - t0
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
print(json.dumps({"before": before, "peak": peak, "leaves": m.stats["leaves"], "faces": len(m.faces),
                  "estimate": m.stats["memory_estimate"], "time": elapsed}))
"""


def run(name: str, coarse: int, fine: int) -> dict:
    text, box = SURFACES[name]
    r = subprocess.run([sys.executable, "-c", CHILD, json.dumps([text, box, coarse, fine])],
                       capture_output=True, text=True)
    if r.returncode:
        raise RuntimeError(r.stderr.strip().splitlines()[-1])
    return json.loads(r.stdout.strip().splitlines()[-1])


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--only", nargs="+", choices=sorted(SURFACES), default=list(SURFACES))
    p.add_argument("--points", nargs="+", metavar="COARSE/FINE", help="instead of each surface's own list")
    args = p.parse_args()
    mb = 1 << 20
    print(f"{'surface':8s} {'coarse/fine':>11s} {'leaves':>8s} {'faces':>8s} {'imports':>8s} {'peak':>8s} "
          f"{'mesh()':>8s} {'estimate':>8s} {'est/peak':>8s} {'B/leaf':>7s} {'time':>7s}")
    for name in args.only:
        for point in args.points or POINTS[name]:
            coarse, fine = map(int, point.split("/"))
            r = run(name, coarse, fine)
            grown = r["peak"] - r["before"]
            print(f"{name:8s} {point:>11s} {r['leaves']:8d} {r['faces']:8d} {r['before'] / mb:7.0f}M "
                  f"{r['peak'] / mb:7.0f}M {grown / mb:7.0f}M {r['estimate'] / mb:7.0f}M {r['estimate'] / r['peak']:8.2f} "
                  f"{grown / max(r['leaves'], 1):7.0f} {r['time']:6.1f}s", flush=True)


if __name__ == "__main__":
    main()
