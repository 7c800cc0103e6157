"""Joint armature and joint springs on Drake (``joint:armature``, ``joint:stiffness``; docs/backends/drake.md).

* **Armature** a (MuJoCo's ``dof_armature``: a added to the joint's diagonal entry of the mass matrix and
  nothing else) is Drake's reflected inertia of the joint's actuator: rotor inertia a at gear ratio 1, so
  ρ² I_r = a. MultibodyTree adds each actuated dof's reflected inertia to the mass matrix diagonal
  (``CalcMassMatrix``), to the articulated body inertias and to the kinetic energy, whatever the actuator's
  input; SAP treats it implicitly, as MuJoCo's Euler step does (drake multibody/tree/multibody_tree.cc,
  multibody/plant/sap_driver.cc). The actuator is the joint's PD motor that every slider and hinge already
  has (``_build``): Drake reads one actuator per dof, so a second one would not add.
* **Stiffness** k with rest ``springref`` (counted from the start, where Drake's q is 0): a
  ``RevoluteSpring`` / ``PrismaticSpring`` force element, -k (q - q0) with q0 the rest in Drake's coordinate
  (``sign`` x the world's). Force elements are evaluated at the step's start state (explicit), as MuJoCo's
  passive spring under its Euler integrator: the same semi-implicit Euler step.

Both exist for one-dof joints only; a ball or free joint's (``joint:ball-dynamics``) is refused up front.
"""

from __future__ import annotations

from typing import Any

from pydrake.multibody.tree import PrismaticSpring, RevoluteSpring

from ..errors import UnsupportedFeature
from ..types import CompiledWorld, JointKind

_ONE_DOF = (JointKind.HINGE, JointKind.SLIDER)


def check(world: CompiledWorld) -> None:
    """Refuse armature or a spring on a joint that is not a slider or hinge (no engine call)."""
    for spec in world.joints:
        dyn = spec.dynamics
        if spec.kind not in _ONE_DOF and (dyn.armature > 0 or dyn.stiffness > 0):
            raise UnsupportedFeature(
                f"Backend `drake` maps armature and stiffness on sliders and hinges only (Drake's reflected inertia "
                f"and joint springs are one-dof); joint `{spec.name}` is a {spec.kind.value} joint."
            )


def add(plant: Any, handle: Any) -> None:
    """Give ``handle``'s joint (a ``JointHandle`` of a slider or hinge, its actuator made) its armature and
    spring, before ``Finalize``."""
    dyn = handle.spec.dynamics
    if dyn.armature > 0:
        handle.actuator.set_default_gear_ratio(1.0)
        handle.actuator.set_default_rotor_inertia(dyn.armature)
    if dyn.stiffness > 0:
        spring = RevoluteSpring if handle.spec.kind is JointKind.HINGE else PrismaticSpring
        plant.AddForceElement(spring(handle.joint, handle.sign * dyn.springref, dyn.stiffness))


__all__ = ["add", "check"]
