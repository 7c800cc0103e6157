"""The names a scenario defines: bodies (arrays expanded), groups, joints, and what expressions may read."""

from __future__ import annotations

from collections.abc import Container, Mapping
from dataclasses import dataclass

from runner.language.model import Scenario
from runner.language.model_names import spelled
from runner.language.model_physics import Body
from runner.language.robot_desc import ModelDesc

BODY_FIELDS = {
    "pos": ("x", "y", "z"),
    "vel": ("x", "y", "z"),
    "angvel": ("x", "y", "z"),
    "quat": ("w", "x", "y", "z"),
    # runner.sim.body_quantities: from the state and the mass properties
    "momentum": ("x", "y", "z"),
    "angmom": ("x", "y", "z"),
    "angmom_origin": ("x", "y", "z"),
    "angvel_body": ("x", "y", "z"),
}
BODY_SCALARS = ("speed", "energy", "kinetic_energy")
JOINT_FIELDS = ("position", "velocity", "force")
#: the wrench a joint applies to its first body, measured by the engine (runner.sim.reactions): force and
#: torque about the joint's anchor in world axes, and the same in the body's axes
REACTION_FIELDS = ("reaction",)
REACTION_VECTORS = ("force", "torque", "force_body", "torque_body")
GLOBALS = ("time", "dt", "duration", "g", "gravity.x", "gravity.y", "gravity.z", "eps")
RESERVED = frozenset(
    {
        "time",
        "dt",
        "duration",
        "g",
        "eps",
        "gravity",
        "state",
        "param",
        "environment",
        "world",
        "true",
        "false",
        "pi",
        "e",
        "inf",
    }
)


@dataclass(frozen=True)
class BodyInstance:
    """A body as the world has it: a single body, or one copy of an array, with its key and index."""

    name: str  # e.g. "crate_3" for an array copy, else the key
    key: str  # the key in `bodies`
    index: tuple[int, int, int]  # (ix, iy, iz) within the array; (0, 0, 0) for a single body
    body: Body


def array_counts(body: Body) -> tuple[int, int, int]:
    if body.array is None:
        return (1, 1, 1)
    count = body.array.count
    return (1, 1, count) if isinstance(count, int) else count


def expand_bodies(model: Scenario) -> list[BodyInstance]:
    out: list[BodyInstance] = []
    for key, body in model.bodies.items():
        if body.array is None:
            out.append(BodyInstance(key, key, (0, 0, 0), body))
            continue
        nx, ny, nz = array_counts(body)
        n = 0
        for iz in range(nz):
            for iy in range(ny):
                for ix in range(nx):
                    out.append(BodyInstance(f"{key}_{n}", key, (ix, iy, iz), body))
                    n += 1
    return out


def groups(model: Scenario) -> dict[str, list[str]]:
    """Array name -> its copies' names."""
    out: dict[str, list[str]] = {}
    for inst in expand_bodies(model):
        if inst.body.array is not None:
            out.setdefault(inst.key, []).append(inst.name)
    return out


def robot_links(robots: Mapping[str, ModelDesc]) -> list[str]:
    """The bodies the robots add: `<robot>.<link>`."""
    return [f"{name}.{link.name}" for name, desc in robots.items() for link in desc.links]


def robot_groups(robots: Mapping[str, ModelDesc]) -> dict[str, list[str]]:
    """Robot -> its links' body names (a robot is the group of its links)."""
    return {name: [f"{name}.{link.name}" for link in desc.links] for name, desc in robots.items()}


def robot_joints(robots: Mapping[str, ModelDesc]) -> list[str]:
    """The joints the robots add: `<robot>.<joint>` (a free joint is no joint)."""
    return [f"{name}.{j.name}" for name, desc in robots.items() for j in desc.joints if j.kind != "free"]


#: what a named frame on a link gives (runner.sim.frames): its pose, its origin's velocity, its angular velocity
FRAME_FIELDS = ("pos", "quat", "vel", "angvel")


def robot_frames(
    robots: Mapping[str, ModelDesc],
) -> dict[str, tuple[str, tuple[float, float, float], tuple[float, float, float, float]]]:
    """`<robot>.<frame>` -> (the body that carries it, its position and orientation in that body's frame): the
    models' named frames (MJCF sites, merged URDF links) that are not a link's or joint's name."""
    out = {}
    for name, desc in robots.items():
        taken = {link.name for link in desc.links} | {j.name for j in desc.joints}
        for frame in desc.frames:
            if frame.name not in taken:
                out[f"{name}.{frame.name}"] = (f"{name}.{frame.link}", frame.pos, frame.quat)
    return out


def split_owner(name: str, members: Container[str]) -> tuple[str, str]:
    """(owner, rest) of a dotted name: the owner is the longest leading part that is a robot's link or joint in
    ``members`` (a model's name may hold dots: `arm.a.b.pos.z` reads link `a.b`), else the first part."""
    parts = name.split(".")
    for k in range(len(parts) - 1, 1, -1):
        owner = ".".join(parts[:k])
        if owner in members:
            return owner, ".".join(parts[k:])
    return parts[0], ".".join(parts[1:])


def readable_names(model: Scenario, robots: Mapping[str, ModelDesc] | None = None) -> list[str]:
    """Every dotted name an expression may read (for suggestions)."""
    robots = robots or {}
    names = list(GLOBALS)
    names += [f"state.{s}" for s in model.state] + [f"param.{p}" for p in model.params]
    owners = [b.name for b in expand_bodies(model)] + list(groups(model)) + robot_links(robots) + list(robots)
    for owner in owners:
        names += [f"{owner}.{f}.{c}" for f, comps in BODY_FIELDS.items() for c in comps]
        names += [f"{owner}.{s}" for s in BODY_SCALARS]
    for frame in robot_frames(robots):
        names += [f"{frame}.{f}.{c}" for f in FRAME_FIELDS for c in BODY_FIELDS[f]]
    for joint in [*model.joints, *robot_joints(robots)]:
        names += [f"{joint}.{f}" for f in JOINT_FIELDS]
        names += [f"{joint}.reaction.{v}.{c}" for v in REACTION_VECTORS for c in "xyz"]
    return names


def written(name: str) -> str:
    """A dotted name as an expression writes it: each part that is not an identifier quoted
    (``arm.8.position`` -> ``arm["8"].position``)."""
    first, *rest = name.split(".")
    return first + "".join(spelled(part) for part in rest)


def check_name(name: str, valid: set[str]) -> str | None:
    """An error message if ``name`` cannot be read, else None."""
    if name in valid:
        return None
    import difflib  # here: only a name that is not valid needs it

    close = difflib.get_close_matches(name, sorted(valid), n=1, cutoff=0.7)
    hint = f"; did you mean `{written(close[0])}`?" if close else ""
    return f"unknown name `{written(name)}` in expression{hint}"
