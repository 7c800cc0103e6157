"""A Panda3D scene graph of a :class:`~reports.scene3d.model.SceneModel`, posed at any simulated time.

One node per body (named after it) under :attr:`PandaScene.root`; under it one node per version of each
of the body's entities (a shape, a collision solid; a scale change is a new version), built when first
shown. Geometry is coloured per vertex and lit by one ambient and one directional light attached to the
root, so any camera that sees the root (an offscreen buffer's, a ShowBase window's) shows it lit.
Translucent primitives (collision solids) are alpha-blended without writing depth; lines are unlit.

Shadows: every opaque shape of a moving or standing body casts a planar shadow on the ground (the highest upward-
facing static plane below the bodies): the same geometry, instanced under a node whose matrix projects it along the
directional light onto the plane (:func:`shadow_matrix`), drawn unlit on it (after the plane, before the rest,
without the depth test) in the plane's colour times :data:`AMBIENT` (what the plane is where only the ambient light
reaches; opaque, so where two shapes' shadows overlap it is no darker). It needs no shader, so Panda3D's software
renderer (the report's pictures and replay) and the window (``scenario view``) show the same shadows; a scene
without such a plane has none.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence

import numpy as np
from panda3d.core import (
    AmbientLight,
    DirectionalLight,
    Geom,
    GeomLinestrips,
    GeomNode,
    GeomTriangles,
    GeomVertexData,
    GeomVertexFormat,
    GeomVertexWriter,
    LMatrix4f,
    Material,
    MaterialAttrib,
    NodePath,
    OmniBoundingVolume,
    Quat,
    RenderState,
    TransparencyAttrib,
)

from backends.geometry import quat_matrices
from reports.scene3d.meshes import primitive_mesh
from reports.scene3d.model import EntityVisual, Primitive, SceneModel
from reports.trace_format import WORLD_FRAME

__all__ = ["AMBIENT", "BACKGROUND", "LIGHT_HPR", "PandaScene", "shadow_matrix", "software_camera_state"]

AMBIENT = 0.42
DIRECTIONAL = 0.62
#: from above the right (+x) and a little in front: it lights the faces the camera sees (reports.scene3d.framing
#: looks from the front right, heading 25) and casts the shadows to the left, beside the bodies, not behind them
LIGHT_HPR = (60.0, -55.0, 0.0)
BACKGROUND = (0.92, 0.94, 0.97)  # the pictures' and the window's clear colour
#: the ground's colour where the model gives none (runner/trace/scene.py's grey)
GROUND_RGB = (0.55, 0.55, 0.55)
#: how far above the plane the shadow lies, m, and how much of a body's height it keeps (a flat but not
#: singular matrix, which Panda3D would refuse to invert)
SHADOW_LIFT, SHADOW_FLATTEN = 1e-3, 1e-4


def software_camera_state() -> RenderState:
    """The initial state of a camera drawn by ``p3tinydisplay``: that renderer multiplies a lit vertex
    colour by itself once more unless a material supplies the lit terms; white ambient and diffuse leave
    the vertex colour to modulate once, as OpenGL does (an OpenGL camera must not get it: a material
    there replaces the vertex colours)."""
    white = Material("white")
    white.setAmbient((1.0, 1.0, 1.0, 1.0))
    white.setDiffuse((1.0, 1.0, 1.0, 1.0))
    return RenderState.make(MaterialAttrib.make(white), 1)


def _triangles(prims: Sequence[Primitive]) -> Geom | None:
    meshes = [(primitive_mesh(p), p.rgba) for p in prims if p.kind != "lines"]
    meshes = [(m, c) for m, c in meshes if len(m[0])]
    if not meshes:
        return None
    data = GeomVertexData("triangles", GeomVertexFormat.getV3n3c4(), Geom.UHStatic)
    count = sum(len(m[0]) for m, _ in meshes)
    data.uncleanSetNumRows(count)
    vertex, normal, colour = (GeomVertexWriter(data, n) for n in ("vertex", "normal", "color"))
    for (vertices, normals), rgba in meshes:
        for v, n in zip(vertices.tolist(), normals.tolist(), strict=True):
            vertex.setData3(*v)
            normal.setData3(*n)
            colour.setData4(*rgba)
    tris = GeomTriangles(Geom.UHStatic)
    tris.addConsecutiveVertices(0, count)
    geom = Geom(data)
    geom.addPrimitive(tris)
    return geom


def _lines(prims: Sequence[Primitive]) -> Geom | None:
    loops = [p for p in prims if p.kind == "lines"]
    strips = [(p, list(p.points) + ([p.points[0]] if p.closed and p.points else [])) for p in loops]
    strips = [(p, pts) for p, pts in strips if len(pts) >= 2]
    if not strips:
        return None
    data = GeomVertexData("lines", GeomVertexFormat.getV3c4(), Geom.UHStatic)
    vertex, colour = GeomVertexWriter(data, "vertex"), GeomVertexWriter(data, "color")
    prim = GeomLinestrips(Geom.UHStatic)
    row = 0
    for p, pts in strips:
        rot = quat_matrices(p.quat)
        for q in np.asarray(pts, float) @ rot.T + np.asarray(p.position, float):
            vertex.addData3(*q.tolist())
            colour.addData4(*p.rgba)
        prim.addConsecutiveVertices(row, len(pts))
        prim.closePrimitive()
        row += len(pts)
    geom = Geom(data)
    geom.addPrimitive(prim)
    return geom


def shadow_matrix(direction: Sequence[float], ground: float) -> LMatrix4f:
    """The matrix (Panda3D's row-vector convention, ``p' = p M``) that moves a point along the light's
    ``direction`` (pointing down) onto the plane z = ``ground``, :data:`SHADOW_LIFT` above it, its height
    above the plane kept times :data:`SHADOW_FLATTEN`."""
    dx, dy, dz = (float(c) for c in direction)
    sx, sy = -dx / dz, -dy / dz
    flat, z0 = SHADOW_FLATTEN, float(ground)
    return LMatrix4f(1.0, 0.0, 0.0, 0.0,
                     0.0, 1.0, 0.0, 0.0,
                     sx, sy, flat, 0.0,
                     -sx * z0, -sy * z0, z0 + SHADOW_LIFT - flat * z0, 1.0)  # fmt: skip


Pose = tuple[Sequence[float], Sequence[float]]


def _ground(model: SceneModel, start: Mapping[str, Pose]) -> tuple[float, str] | None:
    """(z, name) of the highest plane that faces up (+z) and lies below every other body's origin at the
    start (the recorded poses, else ``start``). Planes are static: the language has no moving plane."""
    planes: list[tuple[float, str]] = []
    lowest = np.inf
    for name in model.bodies:
        pose = model.pose(name, 0.0) or start.get(name)
        if pose is None:
            continue
        pos, quat = pose
        if model.shape.get(name) == "plane":
            if quat_matrices(np.asarray(quat, float))[2, 2] > 1.0 - 1e-9:
                planes.append((float(pos[2]), name))
        else:
            lowest = min(lowest, float(pos[2]))
    below = [plane for plane in planes if plane[0] <= lowest]
    return max(below) if below else None


def _shadow_rgb(model: SceneModel, plane: str) -> tuple[float, float, float]:
    """The plane's colour (its drawn faces', else the model's) lit by the ambient light alone."""
    entity = model.entities_at(0.0).get(f"body/{plane}")
    faces = [p.rgba for p in entity.primitives if p.kind != "lines"] if entity is not None else []
    r, g, b = faces[0][:3] if faces else model.color.get(plane, GROUND_RGB)[:3]
    return r * AMBIENT, g * AMBIENT, b * AMBIENT


