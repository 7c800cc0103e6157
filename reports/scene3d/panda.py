"""A Panda3D scene graph of a :class:`~reports.scene3d.model.SceneModel`, posed at any simulated time.

One node per body (named after it) under :attr:`PandaScene.root`; under it one node per version of each
of the body's entities (a shape, a collision solid; a scale change is a new version), built when first
shown. Geometry is coloured per vertex and lit by one ambient and one directional light attached to the
root, so any camera that sees the root (an offscreen buffer's, a ShowBase window's) shows it lit.
Translucent primitives (collision solids) are alpha-blended without writing depth; lines are unlit.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

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
    Material,
    MaterialAttrib,
    NodePath,
    Quat,
    RenderState,
    TransparencyAttrib,
)

from backends.geometry import quat_matrices
from reports.scene3d.meshes import primitive_mesh
from reports.scene3d.model import EntityVisual, Primitive, SceneModel

__all__ = ["AMBIENT", "BACKGROUND", "LIGHT_HPR", "PandaScene", "software_camera_state"]

AMBIENT = 0.42
DIRECTIONAL = 0.62
LIGHT_HPR = (35.0, -60.0, 0.0)  # from above, front-right
BACKGROUND = (0.92, 0.94, 0.97)  # the pictures' and the window's clear colour


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


class PandaScene:
    """The scene graph of ``model``; :meth:`show` poses it at a simulated time."""

    def __init__(self, model: SceneModel) -> None:
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
        self._built: dict[int, NodePath] = {}
        self._solids_visible = True
        self._collision_visible = False  # a model's collision shapes: its visuals are what it looks like

    def _node(self, entity: EntityVisual) -> NodePath | None:
        key = id(entity)
        if key in self._built:
            return self._built[key]
        parent = self.bodies.get(entity.body)
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
                continue
            self.set_pose(name, pose[0], pose[1])
