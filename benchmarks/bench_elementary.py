"""CPU time of ElementarySurface's box and line methods (issue #10).

The octree's use of them is emulated: every box split down to the
coarse level 5 (32^3) with empty boxes pruned (excludes_zero), then
simple boxes kept as leaves (simple_axis) and the others split down to
the fine level 8 (256); the singular-point search (may_vanish on F and
its three derivatives) to level 8; line_roots on random lattice
segments.  Run with OPENBLAS_NUM_THREADS=1:

    .venv/bin/python benchmarks/bench_elementary.py
"""

import time

import numpy as np

from singmesh.elementary import ElementarySurface

_H = "1/(1+exp(-20*({})))"
_F = "0.25-((x-0.35)^2+y^2+z^2)"
_G = "0.25-((x+0.35)^2+y^2+z^2)"
SURFACES = {
    "gyroid": ("sin(x)*cos(y) + sin(y)*cos(z) + sin(z)*cos(x)", [[-3.0, 3.3]] * 3),
    "schwarz-P": ("cos(x)+cos(y)+cos(z)", [[-3.2, 3.3]] * 3),
    "sqrt-torus": ("(sqrt(x^2+y^2)-1)^2 + z^2 - 0.25", [[-1.6, 1.7]] * 3),
    "sigmoid-union": (f"{_H.format(_F)} + {_H.format(_G)} - {_H.format(_F)}*{_H.format(_G)} - 1/2",
                      [[-1.1, 1.2]] * 3),
    "half-sphere-max": ("max(x^2+y^2+z^2-1, -z)", [[-1.3, 1.4]] * 3),
    "half-sphere-R": ("(x^2+y^2+z^2-1) + (-z) + sqrt((x^2+y^2+z^2-1)^2 + z^2)", [[-1.3, 1.4]] * 3),
    "cube": ("max(abs(x),abs(y),abs(z)) - 0.7", [[-1.0, 1.1]] * 3),
    "sin^2 node": ("sin(x)^2+sin(y)^2-sin(z)^2", [[-1.0, 1.1]] * 3),
}


def octree(s, box, coarse=5, fine=8):
    data = s.enclose(np.asarray(box, float))
    leaves = 0
    for level in range(1, fine + 1):
        data = s.split(data).reshape((-1,) + data.shape[1:])
        data = data[~s.excludes_zero(data)]
        if level >= coarse:
            simple = s.simple_axis(data) >= 0
            leaves += int(simple.sum())
            data = data[~simple]
    return leaves, len(data)


def candidates(s, box, level=8):
    data = s.enclose(np.asarray(box, float))
    for _ in range(level):
        data = s.split(data).reshape((-1,) + data.shape[1:])
        data = data[s.may_vanish(data, (0, 1, 2))]
    return len(data)


def main() -> None:
    for name, (text, box) in SURFACES.items():
        s = ElementarySurface.parse(text)
        t = time.process_time()
        leaves, rest = octree(s, box)
        t_oct = time.process_time() - t
        t = time.process_time()
        cand = candidates(s, box)
        t_cand = time.process_time() - t
        print(f"{name:16s} octree 32..256: {leaves:6d} simple leaves, {rest:5d} not simple at 256, "
              f"{t_oct:.2f} s CPU; may_vanish to level 8: {cand:5d} boxes, {t_cand:.2f} s")

    s = ElementarySurface.parse(SURFACES["gyroid"][0])
    box = np.array(SURFACES["gyroid"][1])
    t = time.process_time()
    data = s.enclose(box)
    for _ in range(5):
        data = s.split(data).reshape((-1,) + data.shape[1:])
    t_split = time.process_time() - t
    t = time.process_time()
    empty = s.excludes_zero(data)
    t_empty = time.process_time() - t
    t = time.process_time()
    axis = s.simple_axis(data[~empty])
    t_simple = time.process_time() - t
    print(f"gyroid, 32^3 = {len(data)} boxes: split {t_split:.3f} s, excludes_zero {t_empty:.3f} s "
          f"({(~empty).sum()} kept), simple_axis {t_simple:.3f} s ({(axis >= 0).sum()} simple)")
    rng = np.random.default_rng(0)
    n = 100_000
    cell = 6.3 / 256
    fixed = -3.0 + cell * rng.integers(0, 257, (n, 2))
    start = -3.0 + cell * rng.integers(0, 256, n)
    s0, s1 = start, start + cell * rng.choice([1, 2, 4, 8], n)
    t = time.process_time()
    row, root = s.line_roots(0, fixed, s0, s1)
    print(f"gyroid line_roots on {n} lattice segments (1 to 8 fine cells): {time.process_time() - t:.3f} s, {len(root)} roots")
    t = time.process_time()
    row, root = s.line_roots(0, fixed[:3000], np.full(3000, -3.0), np.full(3000, 3.3))
    print(f"gyroid line_roots on 3000 whole lattice lines: {time.process_time() - t:.3f} s, {len(root)} roots")


if __name__ == "__main__":
    main()
