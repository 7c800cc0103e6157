"""The Foxglove layout shipped with the traces: ``foxglove-layout.json`` (Layouts → Import layout).

One layout per trace folder, in Foxglove Studio's layout format (``configById`` + ``layout`` mosaic, as
Foxglove Studio 1.48 imports and exports it; its newer releases and Lichtblick read the same):

* a 3D panel following ``world``: the bodies as drawn, the joints and the collision solids (/scene,
  frame-locked to /tf), the robots' collision shapes hidden (/scene/collision: the settings turn it on),
  the frames' labels, axes and links hidden (the settings turn them on), a neutral floor grid sized and
  centred on the bodies' extent at their start (:func:`_grid`), the camera framing that extent;
* one Plot per unit of the scenario's asserted quantities (:class:`PlotPath`, from runner/cli/layouts.py:
  every quantity an assertion reads, each copy of an array, no limit), metres first, with the value at the
  current time in the legend;
* a State Transitions panel of the events (/events ``name``) and of state variables;
* the Log (/log: events, handler logs, sounds, each verdict when it was decided, the summary).

The message paths are the ones docs/trace-format.md documents. Pure data: nothing here reads a scenario.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from reports import trace_format as tf

__all__ = ["PLOT_ID", "LayoutSpec", "PlotPath", "body_path", "joint_path", "layout", "state_path", "write_layout"]

PANEL_TITLE = "foxglovePanelTitle"  # Foxglove's key for a panel's title in its config
GRID_COLOR = "#505050"  # dark grey, seen on the light grey background; a body's colour stays the only colour
GRID_CELLS = 10  # the grid's divisions: its size / 10 is a round length (0.1, 0.2, 0.5 x 10^k m)
PLOT_ID = "Plot!asserted"  # the first plot (metres); the others are Plot!asserted_<unit>
#: a unit's part of a panel id (ids are Foxglove's `<type>!<name>`: no "/" or "·")
UNIT_IDS = {"m": "", "m/s": "m_per_s", "rad": "rad", "rad/s": "rad_per_s", "N": "N", "N·m": "N_m", "1": "1",
            "m or rad": "m_or_rad", "J": "J", "N·s": "N_s", "N·m·s": "N_m_s"}  # fmt: skip


@dataclass(frozen=True)
class PlotPath:
    value: str  # a Foxglove message path
    label: str = ""
    unit: str = "m"  # plots are grouped by unit: newtons and metres never share an axis


@dataclass(frozen=True)
class LayoutSpec:
    """What a layout shows: plot paths, state-transition paths, and where the bodies start (camera)."""

    plots: Sequence[PlotPath]
    transitions: Sequence[str] = ()
    spheres: Sequence[tuple[Sequence[float], float]] = ()  # each body at its start: (centre, bounding radius)


def body_path(body: str, field: str, component: str, topic: str = tf.TOPIC_BODIES) -> str:
    """The message path of ``<body>.<field>.<component>``: pose from /tf, velocities from /bodies (or the
    part of it, ``topic``, that holds the body in a world of more than 8,000)."""
    if field in ("pos", "quat"):
        part = "translation" if field == "pos" else "rotation"
        return f'{tf.TOPIC_TF}.transforms[:]{{child_frame_id=="{body}"}}.{part}.{component}'
    return f"{topic}.{tf.field_path(body)}.{field}.{component}"


def joint_path(joint: str, field: str, topic: str = tf.TOPIC_JOINTS) -> str:
    return f"{topic}.{tf.field_path(joint)}.{'motor_force' if field == 'force' else field}"


def state_path(variable: str) -> str:
    return f"{tf.TOPIC_STATE}.{variable}"


def _extent(spheres: Sequence[tuple[Sequence[float], float]]) -> tuple[list[float], list[float]]:
    """The box (low corner, high corner) around the bodies' spheres; a 1 m cube at the origin without any."""
    if not spheres:
        return [-0.5, -0.5, -0.5], [0.5, 0.5, 0.5]
    return ([min(c[i] - r for c, r in spheres) for i in range(3)],
            [max(c[i] + r for c, r in spheres) for i in range(3)])  # fmt: skip


def _round_up(length: float) -> float:
    """The smallest of 1, 2, 5 x 10^k that is at least ``length``."""
    scale = 10.0 ** math.floor(math.log10(length))
    return next(round(m * scale, 12) for m in (1, 2, 5, 10) if m * scale >= length * (1 - 1e-12))


def _grid(spheres: Sequence[tuple[Sequence[float], float]]) -> dict[str, Any]:
    """The floor grid under the bodies: a square twice the bodies' larger horizontal extent at their start
    (2 m at least, as the camera's 1 m radius: bodies move, one layout serves every variant), rounded up to
    1, 2 or 5 x 10^k m, in 10 cells (so each is 0.1, 0.2 or 0.5 x 10^k m), centred under them on a cell
    corner, at z = 0 (the ground of every scenario with a floor)."""
    lo, hi = _extent(spheres)
    size = _round_up(2 * max(hi[0] - lo[0], hi[1] - lo[1], 2.0))
    cell = size / GRID_CELLS
    centre = [round(round((a + b) / 2 / cell) * cell, 9) + 0.0 for a, b in zip(lo[:2], hi[:2], strict=True)]
    return {"visible": True, "frameLocked": True, "label": "Grid", "instanceId": "grid", "layerId": "foxglove.Grid",
            "size": size, "divisions": GRID_CELLS, "lineWidth": 1, "color": GRID_COLOR,
            "position": [*centre, 0], "rotation": [0, 0, 0], "order": 1}  # fmt: skip