class PandaScene:
    """The scene graph of ``model``; :meth:`show` poses it at a simulated time."""

    def __init__(self, model: SceneModel, start: Mapping[str, Pose] | None = None) -> None:
        """``start``: body -> (position, quaternion w x y z) where the model has no recorded poses (a live run),
        for where the ground is."""
        self.model = model
        self.root = NodePath("scene")
        ambient = AmbientLight("ambient")
        ambient.setColor((AMBIENT, AMBIENT, AMBIENT, 1.0))
        sun = DirectionalLight("sun")
        sun.setColor((DIRECTIONAL, DIRECTIONAL, DIRECTIONAL, 1.0))
        self.lights = [self.root.attachNewNode(ambient), self.root.attachNewNode(sun)]
        self.lights[1].setHpr(*LIGHT_HPR)
        for light in self.lights:
            self.root.setLight(light)
        self.bodies = {name: self.root.attachNewNode(name) for name in model.bodies}
        self.shadows: NodePath | None = None
        self._shadow_bodies: dict[str, NodePath] = {}
        ground = _ground(model, start or {})
        if ground is not None:
            self.shadows = self.root.attachNewNode("shadows")
            direction = self.lights[1].getQuat(self.root).getForward()
            self.shadows.setMat(shadow_matrix(direction, ground[0]))
            self.shadows.setLightOff(1)
            self.shadows.setColor((*_shadow_rgb(model, ground[1]), 1.0), 1)  # over the vertex colours
            self.shadows.setTwoSided(True)
            # Drawn right after the ground and before everything else, without the depth test: a shadow 1 mm
            # above the plane fought with it in the software renderer's depth buffer (a speckled shadow at 5 m);
            # what stands on the shadow is drawn later and covers it as it should.
            self.bodies[ground[1]].setBin("background", 0, 1)  # over its translucent grid's "transparent" bin
            self.shadows.setBin("background", 1)
            self.shadows.setDepthTest(False)
            self.shadows.setDepthWrite(False)
            # Panda3D culls by bounds carried through the node's matrix, which a flattening one gets wrong (every
            # shadow was culled): never cull the shadows.
            self.shadows.node().setBounds(OmniBoundingVolume())
            self.shadows.node().setFinal(True)
            self._shadow_bodies = {name: self.shadows.attachNewNode(name) for name in model.bodies
                                   if model.shape.get(name) != "plane"}  # fmt: skip
        self._built: dict[int, NodePath] = {}
        self._solids_visible = True
        self._collision_visible = False  # a model's collision shapes: its visuals are what it looks like

    def _node(self, entity: EntityVisual) -> NodePath | None:
        key = id(entity)
        if key in self._built:
            return self._built[key]
        parent = self.root if entity.body == WORLD_FRAME else self.bodies.get(entity.body)  # contact arrows: world
        if parent is None:
            return None
        node = GeomNode(entity.id)
        for geom in (_triangles(entity.primitives), _lines(entity.primitives)):
            if geom is not None:
                node.addGeom(geom)
        path = parent.attachNewNode(node)
        if any(p.rgba[3] < 1.0 for p in entity.primitives):
            path.setTransparency(TransparencyAttrib.MAlpha)
            path.setDepthWrite(False)
            path.setBin("transparent", 10)
        if any(p.kind == "triangles" for p in entity.primitives):
            path.setTwoSided(True)
        if any(p.kind == "lines" for p in entity.primitives):
            path.setRenderModeThickness(2)
        if entity.solid:
            path.setTag("solid", "1")
        shadow = self._shadow_bodies.get(entity.body)
        opaque = all(p.rgba[3] >= 1.0 for p in entity.primitives)
        if shadow is not None and opaque and not entity.solid and any(p.kind != "lines" for p in entity.primitives):
            path.instanceTo(shadow)  # the same node: shown and hidden with it
        self._built[key] = path
        return path

    def set_solids_visible(self, visible: bool) -> None:
        """Show or hide the collision solids (the lab's ``show()`` on a key)."""
        self._solids_visible = visible

    def set_collision_visible(self, visible: bool) -> None:
        """Show or hide the collision shapes of bodies drawn by their visuals (hidden at first)."""
        self._collision_visible = visible

    def _shown(self, entity: EntityVisual) -> bool:
        if entity.layer == "collision":
            return self._collision_visible
        return self._solids_visible or not entity.solid

    def set_pose(self, body: str, pos: Iterable[float], quat: Iterable[float]) -> None:
        """Put ``body`` at ``pos`` with orientation ``quat`` (w, x, y, z)."""
        node = self.bodies[body]
        node.setPos(*(float(c) for c in pos))
        node.setQuat(Quat(*(float(c) for c in quat)))
        node.show()
        shadow = self._shadow_bodies.get(body)
        if shadow is not None:
            shadow.setTransform(node.getTransform())
            shadow.show()

    def show(self, t: float) -> None:
        """Every body at its recorded pose at ``t``, with the shapes and solids the scene has then; a body
        without a finite pose there (a run that blew up) is hidden."""
        visible = {id(e) for e in self.model.entities_at(t).values() if self._shown(e)}
        for entity in self.model.entities_at(t).values():
            if id(entity) in visible:
                self._node(entity)
        for key, path in self._built.items():
            if key in visible:
                path.show()
            else:
                path.hide()
        for name, node in self.bodies.items():
            pose = self.model.pose(name, t)
            if pose is None:
                if name in self.model.tracks:
                    node.hide()
                    if name in self._shadow_bodies:
                        self._shadow_bodies[name].hide()
                continue
            self.set_pose(name, pose[0], pose[1])
