"""The backend contract: one small abstract class that every engine adapter implements.

A backend is built from a :class:`~backends.types.CompiledWorld` and then driven by the runner, once
per scenario step, in this order (docs/semantics.md, "Step order")::

    set_kinematic(...) / set_motor(...) / apply_force(...) / reset_body(...)   # inputs for this step
    step()                                                                     # advance by world.dt
    body_states(), joint_states(), contacts()                                  # read the result

Semantics every backend must honour (ODE's):

* ``step()`` advances by exactly ``world.dt`` using ``world.substeps`` engine steps of
  ``dt / substeps``; no damping the scenario did not ask for; gravity as given.
* ``apply_force`` accumulates a force and torque at the body's centre of mass (world frame) that act
  during the **next** ``step()`` only, over all its substeps, and are then cleared (ODE's dBodyAddForce).
* ``set_motor`` sets a joint's velocity motor: target rate ``vel`` with force bounded by ``fmax``;
  ``fmax == 0`` switches it off. It persists until changed.
* ``set_kinematic`` places a kinematic body at a pose *now* and gives it the velocity it moves with
  during the next ``step()``; after that step the body is exactly at
  ``pos + lin_vel*dt`` with ``quat`` rotated by ``ang_vel*dt``, and bodies resting on it were
  carried by friction. A kinematic body not set again keeps its last velocity for the next step
  (the runner always sets it, to zero when it stops).
* ``reset_body`` teleports a dynamic body and sets its velocities (the lab's reset on ``mouse1``). Bodies held by
  joints are not reset (the runner refuses such a scenario before it runs).
* ``contacts()`` lists body pairs touching (distance <= 0) during the last ``step()`` (in any of its substeps);
  ``normal_force`` is the step's mean. Pairs of static and kinematic bodies never collide with each other.
* ``JointStates.motor_force`` is the mean over the step's substeps.
* A quaternion and its negation are the same orientation; callers must not rely on the sign.
* States are read fresh after the step (never a stale cache), positions in metres, quaternions
  (w, x, y, z), velocities in the world frame.
* Engine exceptions leave the adapter as :class:`~backends.errors.EngineFailure`.
"""

from __future__ import annotations

import abc
from collections.abc import Mapping
from types import TracebackType
from typing import Any, ClassVar

from .types import BodyStates, Capability, CompiledWorld, Contact, JointStates, Quat, Vec3


class Backend(abc.ABC):
    """Adapter from a compiled world to one physics engine."""

    #: Registry name, e.g. ``"pybullet"``.
    name: ClassVar[str]
    #: The distribution that provides the engine, for the version in trace metadata.
    engine_distribution: ClassVar[str]
    #: What this backend can simulate; checked before a run starts.
    capabilities: ClassVar[frozenset[Capability]]
    #: Keys accepted in the scenario's ``backend_options.<name>`` block, with a one-line meaning each.
    option_keys: ClassVar[Mapping[str, str]] = {}

    def __init__(self, world: CompiledWorld) -> None:
        self.world = world

    @classmethod
    def engine_version(cls) -> str:
        """The installed engine's version (from package metadata; no engine import needed)."""
        from importlib.metadata import PackageNotFoundError, version

        try:
            return version(cls.engine_distribution)
        except PackageNotFoundError:
            return "not installed"

    def settings(self) -> dict[str, Any]:
        """Effective engine settings worth recording in a trace (solver, tolerances, options)."""
        return {}

    @abc.abstractmethod
    def step(self) -> None:
        """Advance the world by ``world.dt``."""

    @abc.abstractmethod
    def body_states(self) -> BodyStates:
        """Fresh states of all bodies, in ``world.bodies`` order."""

    @abc.abstractmethod
    def joint_states(self) -> JointStates:
        """Fresh states of all joints, in ``world.joints`` order."""

    @abc.abstractmethod
    def contacts(self) -> list[Contact]:
        """Touching body pairs after the last step, sorted by (a, b)."""

    @abc.abstractmethod
    def set_kinematic(self, body: int, pos: Vec3, quat: Quat, lin_vel: Vec3, ang_vel: Vec3) -> None:
        """Place kinematic body ``body`` now and set the velocity it moves with during the next step."""

    @abc.abstractmethod
    def set_motor(self, joint: int, vel: float, fmax: float) -> None:
        """Set the velocity motor of ``joint`` (``fmax == 0``: off)."""

    @abc.abstractmethod
    def apply_force(self, body: int, force: Vec3, torque: Vec3) -> None:
        """Add a force and torque (world frame, at the COM) for the next step only."""

    @abc.abstractmethod
    def reset_body(self, body: int, pos: Vec3, quat: Quat, lin_vel: Vec3, ang_vel: Vec3) -> None:
        """Teleport a dynamic body and set its velocities."""

    def close(self) -> None:  # noqa: B027 - optional hook
        """Release the engine (idempotent)."""

    def __enter__(self) -> Backend:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()
