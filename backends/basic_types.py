"""The words every engine-neutral type is built from: vectors, quaternions, and the kinds of motion, shape,
joint and floating-point precision (re-exported by :mod:`backends.types`, where the conventions are)."""

from __future__ import annotations

import enum

Vec3 = tuple[float, float, float]
Quat = tuple[float, float, float, float]  # (w, x, y, z)
Rgba = tuple[float, float, float, float]


class Motion(str, enum.Enum):
    STATIC = "static"  # never moves (ODE: a geom without a body)
    KINEMATIC = "kinematic"  # moved by the runner, with velocity, unaffected by forces
    DYNAMIC = "dynamic"  # simulated


class ShapeKind(str, enum.Enum):
    BOX = "box"
    SPHERE = "sphere"
    CAPSULE = "capsule"
    CYLINDER = "cylinder"
    PLANE = "plane"
    COMPOUND = "compound"  # the body's shapes are BodySpec.shapes, at local poses
    CONVEX = "convex"  # Shape.mesh: a convex hull
    TRIMESH = "trimesh"  # Shape.mesh: a triangle mesh, static bodies only


class JointKind(str, enum.Enum):
    SLIDER = "slider"
    HINGE = "hinge"
    BALL = "ball"
    FIXED = "fixed"
    UNIVERSAL = "universal"


class Precision(str, enum.Enum):
    """The floating-point format an engine keeps its state in (positions, velocities, masses, forces).

    Each step rounds every stored number to it, so a state carries rounding that grows with the number
    of steps: docs/semantics.md ("Rounding") bounds it by ``n * eps * scale`` and the expressions' name
    ``eps`` gives an assertion the running engine's :attr:`eps`."""

    FLOAT32 = "float32"
    FLOAT64 = "float64"

    @property
    def eps(self) -> float:
        """Machine epsilon: the gap between 1 and the next number (2^-23 for float32, 2^-52 for float64)."""
        return 2.0**-23 if self is Precision.FLOAT32 else 2.0**-52


IDENTITY_QUAT: Quat = (1.0, 0.0, 0.0, 0.0)
