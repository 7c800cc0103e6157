"""Kinematic bodies driven by intervals and actions: their current and target poses, and the velocity
the engine is given so that what rests on them is carried (ODE: a body with pose *and* velocity set)."""

from __future__ import annotations

from dataclasses import dataclass

from backends.base import Backend
from backends.geometry import rotation_vector
from backends.types import CompiledWorld, Motion, Vec3
from runner.language.hpr import hpr_to_quat


@dataclass
class KinematicBody:
    """A kinematic body's pose and scale now and at the end of the coming step."""

    index: int
    pos: Vec3
    hpr: Vec3
    scale: float
    target_pos: Vec3
    target_hpr: Vec3
    target_scale: float
    moving: bool = False


class KinematicTable:
    """Poses of every body as intervals see them (get/set pos, hpr, scale), kinematic ones driven."""

    def __init__(self, world: CompiledWorld, start_hpr: dict[str, Vec3], start_scale: dict[str, float]) -> None:
        self.world = world
        self.by_name: dict[str, KinematicBody] = {}
        for i, body in enumerate(world.bodies):
            hpr, scale = start_hpr[body.name], start_scale[body.name]
            self.by_name[body.name] = KinematicBody(i, body.pos, hpr, scale, body.pos, hpr, scale)
        self.driven = [k for k in self.by_name.values() if world.bodies[k.index].motion is Motion.KINEMATIC]
        self.scale_changed: set[str] = set()

    def get(self, name: str) -> KinematicBody:
        return self.by_name[name]

    def teleport(self, backend: Backend, name: str, pos: Vec3, hpr: Vec3) -> None:
        """Move a kinematic body now, with zero velocity (a reset action)."""
        k = self.by_name[name]
        k.pos = k.target_pos = pos
        k.hpr = k.target_hpr = hpr
        backend.set_kinematic(k.index, pos, hpr_to_quat(hpr), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
        k.moving = False

    def drive(self, backend: Backend, dt: float) -> bool:
        """Give the engine each kinematic body's motion over the coming step (target reached at its end).
        True if a kinematic body moves, stops or changes scale over it (it may push what it touches)."""
        changed = False
        for k in self.driven:
            if k.target_scale != k.scale:
                k.scale = k.target_scale
                self.scale_changed.add(self.world.bodies[k.index].name)
                changed = True
            if k.target_pos == k.pos and k.target_hpr == k.hpr:
                if k.moving:
                    backend.set_kinematic(k.index, k.pos, hpr_to_quat(k.hpr), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
                    k.moving = False
                    changed = True
                continue
            changed = True
            q0, q1 = hpr_to_quat(k.hpr), hpr_to_quat(k.target_hpr)
            lin = tuple((k.target_pos[c] - k.pos[c]) / dt for c in range(3))
            ang = tuple(c / dt for c in rotation_vector(q0, q1))
            backend.set_kinematic(k.index, k.pos, q0, lin, ang)  # type: ignore[arg-type]
            k.pos, k.hpr, k.moving = k.target_pos, k.target_hpr, True
        return changed
