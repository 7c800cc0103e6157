"""The pile on ODE (panda3d.ode), written by hand with the adapter's settings (backends/ode, its settings()).

The PyODE-style world: ERP, CFM, a simple space, contacts made in C++ by ``autoCollide`` with one
surface-table entry (the adapter's default ``collide: auto``), ``world.step`` (or ``quickStep``) and the
contact group emptied after each step.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from panda3d.core import BitMask32, Datagram, Quat
from panda3d.ode import (
    OdeBody,
    OdeBoxGeom,
    OdeHashSpace,
    OdeJointGroup,
    OdeMass,
    OdePlaneGeom,
    OdeSimpleSpace,
    OdeUtil,
    OdeWorld,
)

from backends.types import CompiledWorld, Motion, ShapeKind

_STATIC, _DYNAMIC = 1, 4  # the adapter's category bits: static geoms collide with dynamic ones only


def ode_body(w: Any, b: Any) -> Any:
    """A dynamic body of the compiled world ``b`` in the OdeWorld ``w``: mass, inertia, pose, velocities."""
    body = OdeBody(w)
    mass = OdeMass()
    mass.setParameters(b.mass, 0.0, 0.0, 0.0, *b.inertia, 0.0, 0.0, 0.0)
    body.setMass(mass)
    body.setPosition(*b.pos)
    body.setQuaternion(Quat(*b.quat))
    body.setLinearVel(*b.lin_vel)
    body.setAngularVel(*b.ang_vel)
    return body


class OdeLoop:
    def __init__(self, world: CompiledWorld, s: Mapping[str, Any]) -> None:
        if s["collide"] != "auto":
            raise ValueError(f"unexpected ODE settings: {dict(s)}")
        self.h = world.dt
        self.w = w = OdeWorld()
        w.setGravity(*world.gravity)
        w.setErp(s["erp"])
        w.setCfm(s["cfm"])
        w.setContactMaxCorrectingVel(s["max_correcting_vel"])
        w.setQuickStepNumIterations(s["quickstep_iterations"])
        self.stepper = w.step if s["stepper"] == "dWorldStep" else w.quickStep
        self.space = space = OdeSimpleSpace() if s["space"] == "simple" else OdeHashSpace()
        self.group = OdeJointGroup()
        self.bodies: list[Any] = []
        self.geoms: list[Any] = []
        for b in world.bodies:
            if b.shape.kind is ShapeKind.PLANE:  # the plane through pos with normal +z (these worlds' planes)
                geom = OdePlaneGeom(space, 0.0, 0.0, 1.0, b.pos[2])
            else:
                geom = OdeBoxGeom(space, *b.shape.size)
            static = b.motion is Motion.STATIC
            geom.setCategoryBits(BitMask32(_STATIC if static else _DYNAMIC))
            geom.setCollideBits(BitMask32(_DYNAMIC if static else _STATIC | 2 | _DYNAMIC))
            body = None
            if not static:
                body = ode_body(w, b)
                geom.setBody(body)
            self.bodies.append(body)
            self.geoms.append(geom)
        surface = world.default_surface
        mu = OdeUtil.getInfinity() if math.isinf(surface.mu) else surface.mu
        w.initSurfaceTable(1)
        w.setSurfaceEntry(0, 0, mu, surface.bounce, surface.bounce_vel, 0.0, w.getCfm(), 0.0, 0.0)
        space.setAutoCollideWorld(w)
        space.setAutoCollideJointGroup(self.group)
        self.dynamic_at = np.array([i for i, b in enumerate(self.bodies) if b is not None], dtype=int)
        self.dynamic = [b for b in self.bodies if b is not None]
        self.fixed_rows = np.zeros((len(world.bodies), 13))
        self.fixed_rows[:, :7] = [list(b.pos) + list(b.quat) for b in world.bodies]

    def step(self) -> None:
        self.space.autoCollide()
        self.stepper(self.h)
        self.group.empty()

    def read(self) -> np.ndarray:
        """Four getters per body, each vector written as ODE's float32 values into one datagram."""
        rows = self.fixed_rows.copy()
        if self.dynamic:
            dg = Datagram()
            for body in self.dynamic:
                body.getPosition().writeDatagramFixed(dg)
                body.getQuaternion().writeDatagramFixed(dg)
                body.getLinearVel().writeDatagramFixed(dg)
                body.getAngularVel().writeDatagramFixed(dg)
            rows[self.dynamic_at] = np.frombuffer(dg.getMessage(), dtype="<f4").reshape(-1, 13)
        return rows

    def close(self) -> None:
        self.group.empty()
        self.group.destroy()
        for geom in self.geoms:
            geom.destroy()
        for body in self.bodies:
            if body is not None:
                body.destroy()
        self.space.destroy()
        self.w.destroy()


#: The loop bench/measure.py runs for this engine (found by the file name, bench/raw_<registry name>.py).
LOOP = OdeLoop
