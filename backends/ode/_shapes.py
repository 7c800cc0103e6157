"""Robot bodies in ODE: compound bodies, convex hulls, triangle meshes and the COM offset.

ODE puts a body's centre of mass at its origin (``dMassSetParameters`` refuses an offset centre). A body
whose COM is away from its frame (``BodySpec.com``) is therefore an ``OdeBody`` at the COM with the
body frame's orientation and the full inertia tensor in that frame (``BodySpec.inertia_tensor()``, ODE
takes the off-diagonal terms); its geoms hang on it with ODE's geom offsets (``dGeomSetOffsetPosition``)
at their pose relative to the COM. :class:`FrameOffset` converts between the body frame the runner sees
and the COM the engine holds.

panda3d.ode has no convex geom (``dCreateConvex`` is not wrapped), so a hull is an ``OdeTriMeshGeom`` of
exactly the hull's vertices and outward triangles (built from a panda3d ``GeomNode``): the same surface,
collided by ODE's trimesh colliders (plane, box, sphere, capsule, trimesh). A triangle mesh collides as a
surface: a body that got entirely inside a hull in one step would not be pushed out.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from panda3d.core import (
    Geom,
    GeomNode,
    GeomTriangles,
    GeomVertexData,
    GeomVertexFormat,
    GeomVertexWriter,
    NodePath,
    Quat,
)
from panda3d.ode import (
    OdeBoxGeom,
    OdeCappedCylinderGeom,
    OdeCylinderGeom,
    OdePlaneGeom,
    OdeSphereGeom,
    OdeTriMeshData,
    OdeTriMeshGeom,
)

from ..errors import UnsupportedFeature
from ..geometry import quat_mul, quat_rotate
from ..types import IDENTITY_QUAT, BodySpec, Mesh, Motion, PlacedShape, Shape, ShapeKind, Vec3

_ZERO: Vec3 = (0.0, 0.0, 0.0)


def is_robot_body(spec: BodySpec) -> bool:
    """A body built here (several shapes, a mesh or a COM offset), not by the primitive path of _build."""
    return (
        spec.shape.kind in (ShapeKind.COMPOUND, ShapeKind.CONVEX, ShapeKind.TRIMESH)
        or spec.com != _ZERO
        or spec.inertia_quat != IDENTITY_QUAT
    )


def tri_mesh_data(mesh: Mesh) -> OdeTriMeshData:
    """ODE triangle-mesh data holding exactly ``mesh``'s vertices and triangles (in their winding)."""
    vdata = GeomVertexData(mesh.source or "mesh", GeomVertexFormat.getV3(), Geom.UHStatic)
    vdata.setNumRows(len(mesh.vertices))
    writer = GeomVertexWriter(vdata, "vertex")
    for v in mesh.vertices:
        writer.addData3(*v)
    tris = GeomTriangles(Geom.UHStatic)
    for a, b, c in mesh.faces:
        tris.addVertices(a, b, c)
    geom = Geom(vdata)
    geom.addPrimitive(tris)
    node = GeomNode(mesh.source or "mesh")
    node.addGeom(geom)
    return OdeTriMeshData(NodePath(node), False)


def shape_geom(space: Any, shape: Shape, body: str, meshes: dict[int, OdeTriMeshData]) -> Any:
    """One geom of a primitive or mesh shape in its own frame (``meshes`` keeps the mesh data alive)."""
    kind = shape.kind
    if kind is ShapeKind.BOX:
        return OdeBoxGeom(space, *shape.size)
    if kind is ShapeKind.SPHERE:
        return OdeSphereGeom(space, shape.radius)
    if kind is ShapeKind.CAPSULE:
        return OdeCappedCylinderGeom(space, shape.radius, shape.length)
    if kind is ShapeKind.CYLINDER:
        return OdeCylinderGeom(space, shape.radius, shape.length)
    if kind in (ShapeKind.CONVEX, ShapeKind.TRIMESH) and shape.mesh is not None:
        data = meshes.get(id(shape.mesh))
        if data is None:
            data = meshes[id(shape.mesh)] = tri_mesh_data(shape.mesh)
        return OdeTriMeshGeom(space, data)
    raise UnsupportedFeature(f"Body `{body}`: a {kind.value} shape cannot be part of a robot body in ODE.")


