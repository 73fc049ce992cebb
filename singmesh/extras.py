"""Optional dependencies ("extras"): one clear line naming the install when one is missing.

The gallery, the sweep's pictures and animation, and the Dask scale-out
use packages the core mesher does not need.  Asking for them without the
extra installed gives a :class:`MissingExtraError` (a SurfaceError: the
command line prints it as one line and exits with status 2) that names the
``pip install`` to run, instead of a ModuleNotFoundError traceback.
"""

from __future__ import annotations

import importlib.util
from typing import Sequence

from .errors import SurfaceError

#: The extra of pyproject.toml that installs each optional module.
EXTRA_OF = {
    "matplotlib": "sweep",
    "imageio": "sweep",
    "tqdm": "sweep",
    "distributed": "dask",
    "dask": "dask",
    "trimesh": "trimesh",
    "pyvista": "pyvista",
}


class MissingExtraError(SurfaceError, ImportError):
    """An optional package is not installed; the message says which extra installs it.

    A SurfaceError (the command line prints one line and exits 2) and an
    ImportError (what Python code expects of a missing package).
    """


def missing(modules: Sequence[str]) -> list[str]:
    """The names of ``modules`` that cannot be imported (found without importing them)."""
    out = []
    for name in modules:
        try:
            found = importlib.util.find_spec(name) is not None
        except (ImportError, ValueError):  # a parent package missing, or a stub in sys.modules
            found = False
        if not found:
            out.append(name)
    return out


def require(what: str, modules: Sequence[str], extra: str | None = None) -> None:
    """Raise :class:`MissingExtraError` unless every one of ``modules`` is installed.

    Parameters
    ----------
    what : str
        What needs them, for the message ("the sweep's animation").
    modules : sequence of str
        Top-level module names (``"distributed"``, not ``"dask.distributed"``).
    extra : str, optional
        The extra to install; by default that of the first missing module
        (:data:`EXTRA_OF`).
    """
    gone = missing(modules)
    if gone:
        extra = extra or EXTRA_OF.get(gone[0], gone[0])
        names = " and ".join(gone)
        raise MissingExtraError(f"{what} needs {names}, which is not installed: "
                                f"pip install 'singmesh[{extra}]'")
