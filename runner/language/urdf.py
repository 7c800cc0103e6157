"""Read a URDF file into a :class:`~runner.language.robot_desc.ModelDesc`.

Why these libraries: **yourdfpy** parses URDF into typed objects (origins as 4x4 matrices, inertials,
geometry, limits) without needing any engine, so a URDF scenario loads for PyBullet on a machine without
MuJoCo (MuJoCo's own URDF compiler would make the optional `mujoco` extra a requirement, and it merges
fixed links and drops names). **lxml** (yourdfpy's own parser) gives the line of every element, so a bad
model is reported at its line; **trimesh** loads meshes and computes their convex hulls.
"""

from __future__ import annotations

import io
import math
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from backends.types import PlacedShape, Rgba, Shape, ShapeKind
from runner.language.model_numbers import check_urdf_numbers
from runner.language.robot_desc import JointDesc, LinkDesc, ModelDesc, ModelFileError, quat_from_matrix, vec
from runner.language.urdf_joints import joint_dynamics, joint_limits, joint_motion, joint_starts, parents_first
from runner.language.urdf_rules import merge_massless_fixed, usable_inertia
from runner.language.urdf_shapes import collision_shape, mesh_scale
from runner.language.urdf_xml import KINDS, check_structure, find_capsules, mesh_file_lines, parse_xml, yourdfpy_text
from runner.language.visuals import urdf_visuals, within_budget


def _default_mass(link: LinkDesc) -> LinkDesc:
    """A link without <inertial> that is not merged away (runner.language.urdf_rules) gets pybullet's
    default, 1 kg (DART's too), its inertia then from its shapes (``usable_inertia``); a link named
    `world` keeps none, as in pybullet."""
    return replace(link, mass=1.0)


def _pose(matrix: np.ndarray) -> tuple[tuple[float, float, float], tuple[float, float, float, float]]:
    return vec(matrix[:3, 3]), quat_from_matrix(matrix[:3, :3])


def _color(link: Any, materials: dict[str, Rgba]) -> Rgba | None:
    for visual in link.visuals:
        material = visual.material
        if material is None:
            continue
        rgba = material.color.rgba if material.color is not None else materials.get(material.name or "")
        if rgba is not None:
            return (float(rgba[0]), float(rgba[1]), float(rgba[2]), float(rgba[3]))
    return None


