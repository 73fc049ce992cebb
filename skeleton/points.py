"""The record of one singular point of a surface, as the mesh reports it."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np


@dataclass(frozen=True, eq=False)
class SingularPoint:
    """A point where F and grad F vanish.

    Attributes
    ----------
    point : (3,) ndarray
        Location, Newton-refined.
    residual : float
        max(|F|, |grad F|) at ``point`` (scaled by the polynomial's size).
    hessian_rank : int
        Rank of the Hessian (3 for a node A1).
    signature : tuple[int, int, int]
        Positive, negative and zero eigenvalues of the Hessian.
    branches : int or None
        Branches of the mesh meeting at the point: the link cycles fanned
        into it (0 for an isolated real point).  The classification
        carries the number the singularity type predicts; they agree when
        the mesh is right.
    vertex : int or None
        Index of the mesh vertex placed at the point (None if no triangle
        reaches it, as for an isolated real point).
    classification : Any
        The :class:`singmesh.skeleton.classify.SingularityType`, if known.
    """

    point: np.ndarray
    residual: float
    hessian_rank: int
    signature: tuple
    branches: int | None = None
    vertex: int | None = None
    classification: Any = None

    @property
    def name(self) -> str:
        """Type name, e.g. ``"A1--"``, or a rank description if unclassified."""
        c = self.classification
        if c is not None:
            return getattr(c, "real_form", None) or getattr(c, "name", str(c))
        return f"rank {self.hessian_rank}"

    def describe(self) -> str:
        x, y, z = self.point
        parts = [f"({x:.10g}, {y:.10g}, {z:.10g})", self.name]
        c = self.classification
        if c is not None and getattr(c, "milnor", None):
            parts.append(f"Milnor {c.milnor}")
        if self.branches is not None:
            parts.append(f"{self.branches} branch{'es' if self.branches != 1 else ''} in the mesh")
        if c is not None and getattr(c, "name", "") == "non-differentiable":
            parts.append("F not differentiable (no Hessian)")
        else:
            p, n, zr = self.signature
            parts.append(f"Hessian rank {self.hessian_rank} (+{p} -{n} 0x{zr})")
        if self.vertex is None:
            parts.append("no triangle reaches it")
        return "  ".join(parts)

    def __str__(self) -> str:
        return self.describe()
