"""`scenario inspect SCENARIO`: what each robot of a scenario is made of, as its model file says: links (mass),
joints (kind, limits, axis, their own dynamics and URDF `<mimic>`) and actuators (MJCF `<actuator>`), names as
the file spells them."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import fields
from typing import Any

from rich.console import Group
from rich.table import Table
from rich.text import Text

from backends.types import JointDynamics
from runner.language.load import LoadedScenario
from runner.language.robot_desc import ModelDesc

__all__ = ["robots_data", "robots_summary"]

#: the unit of a joint's limits, by its kind (a ball or free joint has none)
_LIMIT_UNITS = {"hinge": "rad", "slider": "m"}


def _number(value: float | None) -> float | None:
    return None if value is None or not math.isfinite(value) else float(value)


def _dynamics(dynamics: JointDynamics) -> dict[str, float]:
    """The joint's own dynamics that are set (damping, friction loss, armature, stiffness with its springref,
    effort and velocity limits), in the joint coordinate's units."""
    out = {f.name: float(value) for f in fields(dynamics) if (value := getattr(dynamics, f.name)) is not None}
    return {k: v for k, v in out.items() if v != 0.0 and (k != "springref" or dynamics.stiffness != 0.0)}


def robot_data(desc: ModelDesc) -> dict[str, Any]:
    """One robot's model as plain data (the JSON output): its file, links, joints and actuators, in file order,
    and the loader's notes."""
    return {
        "file": desc.file,
        "root": desc.root,
        "links": [{"name": link.name, "mass": link.mass, "line": link.line} for link in desc.links],
        "joints": [
            {"name": j.name, "kind": j.kind, "parent": j.parent, "child": j.child, "axis": list(j.axis),
             "lower": _number(j.lo), "upper": _number(j.hi), "unit": _LIMIT_UNITS.get(j.kind), "line": j.line,
             "dynamics": _dynamics(j.dynamics),
             "mimic": None if j.mimic is None else {"leader": j.mimic.leader, "multiplier": j.mimic.multiplier,
                                                     "offset": j.mimic.offset}}
            for j in desc.joints
        ],  # fmt: skip
        "actuators": [{"name": a.name, "kind": a.kind, "joint": a.joint, "line": a.line} for a in desc.actuators],
        "notes": list(desc.notes),  # what the loader decided for the file (a legacy construct upgraded, ...)
    }


def robots_data(loaded: LoadedScenario) -> dict[str, Any]:
    """The scenario's robots, by name, as :func:`robot_data`."""
    return {
        "scenario": loaded.model.scenario,
        "variant": loaded.variant,
        "robots": {name: robot_data(desc) for name, desc in loaded.robots.items()},
    }


def _limits(joint: Mapping[str, Any]) -> str:
    lower, upper = joint["lower"], joint["upper"]
    if lower is None and upper is None:
        return "none" if joint["kind"] in _LIMIT_UNITS else ""
    shown = [f"{v:.6g}" if v is not None else "-inf" if k == 0 else "inf" for k, v in enumerate((lower, upper))]
    return f"{shown[0]} .. {shown[1]} {joint['unit'] or ''}".rstrip()


def _notes(joint: Mapping[str, Any]) -> str:
    """``damping 0.5, effort 300; = -0.5 x finger1 + 0.2``: the joint's dynamics and its `<mimic>`."""
    parts = ", ".join(f"{k} {v:.6g}" for k, v in joint["dynamics"].items())
    mimic = joint["mimic"]
    if mimic is not None:
        follows = f"= {mimic['multiplier']:.6g} x {mimic['leader']}"
        if mimic["offset"]:
            follows += f" {'-' if mimic['offset'] < 0 else '+'} {abs(mimic['offset']):.6g}"
        parts = f"{parts}; {follows}" if parts else follows
    return parts


def _robot(name: str, robot: Mapping[str, Any]) -> list[Any]:
    links = Table(title=f"{name}: links ({len(robot['links'])})", title_justify="left")
    links.add_column("link")
    links.add_column("mass (kg)", justify="right")
    for link in robot["links"]:
        links.add_row(Text(link["name"]), f"{link['mass']:.6g}" if link["mass"] > 0 else "none")
    joints = Table(title=f"{name}: joints ({len(robot['joints'])})", title_justify="left")
    notes = any(j["dynamics"] or j["mimic"] for j in robot["joints"])
    for column in ("joint", "kind", "parent", "child", "limits", "axis", *(["dynamics, mimic"] if notes else [])):
        joints.add_column(column)
    for j in robot["joints"]:
        axis = " ".join(f"{c:.6g}" for c in j["axis"]) if j["kind"] in ("hinge", "slider") else ""
        row = [Text(j["name"]), j["kind"], Text(j["parent"]), Text(j["child"]), _limits(j), axis]
        joints.add_row(*row, *([Text(_notes(j))] if notes else []))
    parts: list[Any] = [Text(f"robot {name}: {robot['file']} (root link {robot['root']})", style="bold"), links,
                        joints]  # fmt: skip
    if robot["actuators"]:
        actuators = Table(title=f"{name}: actuators ({len(robot['actuators'])})", title_justify="left")
        for column in ("actuator", "kind", "joint"):
            actuators.add_column(column)
        for a in robot["actuators"]:
            actuators.add_row(Text(a["name"]), a["kind"], Text(a["joint"] or "(a tendon, site or body)"))
        parts.append(actuators)
    else:
        parts.append(Text(f"{name}: no actuators in the model file"))
    parts += [Text(f"{name}: note: {note}", style="yellow") for note in robot.get("notes", ())]
    return parts


def robots_summary(data: Mapping[str, Any]) -> Group:
    """A rich renderable of :func:`robots_data`'s output."""
    parts: list[Any] = [Text(f"scenario {data['scenario']} (variant {data['variant']})", style="bold underline")]
    if not data["robots"]:
        parts.append(Text("no robots"))
    for name, robot in data["robots"].items():
        parts += _robot(name, robot)
    return Group(*parts)
