"""Surfaces with hundreds of nodes: time per singular point, all of them vertices.

For each surface of ``nodes.LARGE`` (the Barth decic, 300 real nodes in
[-2, 2]^3; the Endrass octic, 144 in [-3, 3]^3, its 168 nodes less the 24
at infinity; Labs' septic, all 99 real nodes in [-12, 12]^3) and, for the scaling, the
smaller ones of ``nodes.SURFACES``, this meshes at singmesh's defaults and
prints: the time, the time per node, how many of the true nodes (found by
``nodes.py`` without singmesh) are mesh vertices with two triangle fans
(two cones), and the open and non-manifold edges.

    .venv/bin/python benchmarks/bench_many_nodes.py [--only barth10 endrass] [--repeat 1]

This is a benchmark that prints figures, not a test.  The reference nodes
of the decic take about a minute to find.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

import nodes
import singmesh

# The fan count of the tests' independent mesh checks.
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
from meshcheck import fans_at  # noqa: E402

#: Starting points per axis for the independent node search.
STARTS = {"barth10": 48, "endrass": 48, "labs7": 64, "chmutov7": 32, "chmutov8": 32, "chmutov9": 32, "chmutov10": 32}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--only", nargs="+", help="keys of nodes.SURFACES / nodes.LARGE")
    p.add_argument("--repeat", type=int, default=1, help="timed runs (the fastest is shown)")
    args = p.parse_args(argv)
    table = {**nodes.SURFACES, **nodes.LARGE}
    keys = args.only or list(table)
    print(f"{'surface':15s} {'nodes':>5s} {'time':>8s} {'per node':>9s} {'vertices w/ 2 fans':>19s} "
          f"{'open':>5s} {'non-manifold':>12s} {'reported':>8s}")
    for key in keys:
        s = table[key]
        t0 = time.perf_counter()
        true = nodes.find_nodes(s.expr, s.box, starts=STARTS.get(key, 16)) if key in nodes.LARGE \
            else nodes.true_nodes(key)
        t_ref = time.perf_counter() - t0
        if len(true) != s.expected:
            print(f"{s.name}: the reference search found {len(true)} nodes, expected {s.expected}", file=sys.stderr)
        best, m = float("inf"), None
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            m = singmesh.mesh(s.text, s.box)
            best = min(best, time.perf_counter() - t0)
        size = float(np.max(np.ptp(np.array(s.box, float), axis=1)))
        d, idx = cKDTree(m.vertices).query(true)
        ok = sum(1 for dist, i in zip(d, idx) if dist <= 1e-9 * size and fans_at(m.faces, i) == 2)
        r = m.report()
        print(f"{s.name:15s} {len(true):5d} {best:7.2f}s {1000 * best / max(len(true), 1):7.1f}ms "
              f"{ok:>12d}/{len(true):<6d} {r['boundary_edges_off_box']:5d} {r['non_manifold_edges']:12d} "
              f"{len(m.singularities):8d}   (reference nodes: {t_ref:.1f} s)", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
