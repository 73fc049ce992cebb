"""Parameter sweeps: mesh a family of surfaces at N values of one parameter.

:func:`sweep` meshes ``F(x, y, z; a) = 0`` at ``frames`` equally spaced
values of ``a`` with the same settings as :func:`singmesh.mesh` (one box,
one resolution), writes one mesh file and one picture per frame (fixed
camera and box, so the frames line up), an animation of the pictures, and
``sweep.json``: the settings and, per frame, the parameter's value and the
singular points with their types, the singular curves, the counts of each
type, the Euler characteristic and the components; then the
``bifurcations``: the pairs of consecutive frames between which the
singular points' types or counts change (where, for instance, two A1
points merge into an A3).

``sweep.json`` holds no timings (they go to ``times.json``): the same
sweep gives the same bytes, run here, in processes or on Dask
(:mod:`singmesh.parallel`).
"""

from __future__ import annotations

import json
import math
import re
import sys
import tempfile
import time
import warnings
from collections import Counter
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from .errors import SurfaceError
from .extras import missing, require
from .files import json_safe, writable_folder

#: Animation formats by suffix; MP4 needs ffmpeg through imageio-ffmpeg.
ANIMATIONS = (".gif", ".mp4")


@dataclass(frozen=True)
class FrameJob:
    """One frame's work, sent to a worker (picklable)."""

    index: int
    value: float
    surface: Any
    param: str
    params: dict
    box: tuple
    settings: dict
    out: str | None  # None: the worker sends the files back (a Dask worker on another machine)
    mesh_file: str
    picture: int  # side in pixels; 0: no picture
    curvature: bool = True  # the curvatures as point data in the mesh files


@dataclass
class SweepResult:
    """What :func:`sweep` wrote and found.

    Attributes
    ----------
    data : dict
        The content of ``sweep.json`` (settings, ``frames``, ``bifurcations``).
    folder : Path
    animation : Path or None
    times : list of float
        Seconds per frame (meshing, writing and drawing), also in ``times.json``.
    """

    data: dict
    folder: Path
    animation: Path | None = None
    times: list = field(default_factory=list)

    @property
    def frames(self) -> list[dict]:
        return self.data["frames"]

    @property
    def bifurcations(self) -> list[dict]:
        return self.data["bifurcations"]

    def table(self) -> str:
        """The bifurcation table as text: one line per frame, value and singular points by type."""
        p = self.data["parameter"]
        lines = []
        for fr in self.frames:
            if fr.get("error"):
                lines.append(f"{p} = {fr['value']:<12.6g} error: {fr['error']}")
                continue
            counts = ", ".join(f"{n} {t}" for t, n in fr["counts"].items()) or "no singular point"
            curves = ", ".join(f"{n} {t}" for t, n in fr["curve_counts"].items())
            lines.append(f"{p} = {fr['value']:<12.6g} {counts}" + (f"; curves: {curves}" if curves else "")
                         + f"; Euler characteristic {fr['euler']}, {fr['components']} component"
                         + ("s" if fr["components"] != 1 else ""))
        return "\n".join(lines)


#: The most frames a sweep takes: a mistyped count (1e8) is refused, not
#: meshed until the memory runs out.
MAX_FRAMES = 10_000


