"""The backend contract's optional capabilities: what :class:`backends.base.Backend` offers on every backend
but an adapter gives only where it declares the capability or overrides the hook (contract: backends/base.py).

* ``contact_points()`` (only an adapter that declares ``contacts:points``; the runner calls it only when a
  scenario asks, as reading points costs time): every touching point (distance <= 0) of the step's **last**
  engine step, sorted by (a, b) and in the engine's order within a pair, each with its world position, its
  unit normal pointing from body ``a`` to body ``b`` (the force on ``b`` is ``+force * normal``), its depth
  and its normal force in that engine step. With one engine step per scenario step a pair's point forces
  sum to its ``contacts()`` normal force; with several, ``contacts()`` is the mean over them and the points
  are the last one's (docs/semantics.md, "Contact points").
* ``set_control`` sets the control input of a model file's actuator (MJCF `<actuator>`, by its index in the
  file), held until changed; only an engine running model files' actuators itself (``actuator:native``).
* ``imported_model()`` (optional hook ``_imported_model``) reads back, before any step, how the engine holds the
  world it was built from: per dynamic body its mass, principal inertia about the COM, COM in the body frame
  and collision shapes counted; per joint its kind, world axis, stops, and the damping, friction loss, effort
  and velocity limits the engine itself holds (``backends.types.ImportedModel``). The values come FROM THE
  ENGINE (pybullet getDynamicsInfo/getJointInfo, MuJoCo's mjModel arrays, DART's BodyNode/Joint getters,
  ODE's OdeMass and joint params), never from ``self.world``: they show what the engine will simulate, which
  is what ``scenario compare`` compares across engines. An adapter that cannot read them back returns None
  (the default) and the comparison says "not reported".
* ``drain_messages()`` (optional hook ``_drain_messages``) returns what the engine printed about itself since
  the last call (lines); by default nothing.

Sensing (``joint:reaction``, declared by an adapter that implements ``_joint_reactions``):

* ``joint_reactions()`` gives, for each joint of ``CompiledWorld.reaction_joints`` in that order, the wrench
  the joint applied to its first body (``JointSpec.body``) during the last step: its constraint rows, its
  motor and its stops together (everything the joint transmits; contacts, gravity and applied forces are not
  the joint's), as the mean over the step's substeps (as ``motor_force``). One row of six numbers: the force
  (N, world frame), then the torque (N m, world frame) **about that body's centre of mass** (the runner moves
  it to the joint's anchor). Zeros before the first step. An engine computes it only for those joints (it
  may cost a sensor or a pass over the tree); the runner calls it only when the list is not empty.
"""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np

from .contract_checks import ContractChecks
from .errors import engine_failure
from .types import Capability, ContactPoint, ImportedModel

__all__ = ["OptionalContract"]


class OptionalContract(ContractChecks):
    """The optional capabilities' public methods and their hooks' defaults (the base's attributes below)."""

    capabilities: ClassVar[frozenset[Capability]]
    engine_errors: ClassVar[tuple[type[BaseException], ...]]
    steps: int

    def contact_points(self) -> list[ContactPoint]:
        """The touching points of the last step's last engine step, sorted by (a, b) (``contacts:points``)."""
        self._open("contact_points")
        if Capability.CONTACT_POINTS not in self.capabilities:
            self._refuse("contact_points(): this backend does not declare contacts:points")
        try:
            return self._contact_points()
        except self.engine_errors as exc:
            raise engine_failure(self.name, "reading contact points", exc) from exc

    def joint_reactions(self) -> np.ndarray:
        """(len(world.reaction_joints), 6): force, then torque about the first body's COM, world frame, that
        each watched joint applied to its first body during the last step (see the module docstring)."""
        self._open("joint_reactions")
        if Capability.JOINT_REACTION not in self.capabilities:
            self._refuse("joint_reactions: this backend does not declare joint:reaction")
        try:
            return self._joint_reactions()
        except self.engine_errors as exc:
            raise engine_failure(self.name, "reading joint reactions", exc) from exc

    def set_control(self, actuator: int, ctrl: float) -> None:
        """Set the control input of the model file's actuator ``actuator`` (MJCF `<actuator>`, in the file's
        order) on an engine that builds the file itself (``Capability.ACTUATOR_NATIVE``); held until changed."""
        self._open("set_control")
        if Capability.ACTUATOR_NATIVE not in self.capabilities:
            self._refuse(f"set_control: {self.name} does not run a model file's actuators")
        if not math.isfinite(ctrl):
            self._refuse(f"set_control: actuator {actuator} needs a finite ctrl; got {ctrl!r}")
        try:
            self._set_control(int(actuator), float(ctrl))
        except self.engine_errors as exc:
            raise engine_failure(self.name, f"setting the control of actuator {actuator}", exc) from exc

    def imported_model(self) -> ImportedModel | None:
        """How the engine holds the world, read back from it (module docstring); None: the adapter cannot say.
        Only before the first step: afterwards the bodies have moved and the read would not be the import."""
        self._open("imported_model")
        if self.steps:
            self._refuse(f"imported_model() after {self.steps} step(s); it reads the world as built")
        try:
            return self._imported_model()
        except self.engine_errors as exc:
            raise engine_failure(self.name, "reading the imported model back", exc) from exc

    def drain_messages(self) -> list[str]:
        """What the engine printed about itself since the last call, one line each (default: nothing)."""
        self._open("drain_messages")
        return self._drain_messages()

    # --- the optional hooks ----------------------------------------------------------------------------

    def _contact_points(self) -> list[ContactPoint]:
        """The last engine step's touching points (an adapter that declares ``contacts:points``)."""
        self._refuse("contact_points() is declared but not implemented")

    def _joint_reactions(self) -> np.ndarray:
        """``joint:reaction``: the rows of :meth:`joint_reactions` (only adapters that declare it)."""
        self._refuse("joint_reactions: not implemented by this adapter")

    def _set_control(self, actuator: int, ctrl: float) -> None:  # an engine running model files overrides it
        self._refuse(f"set_control: {self.name} does not run a model file's actuators")

    def _imported_model(self) -> ImportedModel | None:
        """Read the built world back from the engine (``imported_model``); None: this adapter cannot."""
        return None

    def _drain_messages(self) -> list[str]:
        return []
