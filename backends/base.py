"""The backend contract: one abstract class that every engine adapter implements.

A backend is built from a :class:`~backends.types.CompiledWorld` and then driven by the runner, once
per scenario step, in this order (docs/semantics.md, "Step order")::

    set_kinematic(...) / set_motor(...) / apply_force(...) / reset_body(...)   # inputs for this step
    set_control(...)                                                           # (model-file engines)
    step()                                                                     # advance by world.dt
    body_states(), joint_states(), contacts(), drain_messages()                # read the result

Semantics every backend must honour (ODE's):

* ``step()`` advances by exactly ``world.dt`` using ``world.substeps`` engine steps of
  ``dt / substeps``; no damping the scenario did not ask for; gravity as given.
* ``apply_force`` accumulates a force and torque at the body's centre of mass (world frame) that act
  during the **next** ``step()`` only, over all its substeps, and are then cleared (ODE's dBodyAddForce).
  On a static or kinematic body it has no effect.
* ``set_motor`` sets a joint's velocity motor: target rate ``vel`` with force bounded by ``fmax``;
  ``fmax == 0`` switches it off. It persists until changed. ``set_motors`` is the same for several joints
  in one call (an adapter may send them to the engine in one call: ``_set_motors``).
* ``set_kinematic`` places a kinematic body at a pose *now* and gives it the velocity it moves with
  during the next ``step()`` (linear and angular: what rests on it is carried by friction, also when it
  turns); after that step the body is exactly at ``pos + lin_vel*dt`` with ``quat`` rotated by
  ``ang_vel*dt``. A kinematic body not set again keeps its last velocity for the next step (the runner
  always sets it, to zero when it stops).
* ``reset_body`` teleports a dynamic body that no joint holds and sets its velocities (the lab's reset).
* ``contacts()`` lists the body pairs whose contacts the engine **used during the last step**: found at
  the start of each engine step (at the poses before it), touching (distance <= 0), in any of the step's
  substeps. Per pair: the most points and the deepest penetration of any substep, and the mean normal
  force over the substeps (the transmitted impulse / dt). Static and kinematic bodies never touch each
  other. ``JointStates.motor_force`` is likewise the mean over the step's substeps.
* States are read fresh after the step (never a stale cache), positions in metres, quaternions
  (w, x, y, z; a quaternion and its negation are the same orientation), velocities in the world frame.
* ``drain_messages()`` returns what the engine printed about itself since the last call (lines).

Robots (the capabilities in ``backends.types.ROBOT_CAPABILITIES``; the full text is in backends/types.py and
docs/robots.md). An adapter declares one only when it honours all of it:

* ``shape:compound``: build every ``PlacedShape`` of ``BodySpec.shapes`` at its local pose in the body frame
  (none: a body that never collides); the body's mass properties come from ``mass``/``inertia``/``com``/
  ``inertia_quat``, never from the shapes.
* ``body:com-offset``: the COM at ``BodySpec.com`` and the principal axes at ``BodySpec.inertia_quat`` in the
  body frame; ``body_states()`` still reports the *body frame* (pose, velocity of its origin, angular
  velocity), ``apply_force`` acts at the COM, ``reset_body``/``set_kinematic`` place the body frame.
* ``shape:convex``: collide with exactly the hull in ``Shape.mesh`` (vertices and outward triangles).
* ``shape:trimesh``: ``Shape.mesh`` as a triangle mesh; the compiler only gives it to static bodies.
* ``collision:exclude-pairs``: the pairs of ``CompiledWorld.excluded_pairs`` never touch (no force, not in
  ``contacts()``); every other pair, links of one robot included, collides.
* Joints of a model are ordinary ``JointSpec`` entries (world-frame axis and anchor at the start; positions
  from the start pose); the position servo is the runner's (``set_motor`` every step), never the adapter's.

The optional capabilities (``contact_points()``, ``joint_reactions()``, ``set_control``,
``imported_model()``, ``drain_messages()``) and what they must give: :mod:`backends.optional_contract`.

Edge cases, the same on every backend (checked here, before any engine call):

* a body or joint index outside the world, ``set_kinematic`` on a body that is not kinematic,
  ``reset_body`` on a body that is not dynamic or is held by a joint, ``set_motor`` on a joint without a
  motor (ball, fixed) or with a non-finite ``vel`` or an ``fmax`` that is not a finite number >= 0, and
  every call but ``close()`` after ``close()``: :class:`~backends.errors.ContractViolation`
  (an ``InternalError``: the runner never does this for any scenario);
* ``close()`` is idempotent;
* the engine's own exceptions (``engine_errors``) leave every method as
  :class:`~backends.errors.EngineFailure`; any other exception is a bug in the adapter and propagates as
  it is.

Blow-ups (NaN, inf, runaway speeds) are detected by the runner, once, for every engine
(``runner.sim.blowup.MAX_SPEED``); an adapter reports only what its engine itself calls fatal.

An adapter implements the underscored hooks (``_build``, ``_step``, ``_body_states``, ...); the public
methods here validate, translate engine errors and keep the inputs every adapter needs (the kinematic
track, the one-step forces: see :mod:`backends._kit`).
"""

