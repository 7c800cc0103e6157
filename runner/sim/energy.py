"""The energy watchdog: a run whose bodies gain mechanical energy that nothing gave them stops (exit 3).

Nothing in a scene does work on its dynamic bodies except what the scenario drives (gravity is in the
energy), so their total mechanical energy

    E = sum over dynamic bodies of  1/2 m |v_c|^2  +  1/2 w^T I_world w  -  m g.p_c
        + sum over joints with armature a or stiffness k of  1/2 a qdot^2  +  1/2 k (q - ref)^2

at each body's centre of mass (``p_c = p + R com``, ``v_c = v + w x R com``: the states are the body
frame's, a robot link's COM is off its frame) with its full inertia tensor in world axes (``I_world = R
R_i diag(I) R_i^T R^T``, ``R_i`` the principal axes in the body frame, ``BodySpec.inertia_quat``) cannot
rise: restitution <= 1 gives back at most what an impact took, friction and damping only remove energy,
ideal joints do no work. An engine that creates energy (the MuJoCo pile of 100 boxes throws its top box
up at 29.5 m/s) is an engine failure, reported like a blow-up.

What the scenario drives (docs/semantics.md, "Energy watchdog"):

* motors: their work is booked, as an upper bound, ``|motor_force * joint velocity| * dt`` per joint and
  step (the step's mean force times the velocity at its end), and the check compares ``E - booked work``;
* one-step forces, resets, and kinematic bodies moving (or changing scale) over a step: the work they
  do through contacts is not known, so the check starts afresh from the state after such a step.

The reference and the bound. Energy may sink for a while and come back without anything being wrong:
a contact's penetration holds energy that position correction (ERP, 0.2 per step in the ODE mapping every
backend follows) gives back, 1 - 0.8^25 = 99.6 % of it within ``WINDOW_STEPS`` = 25 steps; the
integrators (semi-implicit Euler on all four engines) make the true energy of a motion of angular
frequency w oscillate between C/(1+a) and C/(1-a), a = w h / 2, around the energy C they conserve. So the
reference is the largest energy of the last 25 steps, and it only ever goes down (``R = min(R, max of the
window)``): a dip shorter than the window does not lower it, and energy lost for good lowers it 25
steps later. A motion whose period is shorter than the window has its maximum inside it and never rises
above the reference; a slower one (w h < 2 pi / 25, a < pi / 25) may, by at most 2a / (1 + a) < 0.223 of
its energy C, which its kinetic energy reaches at its fastest: hence ``GAIN_FRACTION`` = 0.25 of the
largest kinetic energy since the check (re)started, ``K_peak``. Bodies at rest carry none, but their
contacts and joints still correct a step's fall, ``g h^2``, each step, worth ``m |g|^2 h^2``; over the
window that is the floor ``sum(m) |g|^2 h * (25 h)``. Rounding adds ``4 N eps sum |E_i|``.

A rise of ``E - booked work`` above the reference by more than ``GAIN_FRACTION * K_peak + floor +
rounding`` raises :class:`~runner.errors.EnergyGain`, naming the body whose energy rose most since the
reference was taken. The check is a sum and a few products over the bodies, vectorised over the bodies and
over a block of ``BLOCK_STEPS`` steps at once: each whole-array call costs about 1 us whatever its size, so
the block's calls cost about what one step's did. The steps are then taken in order, one by one, as
before: the same reference, bound, time and body. What the block changes is only when a gain is found:
up to ``BLOCK_STEPS - 1`` steps after it happened. The session flushes the block before it reports any
other failure of the run (a blow-up, an engine error, an interruption) and at its end, so that a gain
that came first is the one reported (docs/semantics.md, "Energy watchdog").
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np

from backends.types import IDENTITY_QUAT, BodyStates, CompiledWorld, JointStates, Motion
from runner.errors import EnergyGain
from runner.sim.blowup import last_good_state

__all__ = ["BLOCK_STEPS", "GAIN_FRACTION", "WINDOW_STEPS", "BodyEnergy", "EnergyWatch", "body_energies"]

#: steps the reference looks back: ERP 0.2 corrects 1 - 0.8^25 = 99.6 % of a penetration within them
WINDOW_STEPS = 25
#: a slow motion's integrator error above the window's maximum: 2a/(1+a) with a = pi/25, < 0.223
GAIN_FRACTION = 0.25
#: steps whose energies are computed together (runner.sim.session flushes the block before it reports any
#: other failure and at the end of the run): the check's verdicts and times are those of a step-by-step check
BLOCK_STEPS = WINDOW_STEPS
_ROUNDING = 4 * float(np.finfo(float).eps)
_NONE = np.zeros(0)  # no joint stores energy
#: (3, 9): w -> its cross-product matrix, row-major ([w]x r = w x r), as one product for a whole array
_SKEW = np.zeros((3, 9))
_SKEW[2, 1], _SKEW[1, 2], _SKEW[2, 3], _SKEW[0, 5], _SKEW[1, 6], _SKEW[0, 7] = -1, 1, 1, -1, -1, 1


def _quat_matrix_form() -> np.ndarray:
    """(16, 9): the rotation matrix of a unit quaternion q = (w, x, y, z), row-major, as a linear map of its
    outer product q q^T flattened (each entry is a quadratic form: R00 = w2 + x2 - y2 - z2, R01 = 2 (xy - wz),
    ...), so that a whole array of matrices is one product."""
    form = np.zeros((4, 4, 3, 3))
    w, x, y, z = range(4)
    for i, (a, b, sign) in enumerate(((w, w, 1), (x, x, 1), (y, y, -1), (z, z, -1))):
        form[a, b, 0, 0] = sign
        form[a, b, 1, 1] = (1, -1, 1, -1)[i]
        form[a, b, 2, 2] = (1, -1, -1, 1)[i]
    for (a, b), (row, col), sign in (
        ((x, y), (0, 1), 1), ((w, z), (0, 1), -1), ((x, z), (0, 2), 1), ((w, y), (0, 2), 1),
        ((x, y), (1, 0), 1), ((w, z), (1, 0), 1), ((y, z), (1, 2), 1), ((w, x), (1, 2), -1),
        ((x, z), (2, 0), 1), ((w, y), (2, 0), -1), ((y, z), (2, 1), 1), ((w, x), (2, 1), 1),
    ):  # fmt: skip
        form[a, b, row, col] += sign  # 2 ab = ab + ba
        form[b, a, row, col] += sign
    return form.reshape(16, 9)


_QUAT_MATRIX = _quat_matrix_form()


class BodyEnergy:
    """(kinetic, total) mechanical energy of a fixed set of bodies (J), from their body-frame states:
    translational kinetic energy of the centre of mass, rotational about it, plus the gravitational
    -m g.p_com. ``com`` (N, 3) places each centre of mass in its body frame (None: at the origin) and
    ``tensor`` (N, 3, 3) is each inertia tensor about it in the body frame (None: ``inertia``, principal
    moments along the body axes).

    The check runs every step, mostly on a few to a hundred bodies, where each numpy call costs more than
    its arithmetic (about 1 us): what does not change between steps is made once here, the bodies'
    rotation matrices are one product (:func:`_quat_matrix_form`), the COM offset and the COM's velocity
    are one batched product each, and the rest a few whole-array calls."""

    def __init__(
        self,
        index: np.ndarray | slice,
        mass: np.ndarray,
        inertia: np.ndarray,
        gravity: np.ndarray,
        com: np.ndarray | None = None,
        tensor: np.ndarray | None = None,
    ) -> None:
        self.index = index
        self.half_mass = 0.5 * mass
        self.mass = mass
        self.gravity = gravity
        #: (N, 3, 1): each COM in its body frame, as the batched product takes it
        self.com = None if com is None else np.ascontiguousarray(com, float)[:, :, None]
        #: 1/2 the inertia: principal moments (N, 3), or the full tensor (N, 3, 3) in the body frame
        self.half_inertia = 0.5 * inertia
        self.half_tensor = None if tensor is None else 0.5 * tensor

    def __call__(self, states: BodyStates) -> tuple[np.ndarray, np.ndarray]:
        index = self.index
        return self.of_arrays(states.quat[index], states.ang_vel[index], states.pos[index], states.lin_vel[index])

    def of_arrays(
        self, quat: np.ndarray, w: np.ndarray, pos: np.ndarray, v: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """(kinetic, total) of these bodies' states, (..., N, 4) and (..., N, 3) arrays: one step's (N rows) or
        a block of steps' (K, N) at once, in the same whole-array calls."""
        lead = quat.shape[:-1]
        rot = ((quat[..., :, None] * quat[..., None, :]).reshape(*lead, 16) @ _QUAT_MATRIX).reshape(*lead, 3, 3)
        body_w = (w[..., None, :] @ rot)[..., 0, :]  # R^T w, the body-frame angular velocity
        if self.com is not None:
            offset = (rot @ self.com)[..., 0]  # R com: from the body frame's origin to the COM, world axes
            pos = pos + offset
            v = v + ((w @ _SKEW).reshape(*lead, 3, 3) @ offset[..., None])[..., 0]  # the COM's: v + w x offset
        if self.half_tensor is None:
            rotational = np.add.reduce(self.half_inertia * body_w * body_w, axis=-1)
        else:
            rotational = np.add.reduce((body_w[..., None, :] @ self.half_tensor)[..., 0, :] * body_w, axis=-1)
        kinetic = self.half_mass * np.add.reduce(v * v, axis=-1) + rotational
        return kinetic, kinetic - self.mass * (pos @ self.gravity)


