"""Cross-reference checks of robots' parts: a start (`initial`) inside the joints' stops, motors on robot
joints, the links a joint holds (runner.language.refs runs them)."""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from typing import Any

from runner.language.model import Scenario
from runner.language.robot_desc import ModelDesc
from runner.language.semantics import unknown
from runner.language.yaml_source import Path


def jointed_links(robots: Mapping[str, ModelDesc]) -> Iterator[str]:
    """The robots' links at either end of a joint (a free joint holds nothing)."""
    for name, desc in robots.items():
        for j in desc.joints:
            if j.kind != "free":
                yield f"{name}.{j.parent}"
                yield f"{name}.{j.child}"


def check_motor(
    model: Scenario, bad: Any, path: Path, ref: str, robots: Mapping[str, ModelDesc], field: str = "motor"
) -> None:
    """A motor (or a drive: ``field``) drives a slider or hinge: a hand-written one, or a robot's without a
    servo."""
    kinds: dict[str, str] = {name: j.type for name, j in model.joints.items()}
    kinds.update({f"{r}.{j.name}": j.kind for r, desc in robots.items() for j in desc.joints if j.kind != "free"})
    kind = kinds.get(ref)
    robot, _, joint = ref.partition(".")
    if kind is None:
        bad(path + (field, "joint"), unknown("joint", ref, kinds))
    elif kind not in ("slider", "hinge"):
        bad(path + (field, "joint"), f"joint `{ref}` is a {kind}; {field}s drive sliders and hinges")
    elif robot in model.robots and joint in model.robots[robot].joints and model.robots[robot].joints[joint].servo:
        bad(path + (field, "joint"), f"joint `{ref}` has a servo, which sets its motor every step")


def _joint_limits(robot: Any, joint: Any) -> tuple[float | None, float | None]:
    """A robot joint's stops from the model's zero: the scenario's override, else the model's."""
    override = robot.joints.get(joint.name)
    if override is not None and override.free:
        return None, None
    if override is not None and override.limits is not None:
        limits = override.limits
        return (limits.lo, limits.hi) if not isinstance(limits, tuple) else limits
    return joint.lo, joint.hi


def check_initial(model: Scenario, bad: Any, robots: Mapping[str, ModelDesc]) -> None:
    """A start names the model's hinges and sliders (or keyframe), inside their stops."""
    for rname, robot in model.robots.items():
        start, desc = robot.initial, robots.get(rname)
        if start is None or desc is None:
            continue
        here: tuple[str | int, ...] = ("robots", rname, "initial")
        if start.moving_root and (robot.fixed or robot.format != "urdf"):
            field = "vel" if any(start.vel) else "angvel"
            why = "is welded to the world (`fixed`)" if robot.fixed else "is an MJCF model (its root is the world)"
            bad(here + (field,), f"a start velocity is for a free root link; robot `{rname}` {why}")
        joints = {j.name: j for j in desc.joints}
        values: dict[str, tuple[tuple[float, float], tuple[str | int, ...]]] = {}
        if start.keyframe is not None:
            key = desc.keyframe(start.keyframe)
            if key is None:
                names = [k.name for k in desc.keyframes]
                bad(here + ("keyframe",), unknown("keyframe (MJCF <key>)", start.keyframe, names))
            elif key.others:
                bad(here + ("keyframe",), f"keyframe `{key.name}` moves the free or ball joint(s) "
                    f"{', '.join(f'`{j}`' for j in key.others)}; a start is taken for hinges and slides only")
            else:
                values.update({j: ((q, v), here + ("keyframe",)) for j, q, v in key.values})
        for jname, value in start.values().items():
            given = start.joints[jname]
            values[jname] = (value, here + ("joints", jname) + (() if isinstance(given, float | int) else ("pos",)))
        for jname, ((q, _), path) in values.items():
            joint = joints.get(jname)
            if joint is None:
                bad(here + ("joints", jname) if jname in start.joints else path, unknown("joint", jname, joints),
                    at_key=jname in start.joints)  # fmt: skip
                continue
            if joint.kind not in ("hinge", "slider"):
                bad(path, f"joint `{jname}` is a {joint.kind}; a start position is for hinges and sliders")
                continue
            lo, hi = _joint_limits(robot, joint)
            if (lo is not None and q < lo) or (hi is not None and q > hi):
                shown = f"[{'-inf' if lo is None else f'{lo:g}'}, {'inf' if hi is None else f'{hi:g}'}]"
                bad(path, f"joint `{jname}` starts at {q:g}, outside its limits {shown} (from the model's zero)")