from __future__ import annotations

import abc
import math
from collections.abc import Sequence
from types import TracebackType
from typing import TYPE_CHECKING, Any, ClassVar

from ._kit.chains import LIGHT, chained
from ._kit.motion import KinematicPose, KinematicTrack, OneStepForces
from ._kit.options import BackendOptions
from .contract_checks import held_by_joints
from .errors import engine_failure
from .optional_contract import OptionalContract
from .types import (
    MODEL_FILE_CAPABILITIES,
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

if TYPE_CHECKING:
    from .batch import WorldBatch

#: Joint kinds that have a coordinate and so a velocity motor (a universal joint's first axis).
MOTORISED = frozenset({JointKind.SLIDER, JointKind.HINGE, JointKind.UNIVERSAL})


class Backend(OptionalContract, abc.ABC):
    """Adapter from a compiled world to one physics engine (the optional capabilities: OptionalContract; the
    checks every public method makes: ContractChecks)."""

    #: Registry name, e.g. ``"pybullet"``.
    name: ClassVar[str]
    #: The distribution that provides the engine, for the version in trace metadata.
    engine_distribution: ClassVar[str]
    #: What this backend can simulate; checked before a run starts.
    capabilities: ClassVar[frozenset[Capability]]
    #: The format the engine keeps its state in (its rounding: docs/semantics.md, "Rounding"); the same
    #: as the registry entry's ``precision`` (the contract suite, backends/testing).
    precision: ClassVar[Precision]
    #: The scenario's ``backend_options.<name>`` block, typed (backends._kit.options).
    Options: ClassVar[type[BackendOptions]] = BackendOptions
    #: The exception types the engine itself raises; only these become EngineFailure.
    engine_errors: ClassVar[tuple[type[BaseException], ...]] = ()
    #: True: the adapter gives the engine each joint's ``JointSpec.dynamics.damping`` itself (its own joint
    #: damping), and the runner's motor carries only the friction loss (runner.sim.joint_dynamics).
    native_damping: ClassVar[bool] = False
    #: the mass and inertia of the light bodies that chain several joints of one body, as a fraction of the
    #: body's (backends/_kit/chains.py: the error it costs and why ODE takes more)
    chain_light: ClassVar[float] = LIGHT

    def __init__(self, world: CompiledWorld) -> None:
        self.world = self.engine_world(world)
        self._shown = len(world.bodies)  # the world's bodies; the chains' light bodies come after them
        self.options = self.Options.parse(world.options_for(self.name), self.name)
        self.kinematic = KinematicTrack(world)
        self.forces = OneStepForces()
        self.steps = 0  # scenario steps taken
        self._motion = [b.motion for b in world.bodies]
        self._held = held_by_joints(world)
        self._closed = True  # until built
        self._motor_sets: set[tuple[int, ...]] = set()  # joint tuples ``set_motors`` has checked
        try:
            self._build()
        except self.engine_errors as exc:
            raise engine_failure(self.name, "building the world", exc) from exc
        self._closed = False

    # --- versions ----------------------------------------------------------------------------------

    @classmethod
    def engine_version(cls) -> str:
        """The installed engine's version (from package metadata; no engine import needed)."""
        from backends.versions import version_or_absent

        return version_or_absent(cls.engine_distribution)

    @classmethod
    def engine_label(cls) -> str:
        """The engine's own name and version, and its wrapper's where they differ (``scenario backends``)."""
        return f"{cls.engine_distribution} {cls.engine_version()}"

    @classmethod
    def engine_world(cls, world: CompiledWorld) -> CompiledWorld:
        """The world the adapter builds: several joints moving one body (``joint_chains``) become a chain
        through light bodies (backends/_kit/chains.py), except on an engine that builds model files itself
        (MuJoCo runs a body's joints natively)."""
        if not world.joint_chains or MODEL_FILE_CAPABILITIES <= cls.capabilities:
            return world
        return chained(world, cls.chain_light)

    @classmethod
    def world_batch(cls) -> type[WorldBatch] | None:
        """The class that runs many worlds of this backend in one engine call (backends.batch), or None: a
        batched sweep (`scenario sweep --batch`) then runs each variant on its own."""
        return None

    @classmethod
    def check_world(cls, world: CompiledWorld, options: BackendOptions) -> None:
        """Refuse (UnsupportedFeature) what this backend cannot run in ``world`` with ``options``, judged from
        the world alone before anything is built: the engine's limits (the tallest column it holds, ...).
        The registry calls it with the capability check, so `scenario validate --backend` refuses exactly
        what `scenario run` refuses before its first step, and a refused world is never built."""
        del world, options

    # --- the contract ------------------------------------------------------------------------------

    def settings(self) -> dict[str, Any]:
        """Effective engine settings worth recording in a trace (solver, tolerances, options)."""
        self._open("settings")
        try:
            return self._settings()
        except self.engine_errors as exc:
            raise engine_failure(self.name, "reading settings", exc) from exc

    def step(self) -> None:
        """Advance the world by ``world.dt``."""
        self._open("step")
        try:
            self._step()
        except self.engine_errors as exc:
            raise engine_failure(self.name, f"step {self.steps + 1}", exc) from exc
        self.forces.clear()
        self.kinematic.advance(self.world.dt)
        self.steps += 1

    def body_states(self) -> BodyStates:
        """Fresh states of all bodies, in ``world.bodies`` order."""
        self._open("body_states")
        try:
            states = self._body_states()
        except self.engine_errors as exc:
            raise engine_failure(self.name, "reading body states", exc) from exc
        if len(states.pos) == self._shown:
            return states
        n = self._shown
        return BodyStates(states.pos[:n], states.quat[:n], states.lin_vel[:n], states.ang_vel[:n])

    def joint_states(self) -> JointStates:
        """Fresh states of all joints, in ``world.joints`` order."""
        self._open("joint_states")
        try:
            return self._joint_states()
        except self.engine_errors as exc:
            raise engine_failure(self.name, "reading joint states", exc) from exc

    def contacts(self) -> list[Contact]:
        """The pairs in contact during the last step, sorted by (a, b)."""
        self._open("contacts")
        try:
            return self._contacts()
        except self.engine_errors as exc:
            raise engine_failure(self.name, "reading contacts", exc) from exc

    def set_kinematic(self, body: int, pos: Vec3, quat: Quat, lin_vel: Vec3, ang_vel: Vec3) -> None:
        """Place kinematic body ``body`` now and set the velocity it moves with during the next step."""
        self._open("set_kinematic")
        if self._motion_of(body, "set_kinematic") is not Motion.KINEMATIC:
            self._refuse(f"set_kinematic: body `{self.world.bodies[body].name}` is {self._motion[body].value}, "
                         f"not kinematic")  # fmt: skip
        pose = self.kinematic.set(body, pos, quat, lin_vel, ang_vel)
        try:
            self._place_kinematic(body, pose)
        except self.engine_errors as exc:
            raise engine_failure(self.name, f"placing kinematic body `{self.world.bodies[body].name}`", exc) from exc

    def set_motor(self, joint: int, vel: float, fmax: float) -> None:
        """Set the velocity motor of ``joint`` (``fmax == 0``: off)."""
        self._open("set_motor")
        spec = self._joint(joint, "set_motor")
        if spec.kind not in MOTORISED:
            self._refuse(f"set_motor: joint `{spec.name}` is a {spec.kind.value} joint, which has no motor")
        if not (math.isfinite(vel) and math.isfinite(fmax) and fmax >= 0.0):
            self._refuse(f"set_motor: joint `{spec.name}` needs a finite vel and a finite fmax >= 0; "
                         f"got vel={vel!r}, fmax={fmax!r}")  # fmt: skip
        try:
            self._set_motor(joint, float(vel), float(fmax))
        except self.engine_errors as exc:
            raise engine_failure(self.name, f"setting the motor of `{spec.name}`", exc) from exc

    def set_motors(self, joints: tuple[int, ...], vels: Sequence[float], fmaxes: Sequence[float]) -> None:
        """``set_motor`` for several joints at once (the runner's servos, every step), with the same checks and
        the same effect: one engine call where the engine has one (``_set_motors``). ``joints`` is a tuple so
        that its indices and kinds are checked once per tuple, not per step; the values are checked each call."""
        self._open("set_motors")
        if joints not in self._motor_sets:
            for joint in joints:
                spec = self._joint(joint, "set_motors")
                if spec.kind not in MOTORISED:
                    self._refuse(f"set_motors: joint `{spec.name}` is a {spec.kind.value} joint, which has no motor")
            if len(set(joints)) != len(joints):
                self._refuse(f"set_motors: a joint is given twice in {joints!r}")
            self._motor_sets.add(joints)
        if not (len(vels) == len(fmaxes) == len(joints)):
            self._refuse(f"set_motors: {len(joints)} joints, {len(vels)} vels and {len(fmaxes)} fmaxes")
        if not (all(map(math.isfinite, vels)) and all(map(math.isfinite, fmaxes)) and min(fmaxes, default=0.0) >= 0):
            for joint, vel, fmax in zip(joints, vels, fmaxes, strict=True):
                if not (math.isfinite(vel) and math.isfinite(fmax) and fmax >= 0.0):
                    self._refuse(f"set_motors: joint `{self.world.joints[joint].name}` needs a finite vel and a "
                                 f"finite fmax >= 0; got vel={vel!r}, fmax={fmax!r}")  # fmt: skip
        try:
            self._set_motors(joints, [float(v) for v in vels], [float(f) for f in fmaxes])
        except self.engine_errors as exc:
            raise engine_failure(self.name, "setting the motors", exc) from exc

    def apply_force(self, body: int, force: Vec3, torque: Vec3) -> None:
        """Add a force and torque (world frame, at the COM) for the next step only (none on a body that
        is not dynamic)."""
        self._open("apply_force")
        if self._motion_of(body, "apply_force") is Motion.DYNAMIC:
            self.forces.add(body, force, torque)

    def reset_body(self, body: int, pos: Vec3, quat: Quat, lin_vel: Vec3, ang_vel: Vec3) -> None:
        """Teleport a dynamic body that no joint holds and set its velocities."""
        self._open("reset_body")
        motion = self._motion_of(body, "reset_body")
        name = self.world.bodies[body].name
        if motion is not Motion.DYNAMIC:
            self._refuse(f"reset_body: body `{name}` is {motion.value}; only dynamic bodies are reset")
        if body in self._held:
            self._refuse(f"reset_body: body `{name}` is held by joint `{self._held[body]}`; jointed bodies are "
                         f"not reset")  # fmt: skip
        try:
            self._reset_body(body, pos, quat, lin_vel, ang_vel)
        except self.engine_errors as exc:
            raise engine_failure(self.name, f"resetting `{name}`", exc) from exc

    def close(self) -> None:
        """Release the engine. Idempotent; every other method refuses afterwards."""
        if self._closed:
            return
        self._closed = True
        try:
            self._close()
        except self.engine_errors as exc:
            raise engine_failure(self.name, "closing", exc) from exc

    @property
    def closed(self) -> bool:
        return self._closed

    def __enter__(self) -> Backend:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    # --- what an adapter implements ----------------------------------------------------------------

    @abc.abstractmethod
    def _build(self) -> None:
        """Create the engine's world from ``self.world`` (options already in ``self.options``)."""

    @abc.abstractmethod
    def _step(self) -> None:
        """Advance by ``world.dt``: apply ``self.forces`` for every substep, move the kinematic bodies along
        ``self.kinematic`` (ending each at ``pose.at(dt)``). The base then clears the forces and advances
        the track."""

    @abc.abstractmethod
    def _body_states(self) -> BodyStates: ...

    @abc.abstractmethod
    def _joint_states(self) -> JointStates: ...

    @abc.abstractmethod
    def _contacts(self) -> list[Contact]: ...

    @abc.abstractmethod
    def _set_motor(self, joint: int, vel: float, fmax: float) -> None: ...

    def _set_motors(self, joints: tuple[int, ...], vels: list[float], fmaxes: list[float]) -> None:
        """Several motors in one call (the contract's ``set_motors``; values checked): one ``_set_motor`` each
        unless the engine has a call for many."""
        for joint, vel, fmax in zip(joints, vels, fmaxes, strict=True):
            self._set_motor(joint, vel, fmax)

    @abc.abstractmethod
    def _reset_body(self, body: int, pos: Vec3, quat: Quat, lin_vel: Vec3, ang_vel: Vec3) -> None: ...

    def _place_kinematic(self, body: int, pose: KinematicPose) -> None:  # noqa: B027 - optional hook
        """A kinematic body was given a new pose and velocity (``self.kinematic[body]``): impose it now."""

    def _settings(self) -> dict[str, Any]:
        return {"options": self.options.as_dict()} if self.Options.keys() else {}

    def _close(self) -> None:  # noqa: B027 - optional hook
        """Release the engine's resources (called once)."""
