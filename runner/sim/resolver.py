"""Resolve dotted names (``box.pos.z``, ``slider.force``, ``state.x``, ``time``) against the current state.

``<body>.energy`` is the body's mechanical energy (J) in the world frame, ``1/2 m |v_c|^2 + 1/2 w_b^T I w_b
- m g.p_c``: its centre of mass ``p_c`` (``BodySpec.com`` turned by the body's orientation), that point's
velocity ``v_c = v + w x (R com)``, the body-frame angular velocity ``w_b = R^T w`` and the inertia tensor
about the centre of mass in the body frame (``BodySpec.inertia_tensor()``). The energy watchdog
(runner.sim.energy) computes the same sum for hand-written bodies (com 0, principal axes the body's)."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from backends.types import BodyStates, CompiledWorld, JointStates, Quat, Vec3
from runner.language.names import split_owner
from runner.sim.body_quantities import BODY_VECTORS, body_quantity
from runner.sim.collisions import quat_matrices
from runner.sim.frames import frame_getter
from runner.sim.reactions import reaction_getter

_COMPONENT = {"x": 0, "y": 1, "z": 2}
_QUAT = {"w": 0, "x": 1, "y": 2, "z": 3}
_BODY_ARRAYS = {"pos": "pos", "vel": "lin_vel", "angvel": "ang_vel", "quat": "quat"}
_JOINT_ARRAYS = {"position": "position", "velocity": "velocity", "force": "motor_force"}


class Snapshot:
    """The latest recorded state, as the resolver reads it."""

    def __init__(self) -> None:
        self.time = 0.0
        self.bodies = BodyStates.from_rows(np.zeros((0, 13)))  # until the first read
        self.joints = JointStates(np.zeros(0), np.zeros(0), np.zeros(0))
        self.reactions = np.zeros((0, 6))  # CompiledWorld.reaction_joints' wrenches (Backend.joint_reactions)


class StateResolver:
    """Implements :class:`runner.language.expressions.Resolver` for a run. Getters are built once per name."""

    def __init__(
        self,
        world: CompiledWorld,
        groups: dict[str, list[str]],
        state: dict[str, Any],
        params: dict[str, Any],
        snapshot: Snapshot,
        functions: dict[str, Callable[[Sequence[Any]], Any]],
        *,
        eps: float,
        frames: dict[str, tuple[str, Vec3, Quat]] | None = None,
    ):
        self.world = world
        self.body_index = {b.name: i for i, b in enumerate(world.bodies)}
        self.joint_index = {j.name: i for i, j in enumerate(world.joints)}
        self.frames = frames or {}  # named frames on bodies (runner.sim.frames)
        self._members = frozenset(n for n in [*self.body_index, *self.joint_index, *self.frames] if "." in n)
        self.groups = {g: [self.body_index[n] for n in names] for g, names in groups.items()}
        self.members = {g: list(names) for g, names in groups.items()}
        self.state = state
        self.params = params
        self.snap = snapshot
        self.functions = functions
        self._getters: dict[str, Callable[[], Any]] = {}
        gx, gy, gz = world.gravity
        self._constants = {
            "dt": world.dt,
            "duration": world.duration,
            "g": math.sqrt(gx * gx + gy * gy + gz * gz),
            "gravity.x": gx,
            "gravity.y": gy,
            "gravity.z": gz,
            "eps": eps,  # the running engine's machine epsilon (backends.types.Precision)
        }

    def value(self, name: str) -> Any:
        getter = self._getters.get(name)
        if getter is None:
            getter = self._getters[name] = self._build(name)
        return getter()

    def call(self, func: str, args: Sequence[Any]) -> Any:
        return self.functions[func](args)

    def group_members(self, name: str) -> list[str] | None:
        """The bodies of array ``name``, in the order a group's values are listed (for failure messages)."""
        return self.members.get(name)

    def _build(self, name: str) -> Callable[[], Any]:  # noqa: C901 - one switch over the name forms
        snap = self.snap
        if name == "time":
            return lambda: snap.time
        if name in self._constants:
            value = self._constants[name]
            return lambda: value
        head, rest = split_owner(name, self._members)  # a robot's link or joint: `arm.link_7.pos.z`
        if head == "state":
            return lambda: self.state[rest]
        if head == "param":
            value = self.params[rest]
            return lambda: value
        if head in self.frames:
            body, pos, quat = self.frames[head]
            field, _, comp = rest.partition(".")
            return frame_getter(self.body_index[body], pos, quat, field, comp, lambda: snap.bodies)
        if head in self.joint_index and rest.startswith("reaction."):
            _, vector, comp = rest.split(".")
            return reaction_getter(self.world, head, vector, comp, lambda: (snap.bodies, snap.reactions))
        if head in self.joint_index and rest in _JOINT_ARRAYS:
            j, attr = self.joint_index[head], _JOINT_ARRAYS[rest]
            return lambda: float(getattr(snap.joints, attr)[j])
        rows: list[int] | int | None = self.body_index.get(head)
        if rows is None:
            rows = self.groups.get(head)
        if rows is None:
            raise KeyError(name)
        if rest == "energy":
            energy = self._energy_of([rows] if isinstance(rows, int) else rows)
            if isinstance(rows, int):
                return lambda: float(energy()[0])
            return lambda: energy().tolist()
        field, _, comp = rest.partition(".")
        if rest == "kinetic_energy" or (field in BODY_VECTORS and comp in _COMPONENT):
            return self._derived(rows, field, _COMPONENT.get(comp))
        if rest == "speed":
            if isinstance(rows, int):
                return lambda: float(np.linalg.norm(snap.bodies.lin_vel[rows]))
            group = _index(rows)
            return lambda: _norms(snap.bodies.lin_vel[group]).tolist()
        attr = _BODY_ARRAYS[field]
        col = (_QUAT if field == "quat" else _COMPONENT)[comp]
        if isinstance(rows, int):
            return lambda: float(getattr(snap.bodies, attr)[rows, col])
        group = _index(rows)
        return lambda: getattr(snap.bodies, attr)[group, col].tolist()

    def _derived(self, rows: list[int] | int, field: str, col: int | None) -> Callable[[], Any]:
        """A getter of a quantity of runner.sim.body_quantities (``col``: the component of a vector)."""
        members = [rows] if isinstance(rows, int) else rows
        specs = [self.world.bodies[i] for i in members]
        getter = body_quantity(field, specs, _index(members), lambda: self.snap.bodies)
        if col is None:
            return (lambda: float(getter()[0])) if isinstance(rows, int) else (lambda: getter().tolist())
        if isinstance(rows, int):
            return lambda: float(getter()[0, col])
        return lambda: getter()[:, col].tolist()

    def _energy_of(self, rows: list[int]) -> Callable[[], np.ndarray]:
        """A getter of the mechanical energy (J) of the bodies ``rows`` (the module docstring's sum)."""
        specs = [self.world.bodies[i] for i in rows]
        mass = np.array([b.mass for b in specs], float)
        com = np.array([b.com for b in specs], float).reshape(-1, 3)
        tensor = np.array([b.inertia_tensor() for b in specs], float).reshape(-1, 3, 3)
        gravity = np.asarray(self.world.gravity, float)
        group = _index(rows)
        snap = self.snap

        def energy() -> np.ndarray:
            states = snap.bodies
            rot = quat_matrices(states.quat[group])
            arm = np.einsum("nij,nj->ni", rot, com)  # R com: the centre of mass from the body origin
            v = states.lin_vel[group] + np.cross(states.ang_vel[group], arm)
            wb = np.einsum("nji,nj->ni", rot, states.ang_vel[group])  # R^T w
            spin = np.einsum("ni,nij,nj->n", wb, tensor, wb)
            return 0.5 * mass * np.add.reduce(v * v, axis=1) + 0.5 * spin - mass * ((states.pos[group] + arm) @ gravity)

        return energy


def _index(rows: list[int]) -> slice | np.ndarray:
    """A group's rows as a slice when they are consecutive (a view), else an index array (built once)."""
    if rows and rows == list(range(rows[0], rows[-1] + 1)):
        return slice(rows[0], rows[-1] + 1)
    return np.array(rows, dtype=np.intp)


def _norms(v: np.ndarray) -> np.ndarray:
    """Row norms of (N, 3) ``v``: what ``np.linalg.norm(v, axis=1)`` computes for real arrays (the same
    sum of squares and square root, numpy 2's special case for ord 2), without its argument checks."""
    return np.sqrt(np.add.reduce(v * v, axis=1))
