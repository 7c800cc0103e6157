"""What the trace records, shown as it is recorded: a trace writer that also tells the window.

:class:`TraceTap` stands in for a live run's :class:`runner.trace.writer.TraceWriter` (the session calls it
exactly as it would call the writer, and every call goes on to the writer unchanged) and passes the
scene updates, events, log lines and sounds to a :class:`TapListener`. The scene's entities are built by
the trace writer's own primitive builders (runner.trace.foxglove) and read back by the report's reader
(reports.scene3d.model.entity_from_message), through the same JSON, so the window draws what a replay
of the trace will draw.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, Protocol

from google.protobuf import json_format

from backends.types import BodySpec, ContactPoint, JointSpec
from reports import trace_format as tf
from reports.scene3d.model import EntityVisual, entity_from_message
from runner.trace import contact_arrows, scene
from runner.trace import foxglove as fx
from runner.trace.scene import SolidVisual

__all__ = ["TapListener", "TraceTap", "scene_entities"]


class TapListener(Protocol):
    def on_scene(self, t: float, entities: Sequence[EntityVisual]) -> None: ...
    def on_event(self, t: float, name: str, source: str) -> None: ...
    def on_log(self, t: float, level: str, message: str, name: str) -> None: ...
    def on_sound(self, t: float, name: str, action: str, offset: float, volume: float) -> None: ...


def scene_entities(bodies: Sequence[BodySpec], solids: Sequence[SolidVisual] = (), scales: Mapping[str, float] | None
                   = None, joints: Sequence[JointSpec] = ()) -> list[EntityVisual]:  # fmt: skip
    """The entities one ``TraceWriter.scene`` call publishes (every topic), as a reader of the trace gets them
    back."""
    out = [e for entities in scene.scene_entities(0, bodies, joints, scales).values() for e in entities]
    for s in solids:
        prims = fx.solid_primitives(s.kind, s.center, s.radius, s.size, s.vertices)
        out.append(fx.entity(0, s.body, f"solid/{s.body}/{s.node}", {"solid": s.node}, **prims))
    return [entity_from_message(json_format.MessageToDict(e, preserving_proto_field_name=True)) for e in out]


class TraceTap:
    """Forwards every call to ``inner`` (a trace writer) and tells ``listener`` what was recorded."""

    def __init__(self, inner: Any, listener: TapListener) -> None:
        self._inner = inner
        self._listener = listener
        self._drawn = False  # the joints are drawn with the first scene, as the writer does

    def __getattr__(self, name: str) -> Any:
        return getattr(self._inner, name)

    def scene(self, t: float, solids: Sequence[SolidVisual] = (), scales: Mapping[str, float] | None = None) -> None:
        first = not self._drawn
        self._drawn = True
        self._inner.scene(t, solids, scales)
        meta = self._inner.meta
        self._listener.on_scene(t, scene_entities(meta.bodies, solids, scales, meta.joints if first else ()))

    def contact_points(self, t: float, points: Sequence[ContactPoint]) -> None:
        self._inner.contact_points(t, points)
        scale = float(self._inner.meta.extra[contact_arrows.KEY_SCALE])
        update = contact_arrows.scene_update(0, points, scale)
        self._listener.on_scene(t, [entity_from_message(json_format.MessageToDict(e, preserving_proto_field_name=True))
                                    for e in update.entities])  # fmt: skip

    def event(self, t: float, name: str, source: str, detail: Mapping[str, Any] | None = None) -> None:
        self._inner.event(t, name, source, detail)
        self._listener.on_event(t, name, source)

    def log(self, t: float, level: str, message: str, name: str = tf.LOGGER_SCENARIO) -> None:
        self._inner.log(t, level, message, name)
        self._listener.on_log(t, level, message, name)

    def sound(self, t: float, name: str, action: str, offset: float = 0.0, volume: float = 1.0) -> None:
        self._inner.sound(t, name, action, offset, volume)
        self._listener.on_sound(t, name, action, offset, volume)
