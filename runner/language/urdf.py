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
import re
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from backends.types import NO_DYNAMICS, JointDynamics, Mesh, PlacedShape, Rgba, Shape, ShapeKind
from runner.language.mesh_limits import check_mesh_counts, check_mesh_file
from runner.language.model_names import check_names
from runner.language.model_numbers import check_urdf_numbers, check_vertices
from runner.language.robot_desc import (
    JointDesc,
    LinkDesc,
    ModelDesc,
    ModelFileError,
    quat_from_matrix,
    resolve_package,
    vec,
)
from runner.language.urdf_rules import merge_massless_fixed, usable_inertia
from runner.language.visuals import urdf_visuals, within_budget

_KINDS = {
    "revolute": "hinge",
    "continuous": "hinge",
    "prismatic": "slider",
    "fixed": "fixed",
    "spherical": "ball",  # pybullet's extension (humanoid.urdf): a ball joint at the child's origin
    "floating": "free",  # no joint: the child is a free body, as pybullet and MuJoCo load it
}


def xml_bytes(file: Path) -> bytes:
    """The file's bytes with the quirks pybullet's loader reads past blanked (each byte replaced by a space, so
    lines and columns stay): every XML declaration (pybullet_data declares `version="0.0"`, which XML
    parsers refuse, and two files declare it after a comment or a blank line), and NUL bytes (humanoid.urdf
    ends with one: "Extra content at the end of the document"). docs/robots.md lists them."""

    try:
        raw = file.read_bytes()
    except OSError as exc:
        raise ModelFileError(file, 0, f"cannot read the model file: {exc.strerror}") from None
    blanked = re.sub(rb"<\?xml\s[^>]*\?>", lambda m: b" " * len(m.group(0)), raw.replace(b"\x00", b" "))
    return blanked


def parse_xml(file: Path) -> Any:
    """The lxml tree, or the file and line of the first syntax error."""
    from lxml import etree

    parser = etree.XMLParser(remove_comments=True, resolve_entities=False, no_network=True)
    try:
        return etree.ElementTree(etree.fromstring(xml_bytes(file), parser))
    except etree.XMLSyntaxError as exc:
        line, column = exc.position if exc.position else (exc.lineno or 0, 0)
        raise ModelFileError(file, line or 0, f"malformed XML: {exc.msg}", column=column or 0) from None


#: collision geometry pybullet reads and no engine here simulates, by its tag
_REFUSED_GEOMETRY = {
    "plane": "pybullet's implicit <plane> (the scenario's `plane` body is the ground)",
    "cdf": "pybullet's signed-distance field <cdf>",
}
_XACRO = re.compile(r"\$\((?!optenv\s)|\$\{")


def _check_geometry(tree: Any, file: Path) -> None:
    """Every collision <geometry> is one the loaders read (other elements in a <geometry>, such as the
    <material> racecar.urdf puts there, are read past, as pybullet does), and no xacro expression is left
    (but `$(optenv ...)`)."""
    for geometry in tree.getroot().iterfind("link/collision/geometry"):
        for shape in geometry:
            if isinstance(shape.tag, str) and shape.tag in _REFUSED_GEOMETRY:
                what = _REFUSED_GEOMETRY[shape.tag]
                raise ModelFileError(file, shape.sourceline or 0, f"geometry {what} is not simulated here")
    for element in tree.getroot().iter():
        for key, value in element.attrib.items():
            if _XACRO.search(value):
                raise ModelFileError(
                    file, element.sourceline or 0, f"`{key}` holds a xacro expression {value!r}: run xacro first",
                    near=value,
                )  # fmt: skip