def body_energies(
    states: BodyStates,
    index: np.ndarray | slice,
    mass: np.ndarray,
    inertia: np.ndarray,
    gravity: np.ndarray,
    com: np.ndarray | None = None,
    tensor: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """(kinetic, total) mechanical energy of the bodies ``index`` (J): :class:`BodyEnergy`'s, once."""
    return BodyEnergy(index, mass, inertia, gravity, com, tensor)(states)


def _stacked(arrays: list[np.ndarray]) -> np.ndarray:
    """``np.stack`` of same-shaped arrays by one ``concatenate``: a third of its time for a block of small ones."""
    return np.concatenate(arrays).reshape(len(arrays), *arrays[0].shape)


def totals_back(totals: deque[float], top: float) -> int:
    """How many steps back from the newest the newest of ``totals`` equal to ``top`` is."""
    newest_first = list(totals)
    newest_first.reverse()
    return newest_first.index(top)


class EnergyWatch:
    """Checks one run's energy after each step (see the module docstring)."""

    def __init__(self, world: CompiledWorld, backend: str, zeros: dict[str, float] | None = None) -> None:
        """``zeros``: what the runner adds to a joint's reading (from the start) to read it from its stated zero
        (program.joint_zeros): the readings checked are those, so each spring's rest moves with them."""
        self.backend = backend
        self.names = [b.name for b in world.bodies]
        self.joint_names = [j.name for j in world.joints]
        self.index = np.array([i for i, b in enumerate(world.bodies) if b.motion is Motion.DYNAMIC], dtype=int)
        first = int(self.index[0]) if self.index.size else 0
        contiguous = self.index.size and self.index[-1] - first == self.index.size - 1
        #: the same rows, as a slice when they are consecutive (a view, not a copy, of each state array)
        self.rows: np.ndarray | slice = slice(first, first + self.index.size) if contiguous else self.index
        self.mass = np.array([world.bodies[i].mass for i in self.index], float)
        self.inertia = np.array([world.bodies[i].inertia for i in self.index], float).reshape(-1, 3)
        bodies = [world.bodies[i] for i in self.index]
        offset = any(b.com != (0.0, 0.0, 0.0) for b in bodies)
        turned = any(b.inertia_quat != IDENTITY_QUAT for b in bodies)
        #: each COM in its body frame, and each full tensor in the body frame (None: not needed, as for every
        #: hand-written body, whose frame is its inertial frame)
        self.com = np.array([b.com for b in bodies], float).reshape(-1, 3) if offset else None
        self.tensor = np.array([b.inertia_tensor() for b in bodies], float).reshape(-1, 3, 3) if turned else None
        self.gravity = np.asarray(world.gravity, float)
        self._energy = BodyEnergy(self.rows, self.mass, self.inertia, self.gravity, self.com, self.tensor)
        self.motors = np.array([k for k, j in enumerate(world.joints) if j.motor is not None], dtype=int)
        #: the same joints as a slice when every joint has a motor (a robot's, usually: no copy per step)
        self._motor_rows: np.ndarray | slice = slice(None) if self.motors.size == len(world.joints) else self.motors
        #: joints whose coordinate holds energy of its own: a rotor's (armature) kinetic energy 1/2 a qdot^2 and
        #: a spring's (stiffness) 1/2 k (q - ref)^2, exchanged with the bodies' (docs/semantics.md, "Joint
        #: dynamics"); without them a rotor slowing down would read as the bodies gaining energy
        stored = [(k, j.dynamics) for k, j in enumerate(world.joints) if j.dynamics.armature or j.dynamics.stiffness]
        self.stored = np.array([k for k, _ in stored], dtype=int)
        self.armature = np.array([d.armature for _, d in stored], float)
        self.stiffness = np.array([d.stiffness for _, d in stored], float)
        moved = zeros or {}
        self.springref = np.array([d.springref + moved.get(world.joints[k].name, 0.0) for k, d in stored], float)
        self.dt = world.dt
        g2 = float(self.gravity @ self.gravity)
        self.floor = float(self.mass.sum()) * g2 * world.dt * (WINDOW_STEPS * world.dt)
        self.work = 0.0  # booked motor work so far (J)
        self._driven = True  # the first state is the first reference
        #: (total, each body's energy, each stored joint's rotor and spring energy) of the window's steps
        self._window: deque[tuple[float, np.ndarray, np.ndarray]] = deque(maxlen=WINDOW_STEPS + 1)
        self._totals: deque[float] = deque(maxlen=WINDOW_STEPS + 1)  # the window's totals, for a C-level max
        self._k_peak = 0.0  # the largest kinetic energy since the check (re)started
        self._reference = 0.0
        self._reference_at = 0.0
        self._reference_bodies = np.zeros(0)
        self._reference_joints = np.zeros(0)
        #: steps evaluated together (``check`` queues, ``flush`` evaluates): the whole-array calls cost about
        #: 1 us each whatever their size, so a block of 25 steps costs little more than one step did
        self.block = BLOCK_STEPS
        self._pending: list[tuple[float, BodyStates, JointStates, bool]] = []
        self._previous: tuple[float, BodyStates] | None = None  # the last step evaluated: time and states

    def driven(self) -> None:
        """Something did work of unknown amount during this step: the next check starts afresh."""
        self._driven = True

    def check(self, t: float, states: BodyStates, joints: JointStates) -> None:
        """The state after the step ending at ``t``. Taken with the block's other steps (``block``): raises
        EnergyGain, naming the step where the energy rose beyond the bound, when the block is evaluated."""
        if not self.index.size:
            return
        self._pending.append((t, states, joints, self._driven))
        self._driven = False
        if len(self._pending) >= self.block:
            self.flush()

    def flush(self) -> None:
        """Evaluate the steps checked and not yet evaluated; raises EnergyGain at the first one beyond the bound,
        with the named body's state at the step before it as its last good state."""
        if self._pending:
            pending, self._pending = self._pending, []
            self._evaluate(pending)

    def _evaluate(self, steps: list[tuple[float, BodyStates, JointStates, bool]]) -> None:
        """Each step's energies by whole-array calls over the block, then the reference and the bound step by
        step, in order, exactly as one step at a time."""
        rows = self.rows
        quat = _stacked([s[1].quat for s in steps])[:, rows]
        w = _stacked([s[1].ang_vel for s in steps])[:, rows]
        pos = _stacked([s[1].pos for s in steps])[:, rows]
        v = _stacked([s[1].lin_vel for s in steps])[:, rows]
        kinetic, energy = self._energy.of_arrays(quat, w, pos, v)  # (K, N)
        body_totals = np.add.reduce(energy, axis=1).tolist()
        kinetic_totals = np.add.reduce(kinetic, axis=1).tolist()
        works = [0.0] * len(steps)
        velocity = _stacked([s[2].velocity for s in steps]) if self.motors.size or self.stored.size else None
        if self.motors.size and velocity is not None:
            mrows = self._motor_rows
            force = _stacked([s[2].motor_force for s in steps])[:, mrows]
            power = np.abs(force * velocity[:, mrows])
            works = np.add.reduce(power, axis=1).tolist()
            for k, work in enumerate(works):
                if not math.isfinite(work):  # rare (a sum of |terms| is finite iff they all are, short of overflow)
                    works[k] = float(np.add.reduce(np.nan_to_num(power[k])))
        stored: np.ndarray | None = None
        stored_totals: list[float] = []
        rotor_totals: list[float] = []
        if self.stored.size and velocity is not None:
            rate = velocity[:, self.stored]
            stretch = _stacked([s[2].position for s in steps])[:, self.stored] - self.springref
            joint_kinetic = 0.5 * self.armature * rate * rate
            stored = joint_kinetic + 0.5 * self.stiffness * stretch * stretch
            stored_totals = np.nansum(stored, axis=1).tolist()
            rotor_totals = np.nansum(joint_kinetic, axis=1).tolist()
        # the bound's rounding term for each step: 4 N eps sum |E_i| (the module docstring)
        rounding = (_ROUNDING * energy.shape[1] * np.add.reduce(np.abs(energy), axis=1)).tolist()
        previous = self._previous
        window, totals, dt, floor = self._window, self._totals, self.dt, self.floor
        for k, (t, states, _, restart) in enumerate(steps):
            self.work += works[k] * dt
            total = body_totals[k] - self.work
            k_now = kinetic_totals[k]
            joints_now = _NONE
            if stored is not None:
                total += stored_totals[k]
                k_now += rotor_totals[k]
                joints_now = stored[k]
            entry = (total, energy[k], joints_now)
            if restart:  # the check starts afresh from this step
                window.clear()
                totals.clear()
                self._reference, self._reference_at = total, t
                self._reference_bodies, self._reference_joints = energy[k], joints_now
                self._k_peak = k_now
            else:
                if k_now > self._k_peak:
                    self._k_peak = k_now
                rise = total - self._reference
                if rise > 0.0:
                    bound = GAIN_FRACTION * self._k_peak + floor + rounding[k]
                    if rise > bound:
                        self._raise(t, rise, bound, energy[k], joints_now, previous)
            window.append(entry)
            totals.append(total)
            top = max(totals)  # the window's largest energy
            if top < self._reference:  # the newest entry holding it (steps back from now)
                back = totals_back(totals, top)
                self._reference, self._reference_at = top, t - back * dt
                self._reference_bodies = window[-1 - back][1]
                self._reference_joints = window[-1 - back][2]
            previous = (t, states)
        self._previous = previous

    def _raise(
        self,
        t: float,
        rise: float,
        bound: float,
        energy: np.ndarray,
        stored: np.ndarray,
        previous: tuple[float, BodyStates] | None,
    ) -> None:
        """Name the body, or the joint's rotor and spring (armature, stiffness), whose energy rose most, with the
        body's state at the step before (``previous``: time and states; None when there was none)."""
        gains = energy - self._reference_bodies
        k = int(np.argmax(gains))
        body = int(self.index[k])
        name, what, gain = self.names[body], "body", float(gains[k])
        if stored.size and self._reference_joints.size == stored.size:
            joint_gains = stored - self._reference_joints
            j = int(np.argmax(joint_gains))
            if joint_gains[j] > gain:
                body = -1
                name, what, gain = (
                    self.joint_names[int(self.stored[j])],
                    "the rotor and spring of joint",
                    float(joint_gains[j]),
                )
        raise EnergyGain(
            f"energy gain: {what} `{name}` gained {gain:.4g} J at t = {t:.4f} s on {self.backend} (the bodies' "
            f"energy rose {rise:.4g} J above its level at t = {self._reference_at:.4f} s with no work done on "
            f'them, beyond the bound of {bound:.4g} J; docs/semantics.md, "Energy watchdog")',
            backend=self.backend,
            body=name,
            time=t,
            last_good=None if previous is None or body < 0 else last_good_state(*previous, body),
        )
