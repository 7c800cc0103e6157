"""A URDF joint's reading: its limits and start (0 clamped into them), its `<mimic>` in the description's
coordinates, its `<dynamics>` and `<limit>` as joint dynamics, its motion as a matrix, and the joints in
tree order."""

from __future__ import annotations

import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from backends.types import NO_DYNAMICS, JointDynamics
from runner.language.robot_desc import MimicDesc, ModelFileError


def _start(lo: float | None, hi: float | None) -> float:
    """Where a joint starts: 0, clamped into its limits (a1, aliengo and kuka_iiwa/model_vr_limits put 0
    outside them; pybullet leaves such a joint outside and its stop then throws the robot)."""
    if lo is None or hi is None:
        return 0.0
    return float(min(max(0.0, lo), hi))


def joint_limits(joint: Any) -> tuple[float | None, float | None]:
    """A revolute or prismatic joint's limits as the file gives them; lower > upper is no limit (pybullet's
    convention: cube_no_rotation.urdf)."""
    lo = hi = None
    if joint.type in ("revolute", "prismatic") and joint.limit is not None:
        lo, hi = joint.limit.lower, joint.limit.upper
    if lo is not None and hi is not None and lo > hi:
        return None, None
    return lo, hi


def joint_starts(joints: list[Any], file: Path, lines: dict[str, int]) -> tuple[dict[str, float], dict[str, MimicDesc]]:
    """Each joint's start (:func:`_start`; 0 for a `<mimic>` joint, which the compiler starts where its
    leader puts it: runner.compile.robot_start.mimic_starts) and each `<mimic>` in the description's
    coordinates (a leader started inside its limits counts from there, so the offset takes in multiplier x
    that start). A mimic naming a joint the model lacks, itself, a joint that is not revolute, continuous or
    prismatic, or a loop of mimics is refused at its line (``lines``: the <mimic> element's, by joint)."""
    by_name = {j.name: j for j in joints}
    followed = {j.name: j for j in joints if j.mimic is not None}
    starts = {j.name: 0.0 if j.name in followed else _start(*joint_limits(j)) for j in joints}
    scalar = ("revolute", "continuous", "prismatic")
    mimics = {}
    for name, joint in followed.items():
        line, leader = lines.get(name, 0), joint.mimic.joint
        what = f"joint `{name}`: <mimic joint={leader!r}>"
        if leader not in by_name or leader == name:
            why = "names itself" if leader == name else "names a joint the model does not define"
            raise ModelFileError(file, line, f"{what} {why}", near="<mimic")
        if joint.type not in scalar or by_name[leader].type not in scalar:
            raise ModelFileError(file, line, f"{what}: both joints must be revolute, continuous or prismatic "
                                 f"(they are {joint.type} and {by_name[leader].type})", near="<mimic")  # fmt: skip
        m = 1.0 if joint.mimic.multiplier is None else float(joint.mimic.multiplier)
        c = 0.0 if joint.mimic.offset is None else float(joint.mimic.offset)
        if not (math.isfinite(m) and math.isfinite(c)):
            raise ModelFileError(file, line, f"{what}: multiplier {m} and offset {c} must be finite", near="<mimic")
        chain, at = [name], leader
        while at in followed:  # a loop of mimics has no joint to start from
            if at in chain:
                loop = " -> ".join([*chain, at])
                raise ModelFileError(file, line, f"joint `{name}`: its <mimic> joints form a loop ({loop})",
                                     near="<mimic")  # fmt: skip
            chain.append(at)
            at = followed[at].mimic.joint
        mimics[name] = MimicDesc(leader, m, m * starts[leader] + c)
    return starts, mimics


def joint_motion(kind: str, axis: np.ndarray, q: float) -> np.ndarray:
    """The joint's own motion by ``q`` (rad or m) along its unit ``axis``, as a 4x4 matrix."""
    out = np.eye(4)
    if q == 0.0:
        return out
    if kind == "prismatic":
        out[:3, 3] = axis * q
        return out
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    out[:3, :3] = np.eye(3) + math.sin(q) * k + (1 - math.cos(q)) * (k @ k)  # Rodrigues
    return out


def joint_dynamics(joint: Any, kind: str, file: Path, line: int) -> JointDynamics:
    """`<dynamics damping friction>` and `<limit effort velocity>` of a hinge or slider (docs/semantics.md,
    "Joint dynamics"); `friction` is dry joint friction (friction loss). An effort or velocity of 0 (or none)
    is no limit, as the loaders read it (many files write 0 for "not stated")."""
    if kind not in ("hinge", "slider"):
        return NO_DYNAMICS
    dyn, limit = joint.dynamics, joint.limit
    values = {
        "damping": dyn.damping if dyn is not None else None,
        "friction": dyn.friction if dyn is not None else None,
        "effort": limit.effort if limit is not None else None,
        "velocity": limit.velocity if limit is not None else None,
    }
    for what, value in values.items():
        if value is not None and not (math.isfinite(float(value)) and float(value) >= 0):
            raise ModelFileError(file, line, f"joint `{joint.name}`: {what} {value} is not a number >= 0", near=what)
    number = {k: float(v) if v is not None else 0.0 for k, v in values.items()}
    return JointDynamics(
        damping=number["damping"],
        frictionloss=number["friction"],
        effort=number["effort"] or None,
        velocity=number["velocity"] or None,
    )


def parents_first(root: str, joints: list[Any]) -> Iterator[Any]:
    """Joints parents first."""
    by_parent: dict[str, list[Any]] = {}
    for joint in joints:
        by_parent.setdefault(joint.parent, []).append(joint)
    stack = [root]
    while stack:
        for joint in by_parent.get(stack.pop(), []):
            yield joint
            stack.append(joint.child)
