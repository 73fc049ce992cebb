"""CPU time of ElementarySurface's box and line methods on the gyroid (issue #10).

Run with OPENBLAS_NUM_THREADS=1:  .venv/bin/python benchmarks/bench_elementary.py
"""

import time

import numpy as np

from singmesh.elementary import ElementarySurface

GYROID = "sin(x)*cos(y) + sin(y)*cos(z) + sin(z)*cos(x)"


def main() -> None:
    s = ElementarySurface.parse(GYROID)
    box = np.array([[-3.0, 3.3]] * 3)
    t = time.process_time()
    data = s.enclose(box)
    for _ in range(5):
        data = s.split(data).reshape((-1,) + data.shape[1:])
    t_split = time.process_time() - t
    t = time.process_time()
    empty = s.excludes_zero(data)
    t_empty = time.process_time() - t
    kept = data[~empty]
    t = time.process_time()
    axis = s.simple_axis(kept)
    t_simple = time.process_time() - t
    print(f"32^3 = {len(data)} boxes: split {t_split:.3f} s, excludes_zero {t_empty:.3f} s "
          f"({len(kept)} kept), simple_axis {t_simple:.3f} s ({(axis >= 0).sum()} simple)")
    rng = np.random.default_rng(0)
    for n in (100_000,):
        cell = 6.3 / 256
        for a in range(1):
            fixed = -3.0 + cell * rng.integers(0, 257, (n, 2))
            start = -3.0 + cell * rng.integers(0, 256, n)
            s0, s1 = start, start + cell * rng.choice([1, 2, 4, 8], n)
            t = time.process_time()
            row, root = s.line_roots(a, fixed, s0, s1)
            print(f"line_roots on {n} segments (1 to 8 fine cells): {time.process_time() - t:.3f} s, {len(root)} roots")
            t = time.process_time()
            row, root = s.line_roots(a, fixed[:2000], np.full(2000, -3.0), np.full(2000, 3.3))
            print(f"line_roots on 2000 whole lattice lines: {time.process_time() - t:.3f} s, {len(root)} roots")


if __name__ == "__main__":
    main()
