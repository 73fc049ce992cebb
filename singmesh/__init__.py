"""singmesh: triangle meshes of real algebraic surfaces, right at their singularities."""

from .errors import SurfaceError
from .surface import Surface

__all__ = ["Surface", "SurfaceError"]

from .api import mesh  # noqa: E402
from .defs import Definition, find_definition, read_definitions  # noqa: E402
from .sweeps import SweepResult, sweep  # noqa: E402
from .mesh import CreaseWarning, EmptyMeshWarning, Mesh, SingularPointWarning  # noqa: E402
from singmesh.skeleton.classify import NotSingularError, SingularityType, classify  # noqa: E402
from singmesh.skeleton.points import SingularPoint  # noqa: E402

__all__ += ["mesh", "Mesh", "SingularPointWarning", "EmptyMeshWarning", "CreaseWarning", "Definition", "read_definitions", "find_definition", "classify", "SingularityType", "NotSingularError", "SingularPoint", "sweep", "SweepResult"]
