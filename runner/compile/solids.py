"""Collision solids (Panda3D's CollisionSphere, CollisionPolygon, CollisionBox) as the compiler builds them."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class SolidDef:
    """A solid in its body's frame, unscaled (the body's current scale is applied at test time)."""

    kind: str  # sphere | polygon | box
    center: np.ndarray  # (3,)
    radius: float = 0.0
    half: np.ndarray | None = None  # box half sizes
    vertices: np.ndarray | None = None  # (n, 3) polygon


@dataclass(frozen=True)
class NodeDef:
    """A collision node (Panda3D style: a name for its collision events) and its solids, on a body."""

    name: str
    body: int  # index into the world's bodies
    solids: tuple[SolidDef, ...]
