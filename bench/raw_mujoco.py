"""The pile on MuJoCo, written by hand with the adapter's settings (backends/mujoco, its settings()).

Every pair that can touch gets an explicit contact pair with the ODE-style solref, as the adapter
builds it (docs/backends/mujoco.md), so the physics is the same. The loop is one ``mj_step`` per step,
or, when the adapter's settings say its friction is "Coulomb" (sliding contacts' normal reference
corrected, several constraint solves per step), the adapter's own engine step function for that: it
is the physics, not the runner's overhead.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
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
        self.advance = mujoco.mj_step
        if "Coulomb" in str(s.get("friction", "")):
            from backends.mujoco import _coulomb

            self.advance = _coulomb.step
        impedance, mu_max = s["impedance"], s["mu_max"]
        spec = mujoco.MjSpec()
        spec.compiler.degree = False
        spec.option.timestep = h
        spec.option.gravity = list(world.gravity)
        spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
        spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
        spec.option.tolerance = s["tolerance"]
        spec.option.iterations = s["iterations"]
        spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_AUTORESET
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
            geom.contype = geom.conaffinity = 0
        surface = world.default_surface
        e = surface.bounce
        solref = [-(erp if e == 0.0 else bounce_erp) / h**2, -(1.0 + e) / h]
        solreffriction = [-1.0, -friction_rate]
        mu = min(surface.mu, mu_max)
        solimp = [impedance, impedance, 0.001, 0.5, 2.0]
        names = [b.name for b in world.bodies]
        dynamic = [b.motion is Motion.DYNAMIC for b in world.bodies]
        for i, a in enumerate(names):
            for j in range(i + 1, len(names)):
                if dynamic[i] or dynamic[j]:
                    spec.add_pair(
                        geomname1=f"geom:{a}", geomname2=f"geom:{names[j]}", condim=3,
                        friction=[mu, mu, 0.005, 0.0001, 0.0001], solref=solref, solreffriction=solreffriction,
                        solimp=solimp,
                    )  # fmt: skip
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


#: The loop bench/measure.py runs for this engine (found by the file name, bench/raw_<registry name>.py).
LOOP = MujocoLoop
