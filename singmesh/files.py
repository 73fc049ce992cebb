"""Output folders and JSON: a folder checked writable before the work, values made JSON-safe.

Shared by the sweep (``singmesh.sweeps``) and the gallery (``gallery/``),
which write many files into one folder after minutes of meshing: the
folder is tried first, so a bad ``--out`` costs one line, not the work.
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any

import numpy as np

from .errors import SurfaceError


def writable_folder(path: str | os.PathLike) -> Path:
    """Create ``path`` (and its parents) and write a file into it; SurfaceError of one line if that fails."""
    folder = Path(path)
    try:
        folder.mkdir(parents=True, exist_ok=True)
        probe = folder / f".singmesh-probe-{os.getpid()}"
        probe.open("wb").close()
        probe.unlink()
    except OSError as exc:
        raise SurfaceError(f"cannot write into {folder}: {exc.strerror or exc}") from None
    return folder


def json_safe(value: Any) -> Any:
    """``value`` with numpy scalars and arrays as Python numbers and lists, NaN and infinities as None."""
    if isinstance(value, dict):
        return {str(k): json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_safe(v) for v in value]
    if isinstance(value, np.ndarray):
        return json_safe(value.tolist())
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, (float, np.floating)):
        v = float(value)
        return v if math.isfinite(v) else None
    return value
