"""singmesh: triangle meshes of real algebraic surfaces, right at their singularities."""

from .errors import SurfaceError
from .surface import Surface

__all__ = ["Surface", "SurfaceError"]