def _camera(spheres: Sequence[tuple[Sequence[float], float]]) -> dict[str, Any]:
    """A perspective view from above and to the side, centred on the bodies, at the distance where a 45-degree
    field of view holds the sphere around them all (1 / sin(22.5 deg) = 2.6 times its radius), that radius at
    least 1 m: bodies move, and one layout serves every variant of a file."""
    lo, hi = _extent(spheres)
    target = [(a + b) / 2 for a, b in zip(lo, hi, strict=True)]
    radius = math.dist(lo, hi) / 2
    return {
        "distance": round(2.6 * max(radius, 1.0), 3), "perspective": True, "phi": 55.0, "thetaOffset": 45.0,
        "targetOffset": [round(c, 3) for c in target], "target": [0, 0, 0], "targetOrientation": [0, 0, 0, 1],
        "fovy": 45, "near": 0.01, "far": 5000,
    }  # fmt: skip


def layout(spec: LayoutSpec) -> dict[str, Any]:
    """The layout (Foxglove's ``LayoutData``) for ``spec``."""
    plots = list(dict.fromkeys(spec.plots))
    three_d = {
        "followTf": tf.WORLD_FRAME, "followMode": "follow-pose", "cameraState": _camera(spec.spheres),
        "scene": {"transforms": {"showLabel": False, "axisScale": 0, "lineWidth": 0}},  # bodies, not axes
        "transforms": {},
        "topics": {tf.TOPIC_SCENE: {"visible": True}, tf.TOPIC_SCENE_COLLISION: {"visible": False},
                   tf.TOPIC_CONTACT_POINTS: {"visible": True}},  # only in traces that ask for contact points
        "layers": {"grid": _grid(spec.spheres)},
        "publish": {"type": "point", "poseTopic": "/move_base_simple/goal", "pointTopic": "/clicked_point",
                    "poseEstimateTopic": "/initialpose", "poseEstimateXDeviation": 0.5,
                    "poseEstimateYDeviation": 0.5, "poseEstimateThetaDeviation": 0.26179939},
        "imageMode": {},
        PANEL_TITLE: "Scene",
    }  # fmt: skip
    plots_by_unit: dict[str, list[PlotPath]] = {}
    for p in sorted(plots, key=lambda p: p.unit != "m"):  # metres first (a body's height is always there)
        plots_by_unit.setdefault(p.unit, []).append(p)
    plot_panels = {_plot_id(unit): _plot(unit, paths) for unit, paths in plots_by_unit.items()}
    plot_panels = plot_panels or {PLOT_ID: _plot("m", [])}
    transitions = [f"{tf.TOPIC_EVENTS}.name", *spec.transitions]
    events = {
        "paths": [{"value": p, "timestampMethod": "receiveTime"} for p in dict.fromkeys(transitions)],
        "isSynced": True, PANEL_TITLE: "Events and state",
    }  # fmt: skip
    return {
        "configById": {"3D!scene": three_d, **plot_panels, "StateTransitions!events": events,
                       "RosOut!log": {"searchTerms": [], "minLogLevel": 1, PANEL_TITLE: "Log"}},
        "globalVariables": {},
        "userNodes": {},
        "playbackConfig": {"speed": 1},
        "layout": {"direction": "row", "first": "3D!scene", "splitPercentage": 55,
                   "second": {"direction": "column", "first": _stack(list(plot_panels)), "splitPercentage": 60,
                              "second": {"direction": "column", "first": "StateTransitions!events",
                                         "second": "RosOut!log", "splitPercentage": 35}}},
    }  # fmt: skip


def _plot_id(unit: str) -> str:
    part = UNIT_IDS.get(unit, unit)
    return f"{PLOT_ID}_{part}" if part else PLOT_ID


def _plot(unit: str, paths: Sequence[PlotPath]) -> dict[str, Any]:
    return {
        "paths": [{"value": p.value, "enabled": True, "timestampMethod": "receiveTime", **({"label": p.label}
                   if p.label else {})} for p in paths],
        "showLegend": True, "legendDisplay": "floating", "showPlotValuesInLegend": True, "showXAxisLabels": True,
        "showYAxisLabels": True, "isSynced": True, "xAxisVal": "timestamp", "sidebarDimension": 240,
        PANEL_TITLE: f"Asserted quantities ({unit})",
    }  # fmt: skip


def _stack(panels: Sequence[str]) -> Any:
    """Panels one above the other, each the same height (a mosaic of column splits)."""
    if len(panels) == 1:
        return panels[0]
    return {"direction": "column", "first": panels[0], "second": _stack(panels[1:]),
            "splitPercentage": round(100 / len(panels), 3)}  # fmt: skip


def layout_text(spec: LayoutSpec) -> str:
    return json.dumps(layout(spec), indent=2, ensure_ascii=False) + "\n"


def write_layout(folder: Path, spec: LayoutSpec, name: str = tf.LAYOUT_FILE) -> Path:
    """Write ``folder/<name>`` (default ``foxglove-layout.json``; atomically: a reader never sees half a file)."""
    folder.mkdir(parents=True, exist_ok=True)
    target = folder / name
    tmp = target.with_name(f".{target.name}.{os.getpid()}.partial")
    try:
        tmp.write_text(layout_text(spec), encoding="utf-8")
        os.replace(tmp, target)
    except BaseException:
        tmp.unlink(missing_ok=True)  # a full disk leaves nothing half-written
        raise
    return target