def _yourdfpy_text(file: Path) -> bytes:
    """What yourdfpy reads: the file as pybullet reads it. <capsule> becomes <cylinder> (made a capsule again
    from the tree), `$(optenv NAME default)` (xacro, left in husky.urdf) the variable or its default, and
    numbers as pybullet's reader takes them (:func:`_numbers`)."""
    import os

    text = re.sub(rb"<(/?)capsule\b", rb"<\1cylinder", xml_bytes(file))

    def optenv(m: re.Match[bytes]) -> bytes:
        return os.environ.get(m.group(1).decode(), m.group(2).decode()).encode()

    text = re.sub(rb"\$\(optenv\s+(\S+)\s*([^)]*)\)", optenv, text)
    return re.sub(rb'="([-+0-9.eE,\s]*)"', lambda m: b'="' + _numbers(m.group(1)) + b'"', text)


_NUMBER = re.compile(rb"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def _numbers(value: bytes) -> bytes:
    """A list of numbers as pybullet's reader takes it: commas are separators, and each item is its longest
    leading number (strtod: biped2d_pybullet.urdf writes `-1.57.`); an item with none is left to fail."""
    items = value.replace(b",", b" ").split()
    out = []
    for item in items:
        found = _NUMBER.match(item)
        out.append(found.group(0) if found else item)
    return b" ".join(out)


def _lines(tree: Any, tag: str) -> dict[str, int]:
    return {e.get("name"): e.sourceline or 0 for e in tree.getroot().iter(tag) if e.get("name")}


def _check_structure(tree: Any, file: Path) -> tuple[dict[str, int], dict[str, int]]:
    """Names and references, with the line of each problem; returns the links' and joints' lines."""

    root = tree.getroot()
    if root.tag != "robot":
        raise ModelFileError(file, root.sourceline or 0, f"expected a <robot> URDF document, found <{root.tag}>")
    for kind in ("link", "joint"):
        check_names(file, kind, [(e.get("name"), e.sourceline or 0) for e in root.findall(kind)])
    links, joints = _lines(tree, "link"), _lines(tree, "joint")
    if not links:
        soft = root.find("deformable")
        if soft is not None:
            what = "a deformable body (pybullet's <deformable>), which no engine here simulates"
            raise ModelFileError(file, soft.sourceline or 0, what)
        raise ModelFileError(file, root.sourceline or 0, "the model has no <link>")
    _check_geometry(tree, file)
    children: dict[str, str] = {}
    for joint in root.iter("joint"):
        line = joint.sourceline or 0
        if joint.getparent() is not root:
            continue  # a <transmission>'s joint reference
        kind = joint.get("type", "")
        if kind not in _KINDS:
            raise ModelFileError(
                file,
                line,
                f"joint `{joint.get('name')}` has type `{kind}`, which no engine here simulates"
                f"{' (a planar joint: motion in a plane, on none of the four engines)' if kind == 'planar' else ''}"
                f"; supported: {', '.join(_KINDS)}",
            )
        for end in ("parent", "child"):
            element = joint.find(end)
            ref = element.get("link") if element is not None else None
            if ref is None:
                raise ModelFileError(file, line, f"joint `{joint.get('name')}` has no <{end} link=...>")
            if ref not in links:
                where = element.sourceline or line
                raise ModelFileError(
                    file,
                    where,
                    f"joint `{joint.get('name')}` names {end} link `{ref}`, which the model does not define",
                    near=f"<{end}",
                )
        child = joint.find("child").get("link")
        if child in children:
            raise ModelFileError(file, line, f"link `{child}` is the child of two joints (`{children[child]}` too)")
        children[child] = str(joint.get("name"))
    roots = [name for name in links if name not in children]
    if len(roots) != 1:
        raise ModelFileError(file, root.sourceline or 0, f"expected one root link, found {roots or 'none (a loop)'}")
    return links, joints


def _capsules(tree: Any) -> set[tuple[str, int]]:
    """(link, index of its <collision>) of every capsule: pybullet's extension, radius and length (the
    cylinder between the two half-spheres' centres) along the local z, as our capsule."""
    found = set()
    for link in tree.getroot().iter("link"):
        for k, collision in enumerate(link.findall("collision")):
            if collision.find("geometry/capsule") is not None:
                found.add((str(link.get("name")), k))
    return found


def _mesh_lines(tree: Any) -> dict[str, int]:
    return {e.get("filename"): e.sourceline or 0 for e in tree.getroot().iter("mesh") if e.get("filename")}


def load_mesh(path: Path, scale: tuple[float, float, float], file: Path, line: int, hull: bool, near: str = "") -> Mesh:
    """The mesh file's triangles (scaled), or their convex hull; a file beyond the mesh limits is refused
    before it is read (runner.language.mesh_limits), a vertex not finite or beyond +-1e9 m after."""
    import trimesh

    check_mesh_file(path, file, line, near)
    try:
        loaded = trimesh.load(str(path), force="mesh", process=False)  # processing drops NaN vertices unseen
    except Exception as exc:  # noqa: BLE001 - trimesh raises many types for unreadable files; all mean "bad mesh"
        raise ModelFileError(file, line, f"cannot read the mesh {path.name}: {exc}", near=near) from None
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise ModelFileError(file, line, f"the mesh {path.name} holds no triangles", near=near)
    check_vertices(np.asarray(loaded.vertices) * np.asarray(scale, dtype=float), file, line, path.name)
    loaded.process()  # vertices merged, degenerate faces dropped: as trimesh.load(process=True)
    check_mesh_counts(len(loaded.faces), len(loaded.vertices), path, file, line, near)
    loaded.apply_scale(np.asarray(scale, dtype=float))
    if hull:
        loaded = loaded.convex_hull  # qhull, through trimesh: every vertex of the hull, none moved
    vertices = tuple(vec(v) for v in np.asarray(loaded.vertices, dtype=float))
    faces = tuple((int(a), int(b), int(c)) for a, b, c in np.asarray(loaded.faces))
    return Mesh(vertices=vertices, faces=faces, source=path.name)


def _shape(geometry: Any, file: Path, package_root: Path | None, mesh_lines: dict[str, int], hull: bool) -> Shape:
    g = geometry
    if g.box is not None:
        return Shape(ShapeKind.BOX, size=vec(g.box.size))
    if g.sphere is not None:
        return Shape(ShapeKind.SPHERE, radius=float(g.sphere.radius))
    if g.cylinder is not None:
        c = g.cylinder
        return Shape(ShapeKind.CYLINDER, radius=float(c.radius), length=float(c.length))
    mesh = g.mesh
    line = mesh_lines.get(mesh.filename, 0)
    target = resolve_package(mesh.filename, package_root, file, line)
    scale = mesh_scale(mesh.scale, file, line)
    kind = ShapeKind.CONVEX if hull else ShapeKind.TRIMESH
    return Shape(kind, mesh=load_mesh(target, scale, file, line, hull, near=mesh.filename))


def mesh_scale(scale: Any, file: Path, line: int) -> tuple[float, float, float]:
    """`scale` as the loaders read it: none is 1; one number scales every axis; three are x, y, z; pybullet
    reads the first three of more (pybullet_data's racecar writes `scale="1 1 1 1"`)."""
    if scale is None:
        return (1.0, 1.0, 1.0)
    values = np.atleast_1d(np.asarray(scale, dtype=float)).ravel()
    if values.size == 1:
        values = np.repeat(values, 3)
    if values.size < 3 or not np.all(np.isfinite(values[:3])):
        raise ModelFileError(file, line, f"mesh scale {list(values)} is not 1 or 3 numbers", near="scale")
    return vec(values[:3])


def _start(lo: float | None, hi: float | None) -> float:
    """Where a joint starts: 0, clamped into its limits (a1, aliengo and kuka_iiwa/model_vr_limits put 0
    outside them; pybullet leaves such a joint outside and its stop then throws the robot)."""
    if lo is None or hi is None:
        return 0.0
    return float(min(max(0.0, lo), hi))


def _motion(kind: str, axis: np.ndarray, q: float) -> np.ndarray:
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


def _dynamics(joint: Any, kind: str, file: Path, line: int) -> JointDynamics:
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


def _walk(root: str, joints: list[Any]) -> Iterator[Any]:
    """Joints parents first."""
    by_parent: dict[str, list[Any]] = {}
    for joint in joints:
        by_parent.setdefault(joint.parent, []).append(joint)
    stack = [root]
    while stack:
        for joint in by_parent.get(stack.pop(), []):
            yield joint
            stack.append(joint.child)


def load_urdf(file: Path, package_root: Path | None, static_root: bool, static_triangles: bool) -> ModelDesc:
    """Parse ``file``; links' frames by forward kinematics at the zero configuration (model frame). The
    meshes of a static root are its triangles when ``static_triangles``, else (and for every moving link)
    convex hulls."""
    import yourdfpy

    tree = parse_xml(file)
    link_lines, joint_lines = _check_structure(tree, file)
    check_urdf_numbers(tree, file)
    capsules = _capsules(tree)
    mesh_lines = _mesh_lines(tree)
    try:
        urdf = yourdfpy.URDF.load(io.BytesIO(_yourdfpy_text(file)), build_scene_graph=False, load_meshes=False)
    except Exception as exc:  # noqa: BLE001 - yourdfpy raises ValueError/TypeError/AttributeError on bad values
        raise ModelFileError(file, 0, f"cannot read the URDF: {exc}") from None
    robot = urdf.robot
    materials = {m.name: tuple(m.color.rgba) for m in robot.materials if m.color is not None and m.name}
    children = {j.child for j in robot.joints}
    root = next(link.name for link in robot.links if link.name not in children)
    frames = {root: np.eye(4)}
    descs: list[JointDesc] = []
    notes: list[str] = []
    for joint in _walk(root, list(robot.joints)):
        at_joint = frames[joint.parent] @ np.asarray(joint.origin if joint.origin is not None else np.eye(4))
        kind = _KINDS[joint.type]
        axis = np.asarray(joint.axis if joint.axis is not None else (1.0, 0.0, 0.0), dtype=float)
        if kind in ("hinge", "slider") and np.linalg.norm(axis) < 1e-12:
            raise ModelFileError(file, joint_lines.get(joint.name, 0), f"joint `{joint.name}` has a zero axis")
        unit = axis / max(float(np.linalg.norm(axis)), 1e-300)
        world_axis = at_joint[:3, :3] @ unit
        lo = hi = None
        if joint.type in ("revolute", "prismatic") and joint.limit is not None:
            lo, hi = joint.limit.lower, joint.limit.upper
        if lo is not None and hi is not None and lo > hi:
            lo = hi = None  # pybullet's convention: lower > upper is no limit (cube_no_rotation.urdf)
        start = _start(lo, hi)
        if start != 0.0:
            notes.append(f"joint `{joint.name}`: 0 is outside its limits [{lo:g}, {hi:g}]; it starts at {start:g}, "
                         "and its position counts from there")  # fmt: skip
            lo, hi = float(lo) - start, float(hi) - start  # type: ignore[arg-type]
        frame = at_joint @ _motion(joint.type, unit, start)
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
                _dynamics(joint, kind, file, joint_lines.get(joint.name, 0)),
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
            shape = _shape(collision.geometry, file, package_root, mesh_lines, hull)
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
                urdf_visuals(link, elements.get(link.name), file, materials, package_root, mesh_cache, notes,
                             mesh_scale),
            )
        )
    links, descs, tools = merge_massless_fixed(root, links, descs)
    links = [_default_mass(link) if link.name in no_inertial else link for link in links]
    links = within_budget([usable_inertia(link) for link in links])
    return ModelDesc(str(file), root, tuple(links), tuple(descs), tuple(notes), frames=tuple(tools))
