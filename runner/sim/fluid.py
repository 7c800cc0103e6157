"""MuJoCo's inertia-box fluid model (MJCF `<option density viscosity wind>`) as forces the runner hands every
engine but MuJoCo before each step (docs/semantics.md, "Fluid forces").

MuJoCo's mj_inertiaBoxFluidModel (engine_passive.c), for each body of mass m > 0 with principal moments
I_0, I_1, I_2 about its centre of mass:

* the equivalent box: d_i = sqrt(6 (I_j + I_k - I_i) / m) along principal axis i ({i, j, k} = {0, 1, 2};
  the difference floored at 1e-15, MuJoCo's mjMINVAL), and the sphere diameter d = (d_0 + d_1 + d_2) / 3;
* v, w: the velocity of the centre of mass relative to the wind, and the angular velocity, in the principal
  axes;
* viscosity beta > 0: force -3 pi beta d v, torque -pi beta d^3 w;
* density rho > 0: force_i -= rho d_j d_k |v_i| v_i / 2, torque_i -= rho d_i (d_j^4 + d_k^4) |w_i| w_i / 64;
* turned back to the world's axes and applied at the centre of mass.

MuJoCo adds them to its passive forces from the state at the start of the step (explicitly under its Euler
integrator); here the same: computed from the state read at the step's start and given to the engine as that
step's force at the centre of mass and torque (``Backend.apply_force``, held over every substep).
"""

from __future__ import annotations

import numpy as np

from backends.geometry import quat_matrices
from backends.types import BodyStates, CompiledWorld, Fluid, Motion

#: MuJoCo's mjMINVAL: the floor of a box side's square (times m / 6) and of a body's mass
MIN_VALUE = 1e-15


def box_sides(mass: float, moments: tuple[float, float, float]) -> np.ndarray:
    """The sides of the inertia-equivalent box along the principal axes (MuJoCo's ``box``)."""
    i0, i1, i2 = moments
    diffs = np.array([i1 + i2 - i0, i0 + i2 - i1, i0 + i1 - i2], dtype=float)
    return np.sqrt(np.maximum(MIN_VALUE, diffs) / mass * 6.0)


class FluidForces:
    """The fluid's wrench on every dynamic body with mass, computed from the states at a step's start; none
    where the engine runs the file's fluid itself (``native``: MuJoCo)."""

    def __init__(self, world: CompiledWorld, native: bool) -> None:
        self.fluid = world.fluid if world.fluid is not None else Fluid()
        #: a wind can push bodies (do work on them), whoever computes the forces; without one they only take
        #: energy away (decided once: the step loop asks every step)
        self.adds_energy = any(self.fluid.wind)
        moving = [i for i, b in enumerate(world.bodies) if b.motion is Motion.DYNAMIC and b.mass >= MIN_VALUE]
        self.bodies = np.asarray(moving if world.fluid is not None and not native else [], dtype=np.int64)
        specs = [world.bodies[i] for i in self.bodies]
        self.sides = np.array([box_sides(b.mass, b.inertia) for b in specs]).reshape(-1, 3)
        self.com = np.array([b.com for b in specs], dtype=float).reshape(-1, 3)
        self.axes = quat_matrices(np.array([b.inertia_quat for b in specs], dtype=float).reshape(-1, 4))

    def __bool__(self) -> bool:
        return len(self.bodies) > 0

    def wrenches(self, states: BodyStates) -> tuple[np.ndarray, np.ndarray]:
        """(K, 3) world forces at the centres of mass and (K, 3) world torques of :attr:`bodies`."""
        i = self.bodies
        frames = quat_matrices(np.asarray(states.quat[i], dtype=float))
        omega = np.asarray(states.ang_vel[i], dtype=float)
        arm = np.einsum("nij,nj->ni", frames, self.com)
        v_com = np.asarray(states.lin_vel[i], dtype=float) + np.cross(omega, arm)
        axes = frames @ self.axes  # the principal axes in the world, as columns
        v = np.einsum("nji,nj->ni", axes, v_com - np.asarray(self.fluid.wind, dtype=float))
        w = np.einsum("nji,nj->ni", axes, omega)
        force, torque = np.zeros_like(v), np.zeros_like(w)
        d = self.sides
        if self.fluid.viscosity > 0:
            diameter = d.sum(axis=1, keepdims=True) / 3.0
            torque -= np.pi * diameter**3 * self.fluid.viscosity * w
            force -= 3.0 * np.pi * diameter * self.fluid.viscosity * v
        if self.fluid.density > 0:
            rho = self.fluid.density
            j, k = [1, 0, 0], [2, 2, 1]
            force -= 0.5 * rho * d[:, j] * d[:, k] * np.abs(v) * v
            torque -= rho * d * (d[:, j] ** 4 + d[:, k] ** 4) * np.abs(w) * w / 64.0
        return np.einsum("nij,nj->ni", axes, force), np.einsum("nij,nj->ni", axes, torque)
