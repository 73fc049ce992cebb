"""The memory budget of :func:`singmesh.mesh`: an estimate checked as the octree grows.

Model
-----
Almost all of a mesh's memory is per box of the octree: each box keeps its
bounds of F (``Surface.enclose`` data: the Bernstein tensor of the
polynomial on the box, (degree + 1)^3 doubles, 2.7 kB for a sextic; 96
bytes of intervals for a non-polynomial F), and the later stages (the
events on its edges, the links on its faces, its polygons, the vertices and
triangles made of them, the shaping pass) cost about the same for each leaf
whatever the surface.  So the peak resident size is estimated as::

    peak = resident size when mesh() starts
           + boxes * (DATA_COPIES * data bytes per box + PER_LEAF)
           + FIXED

where ``boxes`` is the number of leaves the subdivision is heading for.
The subdivision counts its boxes level by level (``subdivide``'s
``budget``): before a level is split, the boxes so far are the leaves
made and the frontier's children to come, about ``SURFACE_CHILDREN`` of
each box's 8 (a surface crosses about 4 of the 8 halves of a box it
crosses); while the levels are uniform (below ``coarse``) the frontier
grows by that factor per level down to ``coarse``.  The constants come
from ``benchmarks/bench_memory.py`` (sphere, Cayley's cubic, the Barth
sextic at coarse 16 to 128, fine 128 to 1024), where the estimate is
1.04 to 1.2 times the measured peak (13 runs, never below it).

A request whose estimate exceeds the limit is refused with one line
(:class:`MemoryBudgetError`) before the boxes are made: the limit is the
memory the machine has available (``MemAvailable`` of ``/proc/meminfo``,
else ``os.sysconf``) plus what the process holds already, or the caller's
``max_memory`` if lower.  The check is a few integer operations per level.
"""

from __future__ import annotations

import math
import os
import re

import numpy as np

from .errors import SurfaceError

#: Copies of a box's ``data`` alive at the peak: the leaves' own, the
#: children of a split (made a chunk at a time, pruned at once), and the
#: stages that gather the leaves' data again (faces, edges).
DATA_COPIES = 2.5

#: Bytes per leaf of everything else: corners, levels and keys of the
#: octree, events (several per leaf), links, cycles, polygons, vertices,
#: triangles, the shaping pass's arrays.  Fitted on the sphere (whose
#: data is small, 0.2 kB per box) in ``benchmarks/bench_memory.py``.
PER_LEAF = 2700

#: Bytes on top of the boxes, whatever their number (sympy's expansion,
#: the singular point and curve searches, the caches of the surface).
FIXED = 16 << 20

#: Children of a box kept when it is split, on average: a surface meets
#: about 4 of the 8 halves of a box it meets (its area is quartered, the
#: boxes' too).  Used to project the frontier forward.
SURFACE_CHILDREN = 4

#: Share of the available memory a request may plan to use: the rest is
#: left for the allocator's slack and the other processes of the machine.
AVAILABLE_SHARE = 0.8


class MemoryBudgetError(SurfaceError):
    """A request whose estimated memory is over the limit (one line: estimate, limit, what to lower)."""


def available_bytes() -> int | None:
    """Memory the machine can still give (``MemAvailable``), or None where it cannot be read."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return None


def resident_bytes() -> int:
    """The process's resident size now (``/proc/self/statm``), else its peak so far (``ru_maxrss``)."""
    try:
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError):
        import resource
        import sys

        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        return peak if sys.platform == "darwin" else peak * 1024


_UNITS = {"": 1, "b": 1, "k": 1 << 10, "m": 1 << 20, "g": 1 << 30, "t": 1 << 40}


def parse_size(value) -> float:
    """Bytes from a number or a text such as ``"512M"``, ``"2G"``, ``"1.5 GB"`` (powers of 1024).

    Raises
    ------
    SurfaceError
        For anything else, a negative size or NaN.
    """
    if isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool):
        size = float(value)
    else:
        m = re.fullmatch(r"\s*([0-9]*\.?[0-9]+(?:[eE][+-]?[0-9]+)?)\s*([kKmMgGtT]?)(?:i?[bB])?\s*", str(value))
        if not m:
            raise SurfaceError(f"max_memory is a size in bytes or such as 512M, 2G, not {value!r}")
        size = float(m.group(1)) * _UNITS[m.group(2).lower()]
    if not size > 0:  # (NaN too)
        raise SurfaceError(f"max_memory must be positive, not {value!r}")
    return size


def format_size(n: float) -> str:
    """``n`` bytes as 1.2 GB, 340 MB, 12 kB."""
    for unit, scale in (("GB", 1 << 30), ("MB", 1 << 20), ("kB", 1 << 10)):
        if n >= scale:
            return f"{n / scale:.3g} {unit}"
    return f"{n:.0f} B"


class Budget:
    """The check :func:`singmesh.boxes.octree.subdivide` calls before splitting each level.

    Parameters
    ----------
    data_bytes : int
        Bytes of one box's ``Surface.enclose`` data.
    coarse_level, fine_level : int
        Of the request (for the projection and the message).
    max_memory : float, str or None
        The caller's limit of the peak resident size (bytes, or ``"2G"``);
        None: the machine's available memory only.
    """

    def __init__(self, data_bytes: int, coarse_level: int, fine_level: int, max_memory=None):
        self.start = resident_bytes()
        self.per_box = DATA_COPIES * data_bytes + PER_LEAF
        self.coarse_level, self.fine_level = coarse_level, fine_level
        available = available_bytes()
        limits = []
        if available is not None:
            limits.append((self.start + AVAILABLE_SHARE * available, "the memory available"))
        if max_memory is not None:
            size = parse_size(max_memory)
            if math.isfinite(size):
                limits.append((size, "max_memory"))
        self.limit, self.limit_name = min(limits) if limits else (math.inf, "")
        self.largest = 0.0

    def estimate(self, boxes: float) -> float:
        """Peak resident bytes for ``boxes`` leaves."""
        return self.start + FIXED + boxes * self.per_box

    def __call__(self, level: int, leaves: int, frontier: int) -> None:
        """Refuse (MemoryBudgetError) if ``leaves`` plus the projection of ``frontier`` is over the limit.

        ``frontier``: the boxes of ``level`` about to be split.
        """
        steps = max(self.coarse_level - level, 1)
        boxes = leaves + frontier * float(SURFACE_CHILDREN) ** steps
        need = self.estimate(boxes)
        self.largest = max(self.largest, need)
        if need > self.limit:
            raise MemoryBudgetError(
                f"meshing at coarse {1 << self.coarse_level}, fine {1 << self.fine_level} would need about "
                f"{format_size(need)} (about {boxes:.3g} boxes, seen at level {level}), over {self.limit_name} "
                f"({format_size(self.limit)}): lower coarse or fine"
                + (", or raise max_memory" if self.limit_name == "max_memory" else ""))