def _values(lo: float, hi: float, frames: int) -> list[float]:
    if not (isinstance(frames, (int, np.integer)) and not isinstance(frames, bool) and frames >= 1):
        raise SurfaceError(f"the number of frames is a positive integer, not {frames!r}")
    if frames > MAX_FRAMES:
        raise SurfaceError(f"{frames} frames is more than a sweep takes (at most {MAX_FRAMES})")
    try:
        lo, hi = float(lo), float(hi)
    except (TypeError, ValueError):
        raise SurfaceError(f"the parameter's range is two numbers, not {lo!r} and {hi!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise SurfaceError(f"the parameter's range {lo:g} .. {hi:g} is not finite")
    if frames == 1:
        return [lo]
    # To 12 digits: the frames are meshed at the values the table shows
    # (0.075, not linspace's 0.07500000000000001).
    return [float(f"{v:.12g}") for v in np.linspace(lo, hi, frames)]


def _check(surface, param: str, values: list[float], params: dict, box) -> np.ndarray:
    """SurfaceError for a bad parameter, equation or box, before any frame is meshed."""
    from .api import check_box
    from .surface import Surface

    if not isinstance(param, str) or not param.isidentifier() or param in ("x", "y", "z"):
        raise SurfaceError(f"{param!r} is not a parameter name (x, y and z are the coordinates)")
    if param in params:
        raise SurfaceError(f"the parameter {param} is swept: it cannot also be given a value")
    try:
        first = Surface.parse(surface, **params, **{param: values[0]})
    except SurfaceError as exc:
        # A misspelt --param: say so, not only which symbol was left unknown.
        if isinstance(surface, str) and "unknown symbol" in str(exc) \
                and not re.search(rf"(?<![A-Za-z0-9_]){re.escape(param)}(?![A-Za-z0-9_])", surface):
            raise SurfaceError(f"the equation has no parameter {param}; {exc}") from None
        if f"parameter {param} is not used" in str(exc):
            raise SurfaceError(f"the equation does not depend on {param}: every frame would be the same") from None
        raise
    last = Surface.parse(surface, **params, **{param: values[-1]})
    if values[0] != values[-1] and first.expr == last.expr:
        raise SurfaceError(f"the equation does not depend on {param}: every frame would be the same")
    return check_box(box)


def sweep(surface, param: str, lo: float, hi: float, frames: int, box=None, *, out,
          coarse: int = 32, fine: int = 256, improve: bool = True, size: str = "uniform",
          min_edge: float | None = None, max_edge: float | None = None, chord: float | None = None,
          max_memory=None, curvature: bool = True, mesh_format: str = "ply", animation: str | None = "sweep.gif",
          fps: float = 4.0, picture_size: int = 480, jobs: int = 1, scheduler: Any = None,
          progress: bool = False, **params) -> SweepResult:
    """Mesh ``surface`` at ``frames`` values of ``param`` from ``lo`` to ``hi`` and write the sweep.

    Parameters
    ----------
    surface : str or sympy expression
        The equation with the parameter, e.g. ``"x^2 + y^2 - (z^2 - a)^2"``.
    param : str
        The parameter swept.
    lo, hi : float
        Its first and last values; the frames are equally spaced between
        them (both included).
    frames : int
        Number of frames.
    box : three (lo, hi) pairs, optional
        The region meshed, the same for every frame (default that of
        :func:`singmesh.mesh`).
    out : str or Path
        The folder written: ``frame_000.<mesh_format>`` (and ``.png``) per
        frame, the animation, ``sweep.json`` and ``times.json``.
    coarse, fine, improve, size, min_edge, max_edge, chord, max_memory
        :func:`singmesh.mesh`'s settings, the same for every frame.
    curvature : bool
        Write the per-vertex curvatures into the mesh files that take them
        (:meth:`singmesh.Mesh.write`).
    mesh_format : str
        Suffix of the mesh files (``ply``, ``obj``, ``vtk``, ...).
    animation : str, optional
        File name of the animation in ``out`` (``.gif``, or ``.mp4`` with
        imageio-ffmpeg installed); None: no animation.
    fps : float
        Frames per second of the animation.
    picture_size : int
        Side of the pictures in pixels; 0: no pictures (nor animation).
    jobs : int
        Frames meshed at once (local processes, or LocalCluster workers).
    scheduler : str or dask.distributed.Client, optional
        Mesh the frames on Dask: ``"local"``, a scheduler's address or a
        connected Client (:func:`singmesh.parallel.map_ordered`).
    progress : bool
        Show a progress bar (tqdm if installed, else a line per frame) on
        standard error.
    **params
        Values of the equation's other parameters.

    Returns
    -------
    SweepResult

    Raises
    ------
    SurfaceError
        Bad equation, parameter, range, box or settings (before any frame
        is meshed); :class:`singmesh.extras.MissingExtraError` when the
        pictures, the animation or Dask are asked for without their packages.
    """
    from singmesh.boxes.sizing import sizing_levels

    from .api import DEFAULT_BOX, _level
    from .memory import parse_size
    from .mesh import FORMATS
    from .parallel import map_ordered

    box = DEFAULT_BOX if box is None else box
    values = _values(lo, hi, frames)
    b = _check(surface, param, values, params, box)
    # mesh()'s settings are checked once here, not failed in every frame.
    if _level(fine, "fine") < _level(coarse, "coarse"):
        raise SurfaceError(f"fine ({fine}) must be at least coarse ({coarse})")
    sizing_levels(size, min_edge, max_edge, chord, _level(fine, "fine"))
    if max_memory is not None:
        parse_size(max_memory)
    suffix = "." + str(mesh_format).lstrip(".").lower()
    if suffix not in FORMATS:
        raise SurfaceError(f"unknown mesh format {mesh_format!r}: use one of {', '.join(sorted(FORMATS))}")
    picture = int(picture_size)
    if picture < 0:
        raise SurfaceError(f"the picture size is a number of pixels, not {picture_size!r}")
    if animation is not None and not picture:
        raise SurfaceError("an animation needs pictures: give a picture size, or no animation")
    if animation is not None and Path(animation).suffix.lower() not in ANIMATIONS:
        raise SurfaceError(f"cannot write the animation {animation}: use a .gif or .mp4 file name")
    if not fps > 0:
        raise SurfaceError(f"frames per second must be positive, not {fps!r}")
    # Every package is asked for before the work, not after an hour of it.
    if picture:
        require("the sweep's pictures", ["matplotlib"], extra="sweep")
    if animation is not None:
        require("the sweep's animation", ["imageio"], extra="sweep")
        if Path(animation).suffix.lower() == ".mp4":
            require("an MP4 animation", ["imageio_ffmpeg"], extra="video")
    if scheduler is not None:
        require("--scheduler (Dask)", ["dask", "distributed"], extra="dask")
    folder = writable_folder(out)  # before the frames are meshed, not after

    settings = {"coarse": coarse, "fine": fine, "improve": improve, "size": size, "min_edge": min_edge,
                "max_edge": max_edge, "chord": chord, "max_memory": max_memory}
    width = max(3, len(str(len(values) - 1)))
    box_list = tuple(tuple(float(v) for v in row) for row in b)
    # Dask workers may be on other machines: they send their files back,
    # and only this process writes into the folder.
    where = None if scheduler is not None else str(folder)
    jobs_list = [FrameJob(i, v, surface, param, dict(params), box_list, settings, where,
                          f"frame_{i:0{width}d}{suffix}", picture, curvature) for i, v in enumerate(values)]
    t0 = time.perf_counter()
    with _Progress(len(jobs_list), progress) as bar:
        results = map_ordered(mesh_frame, jobs_list, jobs=jobs, scheduler=scheduler,
                              on_done=lambda i, r: bar.step(f"{param} = {values[i]:.4g}"), capture=True)
    records = [r if isinstance(r, dict) else _failed(job, r) for r, job in zip(results, jobs_list)]
    for r in records:
        for name, content in sorted(r.pop("files", {}).items()):
            (folder / name).write_bytes(content)
    times = [r.pop("time", None) for r in records]

    movie = None
    if animation is not None:
        pictures = [folder / r["picture"] for r in records if r.get("picture")]
        if pictures:
            movie = write_animation(folder / animation, pictures, fps)
    data = {
        "equation": str(surface),
        "parameter": param,
        "range": [float(lo), float(hi)],
        "values": values,
        "params": {k: str(v) for k, v in params.items()},
        "box": [list(r) for r in box_list],
        "settings": {**settings, "curvature": curvature, "mesh_format": suffix[1:]},
        "picture_size": picture,
        "animation": movie.name if movie else None,
        "frames": records,
        "bifurcations": bifurcations(records),
    }
    (folder / "sweep.json").write_text(_dumps(json_safe(data)), encoding="utf-8")
    (folder / "times.json").write_text(json.dumps(
        {"total": time.perf_counter() - t0, "frames": times, "jobs": jobs,
         "scheduler": scheduler if scheduler is None or isinstance(scheduler, str) else repr(scheduler)},
        indent=1) + "\n", encoding="utf-8")
    return SweepResult(data=json_safe(data), folder=folder, animation=movie, times=times)


def mesh_frame(job: FrameJob) -> dict[str, Any]:
    """Mesh, write and draw one frame; its record for ``sweep.json`` (and ``time``).

    A frame that fails gives a record with ``error``, not an exception: the
    other frames go on.  With ``job.out`` None the files are written into
    a temporary folder and returned in the record (``files``: name -> bytes).
    """
    if job.out is None:
        with tempfile.TemporaryDirectory(prefix="singmesh-frame-") as tmp:
            record = mesh_frame(replace(job, out=tmp))
            record["files"] = {p.name: p.read_bytes() for p in Path(tmp).iterdir() if not p.name.startswith(".")}
            return record
    from .api import mesh

    t0 = time.perf_counter()
    record: dict[str, Any] = {"index": job.index, "value": job.value}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            m = mesh(job.surface, job.box, **job.settings, **job.params, **{job.param: job.value})
            record.update(_describe(m))
            folder = Path(job.out)
            m.write(folder / job.mesh_file, curvature=job.curvature)
            record["mesh"] = job.mesh_file
            if job.picture:
                record["picture"] = _draw(m, folder / Path(job.mesh_file).with_suffix(".png").name, job,
                                          record["counts"])
        except Exception as exc:  # the frame's failure, recorded; the sweep goes on
            record["error"] = f"{type(exc).__name__}: {exc}"
    seen: dict[str, None] = {}
    for w in caught:  # once each, in order (file and line left out: they are not the frame's)
        seen.setdefault(f"{w.category.__name__}: {w.message}", None)
    record["warnings"] = list(seen)
    record["time"] = time.perf_counter() - t0
    return record


def _describe(m) -> dict[str, Any]:
    """A frame's singular points, curves and topology, from its Mesh."""
    points = []
    for s in m.singularities:
        c = s.classification
        points.append({"point": [float(v) for v in s.point], "type": getattr(c, "name", None),
                       "real_form": getattr(c, "real_form", None), "milnor": getattr(c, "milnor", None),
                       "branches": s.branches, "vertex": s.vertex is not None})
    counts = Counter(p["type"] or "unclassified" for p in points)
    forms = Counter(p["real_form"] or p["type"] or "unclassified" for p in points)
    curves = [{"type": c.type, "sheets": int(c.sheets), "closed": bool(c.closed), "vertices": len(c.points),
               "length": float(c.length)} for c in m.singular_curves]
    r = m.report()
    return {
        "singular_points": points,
        "counts": dict(sorted(counts.items(), key=_type_order)),
        "real_form_counts": dict(sorted(forms.items())),
        "singular_curves": curves,
        "curve_counts": dict(sorted(Counter(c["type"] for c in curves).items())),
        "special_points": [{"kind": sp.kind, "point": [float(v) for v in sp.point]} for sp in m.special_points],
        "euler": r["euler_characteristic"],
        "components": r["components"],
        "vertices": r["vertices"],
        "faces": r["faces"],
        "boundary_edges_off_box": r["boundary_edges_off_box"],
        "non_manifold_edges": r["non_manifold_edges"],
    }


def _type_order(item: tuple[str, int]) -> tuple:
    """A1, A2, ..., A10, D4, ..., E8, then other names."""
    name = item[0]
    if len(name) > 1 and name[0] in "ADE" and name[1:].isdigit():
        return (0, "ADE".index(name[0]), int(name[1:]))
    return (1, name, 0)


def _draw(m, path: Path, job: FrameJob, counts: dict) -> str:
    """The frame's picture (the box frames it: the same camera for every frame); its file name."""
    from .render import render_png

    found = ", ".join(f"{n} {t}" for t, n in counts.items())
    note = f"{job.param} = {job.value:.4g}" + (f":  {found}" if found else "")
    render_png(path, m.vertices, m.faces, m.box, normals=m.normals, points=m.singular_points,
               point_names=[s.name for s in m.singularities], size=job.picture, note=note,
               curves=[c.points for c in m.singular_curves], curve_names=[c.type for c in m.singular_curves])
    return path.name


def _failed(job: FrameJob, exc: BaseException | None) -> dict[str, Any]:
    """The record of a frame whose worker never returned (crashed, out of memory)."""
    message = "not run" if exc is None else f"{type(exc).__name__}: {exc}"
    return {"index": job.index, "value": job.value, "error": message, "warnings": [], "time": None}


def bifurcations(records: Sequence[dict]) -> list[dict]:
    """The consecutive frames between which the singular points (types, real forms, counts), the curves or the topology change.

    The topology (Euler characteristic, pieces) changes also where the
    surface passes a singular point between two frames: the change is
    between them, and a finer sweep there finds the point.
    """
    out = []
    keys = ("counts", "real_form_counts", "curve_counts", "euler", "components")
    for a, b in zip(records, records[1:]):
        if a.get("error") or b.get("error"):
            continue
        changed = [k for k in keys if a.get(k) != b.get(k)]
        if changed:
            out.append({"between": [a["value"], b["value"]], "frames": [a["index"], b["index"]],
                        "changed": changed,
                        "before": a["counts"], "after": b["counts"],
                        "forms_before": a["real_form_counts"], "forms_after": b["real_form_counts"],
                        "curves_before": a["curve_counts"], "curves_after": b["curve_counts"],
                        "euler_before": a["euler"], "euler_after": b["euler"],
                        "components_before": a["components"], "components_after": b["components"]})
    return out


def write_animation(path: Path, pictures: Sequence[Path], fps: float) -> Path:
    """The pictures as a GIF (looping) or MP4 at ``path``, through imageio."""
    import imageio.v3 as iio

    frames = np.stack([iio.imread(p)[..., :3] for p in pictures])
    if path.suffix.lower() == ".gif":
        # Pillow's writer: duration in milliseconds per frame, loop 0 = forever.
        iio.imwrite(path, frames, extension=".gif", duration=round(1000.0 / fps), loop=0)
    else:
        iio.imwrite(path, frames, extension=".mp4", fps=fps)
    return path


#: A JSON list of numbers only (no strings, lists or objects in it), as json.dumps indents it.
_NUMBER_LIST = re.compile(r"\[\s+([^\[\]{}\"]*?)\s+\]")


def _dumps(data: dict) -> str:
    """``data`` as indented JSON with each list of numbers on one line (points, boxes, ranges)."""
    text = json.dumps(data, indent=1, allow_nan=False)
    return _NUMBER_LIST.sub(lambda m: "[" + ", ".join(v.strip() for v in m.group(1).split(",")) + "]", text) + "\n"


class _Progress:
    """One progress bar for the frames: tqdm when installed, else a plain line per frame."""

    def __init__(self, total: int, show: bool):
        self.total, self.show, self.done, self.bar = total, show, 0, None
        if show and not missing(["tqdm"]):
            from tqdm import tqdm

            self.bar = tqdm(total=total, desc="sweep", unit="frame", dynamic_ncols=True)

    def step(self, text: str) -> None:
        self.done += 1
        if self.bar is not None:
            self.bar.set_postfix_str(text, refresh=False)
            self.bar.update()
        elif self.show:
            print(f"sweep: frame {self.done}/{self.total} ({text})", file=sys.stderr, flush=True)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        if self.bar is not None:
            self.bar.close()
        return False
