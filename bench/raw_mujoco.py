"""The pile on MuJoCo, written by hand with the adapter's settings (backends/mujoco, its settings()).

Every geom carries the ODE-style contact parameters of the world's surface and MuJoCo's own filtering
makes the contacts (only the dynamic boxes have a contype, so the static plane meets every box), as the
adapter builds it (docs/backends/mujoco.md), with the friction rows' reference of a bouncing surface
and ODE's normal reference of impacts and capped push-outs set by the adapter's engine step
function, so the physics is the same. The loop is one ``mj_step`` per step,
or, when the adapter's settings say its friction is "Coulomb" (sliding contacts' normal reference
corrected, several constraint solves per step), the adapter's own engine step function for that: it
is the physics, not the runner's overhead.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping
from typing import Any

import mujoco
import numpy as np

from backends.types import CompiledWorld, Motion, ShapeKind

from .raw_common import Servo, servo_rates


class MujocoLoop:
    def __init__(self, world: CompiledWorld, s: Mapping[str, Any]) -> None:
        h = s["timestep"]
        if s["integrator"] != "implicitfast" or s["cone"] != "elliptic" or s["solver"] != "Newton":
            raise ValueError(f"unexpected MuJoCo settings: {dict(s)}")
        erp_text = re.search(r"erp ([0-9.e+-]+), bounce_erp ([0-9.e+-]+)", s["contact_solref"])
        capped = re.fullmatch(r"\(-1, -min\(([0-9.e+-]+), ([0-9.e+-]+)/h\)\)", s["friction_solref"])
        plain = re.fullmatch(r"\(-1, -([0-9.e+-]+)/h\)", s["friction_solref"])
        if erp_text is None or (capped is None and plain is None):
            raise ValueError(f"unexpected MuJoCo settings: {dict(s)}")
        erp, bounce_erp = float(erp_text[1]), float(erp_text[2])
        friction_rate = min(float(capped[1]), float(capped[2]) / h) if capped else float(plain[1]) / h  # type: ignore[index]
        coulomb = "Coulomb" in str(s.get("friction", ""))
        spec = mujoco.MjSpec()
        spec.compiler.degree = False
        spec.option.timestep = h
        spec.option.gravity = list(world.gravity)
        spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
        spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
        spec.option.tolerance = s["tolerance"]
        spec.option.iterations = s["iterations"]
        spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_AUTORESET
        spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_FILTERPARENT
        impedance, mu_max = s["impedance"], s["mu_max"]
        surface = world.default_surface
        e = surface.bounce
        solref = [-(erp if e == 0.0 else bounce_erp) / h**2, -(1.0 + e) / h]
        mu = min(surface.mu, mu_max)
        solimp = [impedance, impedance, 0.001, 0.5, 2.0]
        # static bodies first, then the dynamic ones (the adapter's tree order)
        order = [b for b in world.bodies if b.motion is Motion.STATIC] + [
            b for b in world.bodies if b.motion is Motion.DYNAMIC
        ]
        for b in order:
            body = spec.worldbody.add_body(name=f"body:{b.name}", pos=list(b.pos), quat=list(b.quat))
            if b.motion is Motion.DYNAMIC:
                body.mass, body.inertia, body.explicitinertial = b.mass, list(b.inertia), True
                body.ipos, body.iquat = [0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]
                body.add_freejoint()
            if b.shape.kind is ShapeKind.PLANE:
                kind, size = mujoco.mjtGeom.mjGEOM_PLANE, [0.0, 0.0, 1.0]
            else:
                kind, size = mujoco.mjtGeom.mjGEOM_BOX, [x / 2.0 for x in b.shape.size]
            geom = body.add_geom(name=f"geom:{b.name}", type=kind, size=size, rgba=list(b.color))
            geom.contype, geom.conaffinity = (1 if b.motion is Motion.DYNAMIC else 0), 1
            geom.condim, geom.friction, geom.solref, geom.solimp = 3, [mu, 0.005, 0.0001], solref, solimp
        # a geom's friction rows take its (normal) solref; the adapter's friction reference is (-1, -rate)
        damping = None if solref[1] == -friction_rate else friction_rate / impedance
        names = [b.name for b in world.bodies]
        self.advance: Callable[[mujoco.MjModel, mujoco.MjData], object] = mujoco.mj_step
        if coulomb:
            from backends.mujoco import _coulomb
            from backends.mujoco._bounce import Impacts

            rest = (1.0 - impedance) * float(np.linalg.norm(world.gravity)) * h * h / bounce_erp
            impacts = Impacts(h, erp, s["max_correcting_vel"], rest, surface.bounce_vel)
            self.advance = lambda m, d: _coulomb.step(m, d, damping, impacts)
        self.m = spec.compile()
        self.d = mujoco.MjData(self.m)
        mujoco.mj_forward(self.m, self.d)  # the adapter bases the solver's scale on the dynamic bodies' inertia
        full = np.zeros((self.m.nv, self.m.nv))
        mujoco.mj_fullM(self.m, self.d, full)
        self.m.stat.meaninertia = float(np.mean(np.diag(full))) if self.m.nv else self.m.stat.meaninertia
        self.d = mujoco.MjData(self.m)
        self.ids = np.array([self.m.body(f"body:{n}").id for n in names])

    def step(self) -> None:
        self.advance(self.m, self.d)

    def read(self) -> np.ndarray:
        m, d = self.m, self.d
        mujoco.mj_kinematics(m, d)
        mujoco.mj_comPos(m, d)
        mujoco.mj_comVel(m, d)
        pos = d.xpos[self.ids]
        ang = d.cvel[self.ids, :3]
        lin = d.cvel[self.ids, 3:] + np.cross(ang, pos - d.subtree_com[m.body_rootid[self.ids]])
        return np.hstack([pos, d.xquat[self.ids], lin, ang])

    def close(self) -> None:
        del self.d, self.m


#: Issue 19: on MuJoCo the runner with the full trace is also held to 1.30 x this loop without reads
#: (bench/report_sections.py reads it here, so that bench/ names no engine outside its own loop).
TARGET_RATIO_RAW = 1.30

#: The loop bench/measure.py runs for this engine (found by the file name, bench/raw_<registry name>.py).
LOOP = MujocoLoop


class MujocoRobotLoop:
    """A robot on MuJoCo by hand (bench/robot.py), in the adapter's model: each servo's rate put on its
    motor's helper dof (the adapter's velocity motor: a tendon frictionloss row, docs/backends/mujoco.md),
    the adapter's engine step function (the physics), the motors' forces from ``qfrc_constraint``, then
    ``mj_kinematics``, ``mj_comPos`` and ``mj_comVel`` and every body's pose and velocity and every joint's
    position and velocity read as numpy arrays (no per-body Python)."""

    def __init__(self, adapter: Any, servos: list[Servo]) -> None:
        """``qpos`` counts from the model's zero, the runner's coordinate: no servo's ``zero`` is added."""
        from backends.mujoco import _coulomb

        self.m, self.d, lay = adapter._m, adapter._d, adapter._layout
        if adapter._nsteps != 1:
            raise ValueError("the hand-written robot loop makes one engine step per step")
        friction, impacts = lay.friction_damping, adapter._impacts
        self.advance: Callable[[], object]
        if adapter.world.model_options:
            self.advance = lambda: mujoco.mj_step(self.m, self.d)
        else:
            self.advance = lambda: _coulomb.step(self.m, self.d, friction, impacts)
        self.servos = servos
        slots = [int(adapter._motor_of[s.joint]) for s in servos]
        self.helper = adapter._helper_dof[slots]
        self.m.tendon_frictionloss[slots] = [s.fmax for s in servos]  # the motors' force bound, set once
        self.sign = adapter._sign[[s.joint for s in servos]]
        self.servo_q = self.m.jnt_qposadr[lay.joint_id[[s.joint for s in servos]]]
        self.all_helpers = adapter._helper_dof
        self.ids, self.root = lay.body_id, adapter._root
        self.rated = adapter._rated
        self.qadr, self.dadr, self.rated_sign = adapter._rated_qpos, adapter._rated_dof, adapter._sign[adapter._rated]
        self.q = [float(x) for x in self.sign * self.d.qpos[self.servo_q]]

    def step(self, targets: list[float]) -> None:
        d = self.d
        d.qvel[self.helper] = self.sign * np.array(servo_rates(self.servos, targets, self.q))
        self.advance()
        self.force = -d.qfrc_constraint[self.all_helpers]

    def read(self) -> None:
        m, d = self.m, self.d
        mujoco.mj_kinematics(m, d)
        mujoco.mj_comPos(m, d)
        mujoco.mj_comVel(m, d)
        ids = self.ids
        pos, quat, cvel = d.xpos[ids], d.xquat[ids], d.cvel[ids]
        ang = cvel[:, :3]
        lin = cvel[:, 3:] + np.cross(ang, pos - d.subtree_com[self.root])
        self.pos, self.quat, self.lin, self.ang = pos, quat, lin, ang
        self.qpos, self.qvel = d.qpos[self.qadr], d.qvel[self.dadr]
        self.q = [float(x) for x in self.sign * d.qpos[self.servo_q]]

    def joint_positions(self) -> dict[int, float]:
        return dict(zip(self.rated.tolist(), (self.rated_sign * self.qpos).tolist(), strict=True))


#: bench/robot.py's hand-written robot loop for this engine (built from the adapter's world).
ROBOT_LOOP = MujocoRobotLoop
