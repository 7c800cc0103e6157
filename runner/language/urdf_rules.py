"""What a URDF leaves to its loader, decided as the established loaders decide it (docs/robots.md, "Rules").

* **Massless links on fixed joints** (frames such as Franka Panda's `panda_link8`, a tool flange, a
  `base_footprint` child) are merged into their parent, as MuJoCo's ``fusestatic`` and pybullet's
  ``URDF_MERGE_FIXED_LINKS`` do: the link's collision shapes and visuals move onto the parent at the same place, the
  joints hanging from it hang from the parent, and the link and its fixed joint are gone (not addressable).
  A chain of them merges into its first ancestor that stays.
* **A link with mass but no usable inertia** (the tensor all zero, or a principal moment not above
  ``DEGENERATE`` times the largest):
  the inertia of its collision shapes' bounding box, about its centre of mass, with its mass; this is
  pybullet's default for every link (``btCompoundShape::calculateLocalInertia``, the AABB box formula),
  kept here only where the file gives nothing usable (MuJoCo refuses such a moving body). A link with no
  collision shape keeps the file's moments ixx, iyy, izz when only the products of inertia make the tensor
  impossible (biped2d_pybullet's sliders: ODE's solver aborts on the 1 cm sphere's tiny inertia there),
  else gets a solid sphere of radius ``FALLBACK_RADIUS``.
* **A tensor that violates A + B >= C** (no body has one; MuJoCo's compiler refuses it, eleven pybullet_data
  URDFs have one): balanced as MuJoCo's ``balanceinertia`` does, on every engine (``_balanced``), so that
  every engine, and the energy watchdog, simulate the same body.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from backends.geometry import quat_conj, quat_mul, quat_rotate
from backends.types import PlacedShape, Shape, ShapeKind
from runner.language.robot_desc import FrameDesc, JointDesc, LinkDesc, vec

#: a principal moment at most this fraction of the largest is none (cube_no_rotation.urdf: 5.6e-17 of 0.215)
DEGENERATE = 1e-12
#: a shortfall of A + B below C up to this fraction of C is rounding, not a wrong tensor
ROUNDING = 1e-9
#: radius (m) of the solid sphere whose inertia a shapeless link of unusable inertia gets
FALLBACK_RADIUS = 0.01


def merge_massless_fixed(
    root: str, links: list[LinkDesc], joints: list[JointDesc]
) -> tuple[list[LinkDesc], list[JointDesc], list[FrameDesc]]:
    """``links`` and ``joints`` (parents first) with every massless link on a fixed joint merged into its parent,
    and the merged links as frames on the links that hold them (a tool frame stays readable)."""
    by_name = {link.name: link for link in links}
    into: dict[str, str] = {}  # merged link -> the link that holds it now
    frames: list[FrameDesc] = []
    kept_joints: list[JointDesc] = []
    for joint in joints:
        parent = into.get(joint.parent, joint.parent)
        child = by_name[joint.child]
        if joint.kind == "fixed" and child.mass <= 0 and joint.child != root:
            holder = by_name[parent]
            moved = tuple(_into_frame(holder, child, placed) for placed in child.shapes)
            drawn = tuple(_into_frame(holder, child, placed) for placed in child.visuals)
            by_name[parent] = replace(holder, shapes=holder.shapes + moved, visuals=holder.visuals + drawn)
            into[joint.child] = parent
            frame = _into_frame(holder, child, PlacedShape(Shape(ShapeKind.SPHERE)))
            frames.append(FrameDesc(child.name, parent, frame.pos, frame.quat))
            continue
        kept_joints.append(joint if parent == joint.parent else replace(joint, parent=parent))
    kept_links = [by_name[link.name] for link in links if link.name not in into]
    return kept_links, kept_joints, frames


def _into_frame(holder: LinkDesc, link: LinkDesc, placed: PlacedShape) -> PlacedShape:
    """``placed`` (in ``link``'s frame) in ``holder``'s frame; both frames are given in the model frame."""
    world_pos = np.add(link.pos, quat_rotate(link.quat, placed.pos))
    back = quat_conj(holder.quat)
    pos = quat_rotate(back, vec(world_pos - np.asarray(holder.pos)))
    return replace(placed, pos=pos, quat=quat_mul(back, quat_mul(link.quat, placed.quat)))


def usable_inertia(link: LinkDesc) -> LinkDesc:
    """``link`` with the bounding-box inertia when it has mass and its tensor is unusable (module docstring)."""
    tensor = np.asarray(link.inertia, dtype=float)
    moments, axes = np.linalg.eigh((tensor + tensor.T) / 2)
    if link.mass <= 0:
        return link
    if moments.min() > DEGENERATE * moments.max():
        return _balanced(link, moments, axes)
    diagonal = np.diag(tensor)
    a, b, c = np.sort(diagonal)
    if not link.shapes and a > DEGENERATE * c and a + b >= c:  # only the products of inertia are impossible
        full = np.diag(diagonal)
        return replace(link, inertia=(vec(full[0]), vec(full[1]), vec(full[2])))
    corners = [shape_points(placed) for placed in link.shapes]
    points = np.concatenate(corners) if corners else np.zeros((0, 3))
    if len(points):
        lo, hi = points.min(axis=0), points.max(axis=0)
        box = hi - lo
        com = (lo + hi) / 2
        moments = link.mass / 12.0 * np.array([box[1] ** 2 + box[2] ** 2, box[0] ** 2 + box[2] ** 2,
                                               box[0] ** 2 + box[1] ** 2])  # fmt: skip
    else:
        moments, com = np.zeros(3), np.asarray(link.com)
    moments = np.maximum(moments, 0.4 * link.mass * FALLBACK_RADIUS**2)  # a flat or point-like box: never 0
    d = np.asarray(link.com) - com  # about the link's own COM: the box's tensor shifted (parallel axes)
    full = np.diag(moments) + link.mass * ((d @ d) * np.eye(3) - np.outer(d, d))
    return replace(link, inertia=(vec(full[0]), vec(full[1]), vec(full[2])))


def _balanced(link: LinkDesc, moments: np.ndarray, axes: np.ndarray) -> LinkDesc:
    """A tensor no body has (principal moments A + B < C) made one as MuJoCo's ``balanceinertia`` does: the
    three moments become their mean, about the same axes. A shortfall within rounding (``ROUNDING`` of C; a
    flat plate has A + B = C exactly) lowers C to A + B instead."""
    a, b, c = moments  # ascending
    if a + b >= c:
        return link
    fixed = np.array([a, b, a + b]) if c - (a + b) <= ROUNDING * c else np.full(3, moments.mean())
    full = axes @ np.diag(fixed) @ axes.T
    return replace(link, inertia=(vec(full[0]), vec(full[1]), vec(full[2])))


def shape_points(placed: PlacedShape) -> np.ndarray:
    """Points bounding one shape in its link's frame: the corners of its local bounding box, turned and placed."""
    s = placed.shape
    if s.mesh is not None:
        local = np.asarray(s.mesh.vertices, dtype=float).reshape(-1, 3)
    else:
        radius, length = s.radius, s.length
        cap = radius if s.kind is ShapeKind.CAPSULE else 0.0  # a capsule's caps reach beyond its cylinder
        along = length / 2 + cap or radius
        half = np.asarray(s.size, dtype=float) / 2 if any(s.size) else np.array([radius, radius, along])
        local = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float) * half
    return np.array([np.add(placed.pos, quat_rotate(placed.quat, vec(p))) for p in local])
