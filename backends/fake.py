"""A pure-Python test backend: exact ODE-style free motion, no contacts. For tests of the runner's logic.

Dynamic bodies move by semi-implicit Euler (v += (g + F/m) dt; x += v dt) with orientation integrated from
the angular velocity (no gyroscopic term); sliders to the environment carry a velocity motor bounded by
fmax; kinematic bodies follow the kit's track exactly. There are no contacts, so no collisions.

Its world batch (:class:`FakeWorldBatch`, backends.batch), for the runner's lockstep and batched-sweep logic:
Each view is a FakeBackend whose ``_step`` only consumes the step ``step_all`` took for it. ``step_all``
advances each active world by the fake engine's own step, with numpy's floating-point errors raised: an
overflow or an invalid operation in a world's step is that world's :class:`~backends.errors.EngineFailure`
(the batch's engine calling that world fatal, as a real batched engine reports a world gone unstable), and
the other worlds go on. Worlds batch when they have the same structure (the bodies and joints by name, kind
and motion, the step and substeps); masses, surfaces, starting states, gravity and inputs may differ.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import ClassVar

import numpy as np

from ._kit import KinematicPose, SubstepMean, substep_times
from .base import Backend
from .batch import WorldBatch
from .errors import EngineFailure
from .geometry import integrate_quat
from .types import (
    ALL_SHAPES,
    BodyStates,
    Capability,
    CompiledWorld,
    Contact,
    JointKind,
    JointStates,
    Motion,
    Precision,
    Quat,
    Vec3,
)


class FakeBackend(Backend):
    name = "fake"
    engine_distribution = "numpy"
    precision = Precision.FLOAT64
    capabilities: ClassVar[frozenset[Capability]] = ALL_SHAPES | {
        Capability.KINEMATIC,
        Capability.JOINT_SLIDER,
        Capability.JOINT_MOTOR,
        Capability.JOINT_LIMITS,
        Capability.SUBSTEPS,
        Capability.CONTACT_BOUNCE,  # vacuous: the fake backend has no contacts, so no surface changes anything
    }

    def _build(self) -> None:
        world = self.world
        n = len(world.bodies)
        self.pos = np.array([b.pos for b in world.bodies], float).reshape(n, 3)
        self.quat = np.array([b.quat for b in world.bodies], float).reshape(n, 4)
        self.vel = np.array([b.lin_vel for b in world.bodies], float).reshape(n, 3)
        self.ang = np.array([b.ang_vel for b in world.bodies], float).reshape(n, 3)
        self.mass = np.array([b.mass for b in world.bodies], float)
        self.inertia = np.array([b.inertia for b in world.bodies], float).reshape(n, 3)
        self.moves = np.array([b.motion is Motion.DYNAMIC for b in world.bodies])
        index = {b.name: i for i, b in enumerate(world.bodies)}
        self.sliders = [(index[j.body], np.asarray(j.axis), j) for j in world.joints if j.kind is JointKind.SLIDER]
        self.start = {i: self.pos[i].copy() for i, _, _ in self.sliders}
        self.motor = {j.name: (j.motor.vel, j.motor.fmax) if j.motor else (0.0, 0.0) for _, _, j in self.sliders}
        self.applied = SubstepMean(len(world.joints))

    def _step(self) -> None:
        n = self.world.substeps
        h = self.world.dt / n
        g = np.asarray(self.world.gravity)
        force = np.zeros((len(self.world.bodies), 6))
        for i, acc in self.forces.items():
            force[i] = acc
        self.applied.start()
        for t in substep_times(self.world.dt, n):
            for d in np.flatnonzero(self.moves):
                self.vel[d] += (g + force[d, :3] / self.mass[d]) * h
                self.ang[d] += force[d, 3:] / self.inertia[d].mean() * h
            applied = np.zeros(len(self.world.joints))
            for k, (i, axis, joint) in enumerate(self.sliders):
                vel, fmax = self.motor[joint.name]
                along = float(self.vel[i] @ axis)
                # the joint removes all motion off its axis; the motor changes the rate within fmax*h/m
                self.vel[i] = along * axis
                self.ang[i] = 0.0
                dv = np.clip(vel - along, -fmax * h / self.mass[i], fmax * h / self.mass[i]) if fmax > 0 else 0.0
                self.vel[i] += dv * axis
                applied[k] = dv * self.mass[i] / h
            self.applied.add(applied)
            for d in np.flatnonzero(self.moves):
                self.pos[d] += self.vel[d] * h
                self.quat[d] = integrate_quat(self.quat[d], self.ang[d], h)
            for i, pose in self.kinematic.items():
                self.pos[i], self.quat[i] = pose.at(t)
        self.applied.finish()

    def _body_states(self) -> BodyStates:
        return BodyStates(self.pos.copy(), self.quat.copy(), self.vel.copy(), self.ang.copy())

    def _joint_states(self) -> JointStates:
        m = len(self.world.joints)
        position, velocity = np.full(m, np.nan), np.full(m, np.nan)
        for k, (i, axis, _) in enumerate(self.sliders):
            position[k] = float((self.pos[i] - self.start[i]) @ axis)
            velocity[k] = float(self.vel[i] @ axis)
        return JointStates(position, velocity, self.applied.mean.copy())

    def _contacts(self) -> list[Contact]:
        return []

    def _place_kinematic(self, body: int, pose: KinematicPose) -> None:
        self.pos[body], self.quat[body] = pose.pos, pose.quat
        self.vel[body], self.ang[body] = pose.lin_vel, pose.ang_vel

    def _set_motor(self, joint: int, vel: float, fmax: float) -> None:
        self.motor[self.world.joints[joint].name] = (vel, fmax)

    def _reset_body(self, body: int, pos: Vec3, quat: Quat, lin_vel: Vec3, ang_vel: Vec3) -> None:
        self.pos[body], self.quat[body], self.vel[body], self.ang[body] = pos, quat, lin_vel, ang_vel

    @classmethod
    def world_batch(cls) -> type[WorldBatch] | None:
        return FakeWorldBatch if cls is FakeBackend else None  # a subclass (crash) steps its own way


class _FakeView(FakeBackend):
    """One world of the batch: its ``step()`` consumes the step ``step_all`` took (or raises its failure)."""

    def _build(self) -> None:
        super()._build()
        self.taken: EngineFailure | None | bool = False  # False: not stepped since the last step()

    def engine_step(self) -> None:
        """The fake engine's own step of this world (what a single FakeBackend's ``step()`` runs)."""
        super()._step()

    def _step(self) -> None:
        taken, self.taken = self.taken, False
        if taken is False:
            raise RuntimeError(f"{self.name}: step() on a batched world that step_all() did not step")
        if isinstance(taken, EngineFailure):
            raise taken


def _structure(world: CompiledWorld) -> tuple[object, ...]:
    """What the batch's worlds must share: bodies and joints (names, kinds, motions), step and substeps."""
    bodies = tuple((b.name, b.motion.value) for b in world.bodies)
    joints = tuple((j.name, j.kind.value, j.body, j.other) for j in world.joints)
    return bodies, joints, world.dt, world.substeps


