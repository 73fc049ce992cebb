"""Shared pieces of the benchmark scripts: timing, marching cubes, tables.

Not a test module and not part of singmesh; the scripts in this folder
import it by name (they run with this folder first on ``sys.path``).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np


def best_time(fn, repeat: int):
    """Run ``fn`` once to warm up, then ``repeat`` times; the fastest.

    The warm-up run is discarded so that one-off costs (imports done
    lazily, first-call allocations, scikit-image's setup) are not charged
    to either mesher.  The minimum, not the mean, is reported: it is the
    least disturbed by other load on the machine.

    Returns
    -------
    seconds : float
    result
        What the fastest run of ``fn`` returned (so that timings stored
        in it, such as ``TriMesh.sample_time``, belong to that run).
    """
    fn()
    best, best_result = float("inf"), None
    for _ in range(max(repeat, 1)):
        t0 = time.perf_counter()
        result = fn()
        elapsed = time.perf_counter() - t0
        if elapsed < best:
            best, best_result = elapsed, result
    return best, best_result


def box_size(box) -> float:
    """Largest side of the box: the unit of the relative distances."""
    b = np.asarray(box, dtype=float).reshape(3, 2)
    return float(np.max(b[:, 1] - b[:, 0]))


@dataclass
class TriMesh:
    """Vertices and faces, whatever mesher made them."""

    vertices: np.ndarray
    faces: np.ndarray
    #: Seconds spent sampling F on the grid (marching cubes only).
    sample_time: float = 0.0


def marching_cubes(surface, box, res: int) -> TriMesh:
    """scikit-image's marching cubes on a (res + 1)^3 grid over ``box``.

    The sampling of F is part of the work (and of the time): F is
    evaluated once, vectorised, at every grid point with the same
    evaluator singmesh uses, ``surface(points)``.

    Parameters
    ----------
    surface : callable
        F on an (n, 3) array of points (e.g. a ``singmesh.Surface``).
    box : three (lo, hi) pairs
    res : int
        Cells per axis, the same number as singmesh's ``coarse``.
    """
    from skimage.measure import marching_cubes as _mc

    b = np.asarray(box, dtype=float).reshape(3, 2)
    axes = [np.linspace(lo, hi, res + 1) for lo, hi in b]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)
    # Timed apart: with a slow evaluator the sampling, not marching cubes
    # itself, is most of the time, and the tables say how much.
    t0 = time.perf_counter()
    values = surface(grid.reshape(-1, 3)).reshape(grid.shape[:-1])
    sample_time = time.perf_counter() - t0
    spacing = tuple((hi - lo) / res for lo, hi in b)
    verts, faces, _, _ = _mc(values, level=0.0, spacing=spacing)
    # marching_cubes works in index space scaled by spacing: shift to the box.
    return TriMesh(vertices=verts + b[:, 0], faces=faces, sample_time=sample_time)


def surface_distance(surface, vertices, box) -> float:
    """Largest first-order distance |F|/|grad F| of the vertices to F = 0.

    Relative to the box size, as in ``singmesh.Mesh.report``; at a vertex
    where grad F (nearly) vanishes, i.e. on a singular point, |F| itself
    is taken, also as the report does, so both meshers are measured by
    the same rule.
    """
    v = np.asarray(vertices, dtype=float)
    if not len(v):
        return 0.0
    size = box_size(box)
    residual = np.abs(surface(v))
    grad = np.linalg.norm(surface.gradient(v), axis=1)
    dist = residual / np.maximum(grad, 1e-300)
    dist = np.where(grad > 1e-8 * max(size, 1.0), dist, residual)
    return float(dist.max() / size)


# ---------------------------------------------------------------- tables
def format_table(columns, rows) -> str:
    """An aligned plain-text table with grouped column headers.

    Parameters
    ----------
    columns : list of (group, name, align)
        ``group`` spans consecutive columns with the same group label
        ("" for none); ``align`` is "<" or ">".
    rows : list of lists of str
        Already formatted cells; ``None`` draws a rule across the table.

    Returns
    -------
    str
    """
    widths = [len(name) for _, name, _ in columns]
    for row in rows:
        if row is None:
            continue
        for i, cell in enumerate(row):
            widths[i] = max(widths[i], len(cell))
    sep = "  "
    # Spans of equal consecutive group labels; widen the columns of a span
    # if the label does not fit over them.
    spans = []
    i = 0
    while i < len(columns):
        j = i
        while j + 1 < len(columns) and columns[j + 1][0] == columns[i][0]:
            j += 1
        spans.append((columns[i][0], i, j))
        i = j + 1
    for label, i, j in spans:
        span_width = sum(widths[i:j + 1]) + len(sep) * (j - i)
        extra = len(label) - span_width
        for c in range(i, j + 1):  # share the extra width out evenly
            widths[c] += extra // (j - i + 1) + (c - i < extra % (j - i + 1)) if extra > 0 else 0
    group_cells = []
    for label, i, j in spans:
        span_width = sum(widths[i:j + 1]) + len(sep) * (j - i)
        group_cells.append(label.center(span_width) if label else " " * span_width)
    lines = []
    if any(label for label, _, _ in spans):
        lines.append(sep.join(group_cells).rstrip())
    lines.append(sep.join(f"{name:{align}{w}}" for (_, name, align), w in zip(columns, widths)).rstrip())
    rule = "-" * len(sep.join(" " * w for w in widths))
    lines.append(rule)
    for row in rows:
        if row is None:
            lines.append(rule)
            continue
        lines.append(sep.join(f"{cell:{align}{w}}" for cell, (_, _, align), w
                              in zip(row, columns, widths)).rstrip())
    return "\n".join(lines)


def sci(value: float) -> str:
    """A distance or residual, 1.2e-03 style."""
    return f"{value:.1e}"


def print_footer(res, notes=()):
    """The explanation printed under both comparison tables."""
    print()
    print("mc = skimage.measure.marching_cubes on a (res+1)^3 grid, sampling included; "
          "ratio = singmesh time / mc time.")
    print("mc F = the part of mc's time spent sampling F with singmesh's Surface evaluator "
          "(skimage's marching cubes is the rest).")
    for line in notes:
        print(line)
    print(f"One grid cell is 1/res of the box: {', '.join(sci(1 / r) for r in res)}.")


def parse_args(description: str, argv=None):
    """The options both comparison scripts take."""
    import argparse

    p = argparse.ArgumentParser(description=description.split("\n\n")[0])
    p.add_argument("--res", type=int, nargs="+", default=[32, 64],
                   help="boxes per axis: singmesh's coarse, marching cubes' cells (default 32 64)")
    p.add_argument("--repeat", type=int, default=3,
                   help="timed runs after one warm-up; the best is shown (default 3)")
    p.add_argument("--fine", type=int, default=256,
                   help="singmesh's finest subdivision, at least --res (default 256)")
    return p.parse_args(argv)


#: The columns both comparison tables start with: (group, name, alignment).
TIME_COLUMNS = [
    ("", "surface", "<"), ("", "res", ">"),
    ("time [s]", "singmesh", ">"), ("time [s]", "mc", ">"), ("time [s]", "mc F", ">"),
    ("time [s]", "ratio", ">"),
    ("vertices", "singmesh", ">"), ("vertices", "mc", ">"),
]
