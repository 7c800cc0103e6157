"""The built world read back from ODE (``Backend.imported_model``): panda3d.ode's OdeBody, OdeMass, geoms and
joint parameters.

The OdeBody sits at the centre of mass (``dBodySetMass`` wants it there), so ``getPosition`` is the COM in
the world; ``getMass().getInertialTensor()`` is the tensor about it. A body's shapes are the geoms of the
space attached to it (a cylinder's capsule stand-in, ``_colliders``, left out). Per joint: its type,
``getAxis`` (world; a universal joint's ``getAxis1``) and
``getParamLoStop``/``HiStop`` (ODE's +-dInfinity: no stop). Damping is the adapter's implicit row's
(``_joint_dynamics``: c = 1 / CFM - a / h from the row's CFM; 0 without one). ODE has no joint friction, effort
or velocity parameter (the motor's FMax is the runner's command): those are None.
"""

from __future__ import annotations

from typing import Any

from .._kit.imported import body, principal, stops, unit
from ..types import CompiledWorld, ImportedBody, ImportedJoint, ImportedModel, JointKind, Motion
from ._build import Scene, axis_arg
from ._colliders import CAT_PRISM
from ._joint_dynamics import JointDynamics


def _geoms_per_body(space: Any, bodies: list[Any]) -> list[int]:
    count = [0] * len(bodies)
    for g in range(space.getNumGeoms()):
        geom = space.getGeom(g)
        if not geom.hasBody() or geom.getCategoryBits().getWord() == CAT_PRISM:  # a stand-in is no shape
            continue
        owner = geom.getBody()
        for i, b in enumerate(bodies):
            if b is not None and owner == b:
                count[i] += 1
                break
    return count


def read_imported(world: CompiledWorld, scene: Scene, dynamics: JointDynamics) -> ImportedModel:
    shapes = _geoms_per_body(scene.space, scene.bodies)
    out: list[ImportedBody] = []
    for i, spec in enumerate(world.bodies):
        ode_body = scene.bodies[i]
        if spec.motion is not Motion.DYNAMIC or ode_body is None:
            continue
        mass = ode_body.getMass()
        tensor = mass.getInertialTensor()
        rows = [[float(tensor.getCell(r, c)) for c in range(3)] for r in range(3)]
        pos = ode_body.getPosition()
        out.append(body(spec, float(mass.getMagnitude()), principal(rows), (pos[0], pos[1], pos[2]), shapes[i]))
    joints: list[ImportedJoint] = []
    for joint_spec, handle in zip(world.joints, scene.joints, strict=True):
        joint = handle.joint
        if joint_spec.kind not in (JointKind.HINGE, JointKind.SLIDER, JointKind.UNIVERSAL):
            joints.append(ImportedJoint(joint_spec.name, _kind(joint), None, None, None, None, None, None, None))
            continue
        axis = joint.getAxis1() if joint_spec.kind is JointKind.UNIVERSAL else joint.getAxis()
        arg = axis_arg(handle)
        lo, hi = stops(float(joint.getParamLoStop(*arg)), float(joint.getParamHiStop(*arg)))
        joints.append(ImportedJoint(joint_spec.name, _kind(joint), unit((axis[0], axis[1], axis[2])), lo, hi,
                                    dynamics.damping(handle), None, None, None))  # fmt: skip
    return ImportedModel("ode", tuple(out), tuple(joints))


def _kind(joint: Any) -> JointKind:
    """The ODE joint's class, as our kind."""
    names = {"OdeHingeJoint": JointKind.HINGE, "OdeSliderJoint": JointKind.SLIDER, "OdeBallJoint": JointKind.BALL,
             "OdeFixedJoint": JointKind.FIXED, "OdeUniversalJoint": JointKind.UNIVERSAL}  # fmt: skip
    return names.get(type(joint).__name__, JointKind.FIXED)
