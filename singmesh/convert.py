"""A mesh as an object of other libraries: ``trimesh.Trimesh`` and ``pyvista.PolyData``.

Both libraries are optional (the extras ``singmesh[trimesh]`` and
``singmesh[pyvista]``); without them the conversion raises an ImportError
of one line that names the command to run.
"""

from __future__ import annotations

import importlib
from typing import Any

import numpy as np

from .extras import MissingExtraError




def require(module: str, extra: str, what: str) -> Any:
    """Import ``module``, or raise :class:`MissingExtraError` naming ``pip install singmesh[extra]``.

    Parameters
    ----------
    module : str
        The module to import.
    extra : str
        The singmesh extra that installs it.
    what : str
        What needs it, for the message (e.g. ``"Mesh.to_trimesh()"``).
    """
    try:
        return importlib.import_module(module)
    except ImportError:
        raise MissingExtraError(f"{what} needs the package {module}, which is not installed: "
                                f"pip install 'singmesh[{extra}]'") from None


def to_trimesh(mesh) -> Any:
    """The triangles as a ``trimesh.Trimesh``, vertices and faces as they are.

    The unit normals (grad F) are its vertex normals; ``process=False``
    keeps trimesh from merging or reordering vertices, so vertex ``i`` is
    the mesh's vertex ``i`` (singular vertices included).  Trimesh has no
    line cells: the one-dimensional part (isolated real lines) is not in it.
    """
    trimesh = require("trimesh", "trimesh", "Mesh.to_trimesh()")
    return trimesh.Trimesh(vertices=np.array(mesh.vertices, dtype=float), faces=np.array(mesh.faces, dtype=np.int64),
                           vertex_normals=np.array(mesh.normals, dtype=float), process=False, validate=False)


def to_pyvista(mesh, curvature: bool = True) -> Any:
    """The mesh as a ``pyvista.PolyData``: triangles, and line cells for the one-dimensional part.

    Points are those of ``Mesh.curve_lines()`` (the vertices, then the
    points of isolated lines no triangle has), as in ``Mesh.to_meshio()``.
    Point data: ``Normals`` (zero at the extra points) and, with
    ``curvature``, the curvatures of ``Mesh.curvature_data()`` (NaN at the
    extra points and where undefined).
    """
    pv = require("pyvista", "pyvista", "Mesh.to_pyvista()")
    points, lines = mesh.curve_lines()
    faces = np.asarray(mesh.faces, dtype=np.int64).reshape(-1, 3)
    lines = np.asarray(lines, dtype=np.int64).reshape(-1, 2)
    # VTK's cell arrays: each cell as its size followed by its point indices.
    cells = lambda c: np.hstack([np.full((len(c), 1), c.shape[1]), c]).ravel()  # noqa: E731
    poly = pv.PolyData(np.array(points, dtype=float), faces=cells(faces) if len(faces) else None,
                       lines=cells(lines) if len(lines) else None)
    extra = len(points) - len(mesh.vertices)
    poly.point_data["Normals"] = np.vstack([np.asarray(mesh.normals, dtype=float), np.zeros((extra, 3))])
    if curvature:
        for name, values in mesh.curvature_data().items():
            poly.point_data[name] = np.concatenate([values, np.full(extra, np.nan)])
    return poly