def _differences(a: CompiledWorld, b: CompiledWorld) -> str:
    """How world ``b`` differs in structure from ``a``, in words."""
    if len(a.bodies) != len(b.bodies):
        return f"{len(b.bodies)} bodies, where variant 0 has {len(a.bodies)}"
    if len(a.joints) != len(b.joints):
        return f"{len(b.joints)} joints, where variant 0 has {len(a.joints)}"
    if (a.dt, a.substeps) != (b.dt, b.substeps):
        return f"dt {b.dt:g} s x {b.substeps} substeps, where variant 0 has {a.dt:g} s x {a.substeps}"
    return "other bodies or joints (names, kinds or motions) than variant 0"


class FakeWorldBatch(WorldBatch):
    """N fake worlds (see the module docstring)."""

    backend = FakeBackend

    @classmethod
    def why_not(cls, worlds: Sequence[CompiledWorld]) -> str | None:
        if not worlds:
            return "no worlds to batch"
        first = _structure(worlds[0])
        for k, world in enumerate(worlds[1:], start=1):
            if _structure(world) != first:
                return f"variant {k} has {_differences(worlds[0], world)}"
        return None

    def __init__(self, worlds: Sequence[CompiledWorld]) -> None:
        super().__init__(worlds)
        refusal = self.why_not(self.worlds)
        if refusal is not None:
            raise ValueError(f"these worlds do not batch: {refusal}")
        self._views: list[_FakeView] = []
        try:
            for world in self.worlds:
                self._views.append(_FakeView(world))
        except BaseException:
            self.close()
            raise

    @property
    def views(self) -> Sequence[FakeBackend]:
        return self._views

    def step_all(self, active: Sequence[bool]) -> dict[int, EngineFailure]:
        if len(active) != len(self._views):
            raise ValueError(f"step_all: {len(active)} flags for {len(self._views)} worlds")
        failed: dict[int, EngineFailure] = {}
        for i, (view, on) in enumerate(zip(self._views, active, strict=True)):
            if not on or view.closed:
                continue
            try:
                with np.errstate(over="raise", invalid="raise", divide="raise"):
                    view.engine_step()
            except FloatingPointError as exc:
                failed[i] = EngineFailure(f"fake (batched): world {i} failed in step {view.steps + 1}: {exc}",
                                          backend=view.name)  # fmt: skip
                view.taken = failed[i]
            else:
                view.taken = None
        return failed

    def close(self) -> None:
        for view in self._views:
            view.close()
