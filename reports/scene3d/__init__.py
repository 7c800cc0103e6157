"""The 3D scene of a trace, for the report's pictures and replay and for a live Panda3D window.

Layers, engine-neutral first (nothing above ``panda`` imports Panda3D):

* :mod:`.model`: :class:`SceneModel`, what a run looks like: every body's visual primitives (boxes,
  spheres, cylinders, triangle lists, lines; colours, scale) and collision solids, as the trace's
  ``foxglove.SceneUpdate`` channel publishes them over time (read by :mod:`.scene_channel`, falling
  back to the shapes in the trace's metadata), and every body's recorded pose per step.
* :mod:`.framing`: where to put the camera so the bodies that move fill the picture.
* :mod:`.meshes`: triangle meshes of the primitives (trimesh), flat-shaded.
* :mod:`.panda`: :class:`PandaScene` builds a Panda3D scene graph from a :class:`SceneModel` (one node
  per body, parented to a root the caller owns, lights included) and :meth:`PandaScene.show` sets
  every body's pose, scale and geometry at a simulated time. It does not open a window.
* :mod:`.offscreen`: :class:`OffscreenRenderer`, Panda3D's software renderer (``p3tinydisplay``,
  offscreen buffer: no display, no GPU) drawing a :class:`PandaScene` into a Pillow image, and where
  each body's centre lands in it.

For a live window (``scenario view``), build the scene the same way and parent it to ShowBase's
``render``; the pictures and the window then show the same geometry, colours and lights::

    from reports.scene3d import PandaScene, scene_model
    model = scene_model(trace)                  # a reports.trace_reader.Trace
    scene = PandaScene(model)
    scene.root.reparentTo(base.render)          # base: a ShowBase
    scene.show(t)                               # every frame; scene.set_solids_visible(True) on a key

A live run that has no trace yet can build a :class:`SceneModel` directly from
``SceneModel.from_specs(body_specs)`` and feed poses with :meth:`PandaScene.set_pose`.
"""

from __future__ import annotations

from reports.scene3d.framing import CameraSpec, frame_camera, moving_bodies
from reports.scene3d.model import BodyTrack, EntityVisual, Primitive, SceneModel, scene_model

__all__ = [
    "BodyTrack",
    "CameraSpec",
    "EntityVisual",
    "Primitive",
    "SceneModel",
    "frame_camera",
    "moving_bodies",
    "scene_model",
]


def __getattr__(name: str) -> object:
    """``PandaScene`` and ``OffscreenRenderer`` import Panda3D, so only when asked for."""
    if name == "PandaScene":
        from reports.scene3d.panda import PandaScene

        return PandaScene
    if name == "OffscreenRenderer":
        from reports.scene3d.offscreen import OffscreenRenderer

        return OffscreenRenderer
    raise AttributeError(name)