def load_urdf(file: Path, package_root: Path | None, static_root: bool, static_triangles: bool) -> ModelDesc:
    """Parse ``file``; links' frames by forward kinematics at the zero configuration (model frame). The
    meshes of a static root are its triangles when ``static_triangles``, else (and for every moving link)
    convex hulls."""
    import yourdfpy

    tree = parse_xml(file)
    link_lines, joint_lines = check_structure(tree, file)
    check_urdf_numbers(tree, file)
    capsules = find_capsules(tree)
    mesh_lines = mesh_file_lines(tree)
    try:
        urdf = yourdfpy.URDF.load(io.BytesIO(yourdfpy_text(file)), build_scene_graph=False, load_meshes=False)
    except Exception as exc:  # noqa: BLE001 - yourdfpy raises ValueError/TypeError/AttributeError on bad values
        raise ModelFileError(file, 0, f"cannot read the URDF: {exc}") from None
    robot = urdf.robot
    materials = {m.name: tuple(m.color.rgba) for m in robot.materials if m.color is not None and m.name}
    children = {j.child for j in robot.joints}
    root = next(link.name for link in robot.links if link.name not in children)
    frames = {root: np.eye(4)}
    descs: list[JointDesc] = []
    notes: list[str] = []
    mimic_lines = {j.get("name"): j.find("mimic").sourceline or 0 for j in tree.getroot().iterfind("joint")
                   if j.find("mimic") is not None}  # fmt: skip
    starts, mimics = joint_starts(list(robot.joints), file, {**joint_lines, **mimic_lines})
    for joint in parents_first(root, list(robot.joints)):
        at_joint = frames[joint.parent] @ np.asarray(joint.origin if joint.origin is not None else np.eye(4))
        kind = KINDS[joint.type]
        axis = np.asarray(joint.axis if joint.axis is not None else (1.0, 0.0, 0.0), dtype=float)
        if kind in ("hinge", "slider") and np.linalg.norm(axis) < 1e-12:
            raise ModelFileError(file, joint_lines.get(joint.name, 0), f"joint `{joint.name}` has a zero axis")
        unit = axis / max(float(np.linalg.norm(axis)), 1e-300)
        world_axis = at_joint[:3, :3] @ unit
        lo, hi = joint_limits(joint)
        start = starts[joint.name]
        if start != 0.0:
            notes.append(f"joint `{joint.name}`: 0 is outside its limits [{lo:g}, {hi:g}]; it starts at {start:g}, "
                         "and its position counts from there")  # fmt: skip
            lo = None if lo is None else float(lo) - start
            hi = None if hi is None else float(hi) - start
        frame = at_joint @ joint_motion(joint.type, unit, start)
        frames[joint.child] = frame
        descs.append(
            JointDesc(
                joint.name,
                kind,
                joint.parent,
                joint.child,
                vec(world_axis),
                vec(frame[:3, 3]),
                None if lo is None else float(lo),
                None if hi is None else float(hi),
                joint_lines.get(joint.name, 0),
                joint_dynamics(joint, kind, file, joint_lines.get(joint.name, 0)),
                mimics.get(joint.name),
            )
        )
    links: list[LinkDesc] = []
    no_inertial = {link.name for link in robot.links if link.inertial is None and link.name != "world"}
    elements = {e.get("name"): e for e in tree.getroot().iterfind("link")}
    mesh_cache: dict[Any, Any] = {}
    for link in robot.links:
        line = link_lines.get(link.name, 0)
        inertial = link.inertial
        mass = float(inertial.mass) if inertial is not None and inertial.mass is not None else 0.0
        if not math.isfinite(mass) or mass < 0:
            raise ModelFileError(file, line, f"link `{link.name}` has mass {mass}")
        origin = np.asarray(inertial.origin) if inertial is not None and inertial.origin is not None else np.eye(4)
        tensor = (
            np.asarray(inertial.inertia, dtype=float)
            if inertial is not None and inertial.inertia is not None
            else np.zeros((3, 3))
        )
        rot = origin[:3, :3]
        tensor = rot @ tensor @ rot.T  # the inertial frame's tensor, in the link frame
        hull = not (static_root and link.name == root and static_triangles)
        shapes = []
        for k, collision in enumerate(link.collisions):
            pos, quat = _pose(np.asarray(collision.origin) if collision.origin is not None else np.eye(4))
            shape = collision_shape(collision.geometry, file, package_root, mesh_lines, hull)
            if (link.name, k) in capsules:
                shape = Shape(ShapeKind.CAPSULE, radius=shape.radius, length=shape.length)
            shapes.append(PlacedShape(shape, pos, quat))
        pos, quat = _pose(frames[link.name])
        links.append(
            LinkDesc(
                link.name,
                mass,
                vec(origin[:3, 3]),
                (vec(tensor[0]), vec(tensor[1]), vec(tensor[2])),
                pos,
                quat,
                tuple(shapes),
                _color(link, materials),
                line,
                urdf_visuals(
                    link, elements.get(link.name), file, materials, package_root, mesh_cache, notes, mesh_scale
                ),
            )
        )
    links, descs, tools = merge_massless_fixed(root, links, descs)
    links = [_default_mass(link) if link.name in no_inertial else link for link in links]
    links = within_budget([usable_inertia(link) for link in links])
    return ModelDesc(str(file), root, tuple(links), tuple(descs), tuple(notes), frames=tuple(tools))
