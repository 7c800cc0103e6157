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
#: (bench/report.py reads it here, so that bench/ names no engine outside its own loop).
TARGET_RATIO_RAW = 1.30

#: The loop bench/measure.py runs for this engine (found by the file name, bench/raw_<registry name>.py).
LOOP = MujocoLoop
