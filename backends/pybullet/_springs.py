"""Joint springs on PyBullet: the spring's torque applied to the joint before every engine step.

PyBullet has no joint spring. A slider's or hinge's spring ``-k (q - ref)`` is applied as the joint's own
force (``TORQUE_CONTROL``, a one-step generalised force that leaves the joint's velocity motor in place,
measured: 0.4 N m for 10 steps on a 0.04 kg m^2 wheel with its motor off gives 0.100 rad/s; with a 0.1 N m
motor towards rest 0.175 rad/s), from the position at the start of the engine step. With PyBullet's
semi-implicit Euler that is the symplectic Euler step MuJoCo's Euler integrator takes with its own passive
spring force (computed at the step's start too): stable while ``w h < 2`` (``w = sqrt(k / I)``, I the
joint's effective inertia with its armature); the stiffest spring of dm_control's suite and pybullet_data
(cheetah's 240 N m/rad on its 0.1 kg m^2 armature and thigh, ``w`` about 50 rad/s) has ``w h`` = 0.1 at
dt = 2 ms.
"""

from __future__ import annotations

from typing import Any

from ..types import CompiledWorld, JointKind
from ._build import Layout


class Springs:
    """The world's joint springs: per engine step, each one's torque from its joint's position."""

    def __init__(self, world: CompiledWorld, layout: Layout) -> None:
        #: (body id, link, stiffness, rest in PyBullet's coordinate)
        self.joints = [
            (h.uid, h.link, j.dynamics.stiffness, h.sign * j.dynamics.springref)
            for j, h in zip(world.joints, layout.joints, strict=True)
            if j.dynamics.stiffness > 0 and j.kind in (JointKind.HINGE, JointKind.SLIDER) and h.dofs == 1
        ]

    def __bool__(self) -> bool:
        return bool(self.joints)

    def apply(self, p: Any, c: int) -> None:
        for uid, link, stiffness, rest in self.joints:
            q = p.getJointState(uid, link, physicsClientId=c)[0]
            p.setJointMotorControl2(uid, link, p.TORQUE_CONTROL, force=-stiffness * (q - rest), physicsClientId=c)