@dataclass(frozen=True)
class FrameOffset:
    """The COM in the body frame: converts the body frame's pose and velocity to the COM's and back."""

    com: np.ndarray  # (3,), body frame

    def com_pose(self, pos: Vec3, quat: Any) -> Vec3:
        r = quat_rotate(quat, tuple(self.com))
        return (pos[0] + r[0], pos[1] + r[1], pos[2] + r[2])

    def com_velocity(self, quat: Any, lin_vel: Vec3, ang_vel: Vec3) -> Vec3:
        """The COM's velocity from the origin's: v + w x (R com)."""
        r = np.asarray(quat_rotate(quat, tuple(self.com)))
        v = np.asarray(lin_vel, dtype=float) + np.cross(np.asarray(ang_vel, dtype=float), r)
        return (float(v[0]), float(v[1]), float(v[2]))

    def frame_row(self, row: np.ndarray) -> None:
        """Turn a state row (pos, quat, lin_vel, ang_vel) of the COM into the body frame's, in place."""
        r = np.asarray(quat_rotate(row[3:7], tuple(self.com)))
        row[0:3] -= r
        row[7:10] -= np.cross(row[10:13], r)


def build_robot_geoms(
    space: Any, spec: BodySpec, body: Any | None, meshes: dict[int, OdeTriMeshData]
) -> list[Any]:
    """Every placed shape of ``spec``: on ``body`` at its offset from the COM, or placed in the world (static)."""
    geoms: list[Any] = []
    com = spec.com
    for placed in spec.placed_shapes():
        if placed.shape.kind is ShapeKind.PLANE:
            geoms.append(_static_plane(space, spec, placed, body))
            continue
        geom = shape_geom(space, placed.shape, spec.name, meshes)
        if body is None:
            geom.setPosition(*_compose_pos(spec, placed))
            geom.setQuaternion(_panda_quat(quat_mul(spec.quat, placed.quat)))
        else:
            geom.setBody(body)
            offset = (placed.pos[0] - com[0], placed.pos[1] - com[1], placed.pos[2] - com[2])
            if offset != _ZERO:
                geom.setOffsetPosition(*offset)
            if placed.quat != IDENTITY_QUAT:
                geom.setOffsetQuaternion(_panda_quat(placed.quat))
        geoms.append(geom)
    return geoms


def _static_plane(space: Any, spec: BodySpec, placed: PlacedShape, body: Any | None) -> Any:
    """A plane of a static body (an MJCF world body's floor): normal the shape's local +z, through its origin."""
    if body is not None:
        raise UnsupportedFeature(f"Plane of body `{spec.name}` must be static (ODE planes are non-placeable).")
    n = quat_rotate(quat_mul(spec.quat, placed.quat), (0.0, 0.0, 1.0))
    p = _compose_pos(spec, placed)
    return OdePlaneGeom(space, n[0], n[1], n[2], n[0] * p[0] + n[1] * p[1] + n[2] * p[2])


def _compose_pos(spec: BodySpec, placed: PlacedShape) -> Vec3:
    r = quat_rotate(spec.quat, placed.pos)
    return (spec.pos[0] + r[0], spec.pos[1] + r[1], spec.pos[2] + r[2])


def _panda_quat(q: Any) -> Quat:
    return Quat(q[0], q[1], q[2], q[3])


def check_static_shapes(spec: BodySpec) -> None:
    """Triangle meshes only on static bodies (the compiler guarantees it; an adapter still refuses)."""
    if spec.motion is not Motion.STATIC and any(p.shape.kind is ShapeKind.TRIMESH for p in spec.placed_shapes()):
        raise UnsupportedFeature(f"Body `{spec.name}`: triangle meshes are only for static bodies.")
