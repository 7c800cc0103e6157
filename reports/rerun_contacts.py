"""A trace's contact points (/contact_points, written with ``trace: {contact_points: true}``) as Rerun
``Arrows3D`` on ``/world/contact_points``: at every recorded step, one arrow per point from the point along
the force on the second body, as long as the trace drew it (its normal force times the scale the trace's
scenario record states, m/N). Nothing for a trace without the channel."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from reports import trace_format as tf
from reports.rerun_scene import WORLD

ENTITY = f"{WORLD}/contact_points"
RGBA = (255, 64, 26, 255)


@dataclass(frozen=True)
class ArrowSteps:
    """Every recorded step's arrows: ``counts[k]`` arrows at ``times[k]`` (seconds), their ``origins`` and
    ``vectors`` (metres, world frame) one row each, the steps' rows in order."""

    times: np.ndarray
    counts: np.ndarray
    origins: np.ndarray
    vectors: np.ndarray


def read_arrows(trace_path: Path) -> ArrowSteps | None:
    """The /contact_points arrows of the MCAP at ``trace_path`` (None without the channel)."""
    from foxglove_schemas_protobuf.SceneUpdate_pb2 import SceneUpdate
    from mcap.reader import make_reader

    times: list[float] = []
    counts: list[int] = []
    rows: list[tuple[float, ...]] = []
    with open(trace_path, "rb") as f:
        for _, _, message in make_reader(f).iter_messages(topics=[tf.TOPIC_CONTACT_POINTS], log_time_order=True):
            arrows = [a for e in SceneUpdate.FromString(message.data).entities for a in e.arrows]
            times.append(message.log_time / 1e9)
            counts.append(len(arrows))
            rows.extend((*_xyz(a.pose.position), *(_direction(a.pose.orientation) * (a.shaft_length + a.head_length)))
                        for a in arrows)  # fmt: skip
    if not times:
        return None
    table = np.asarray(rows, dtype=float).reshape(-1, 6)
    return ArrowSteps(np.asarray(times), np.asarray(counts, dtype=np.int64), table[:, :3], table[:, 3:])


def _xyz(v: Any) -> tuple[float, float, float]:
    return float(v.x), float(v.y), float(v.z)


def _direction(q: Any) -> np.ndarray:
    """The unit vector a Foxglove arrow points along: its pose's rotation of +x."""
    w, x, y, z = float(q.w), float(q.x), float(q.y), float(q.z)
    return np.array([1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y + w * z), 2.0 * (x * z - w * y)])


def send_arrows(rec: Any, steps: ArrowSteps, duration: Any, timeline: str) -> None:
    """One row of arrows per recorded step (none at a step without contacts) on :data:`ENTITY`."""
    import rerun as rr

    radius = 0.05 * float(np.median(np.linalg.norm(steps.vectors, axis=1))) if len(steps.vectors) else 0.01
    columns = rr.Arrows3D.columns(origins=steps.origins, vectors=steps.vectors,
                                  radii=np.full(len(steps.vectors), radius, dtype=np.float32),
                                  colors=np.tile(np.array(RGBA, dtype=np.uint8), (len(steps.vectors), 1)))  # fmt: skip
    rec.send_columns(ENTITY, indexes=[rr.TimeColumn(timeline, duration=duration(steps.times))],
                     columns=columns.partition(steps.counts.tolist()))  # fmt: skip
