"""What a layout's Plot panels should show for a trace, read from the trace with our reader.

A Foxglove message path of docs/trace-format.md (``/tf.transforms[:]{child_frame_id=="box"}.translation.z``,
``/bodies.box.vel.x``, ``/joints.slider.position``, ``/state.door_open``,
``/contacts.pairs[:]{a=="box"}{b=="door"}.normal_force``) is parsed here into the quantity it plots and its
series taken from :func:`reports.trace_reader.read_trace`'s arrays: an outside view of the paths the
layout writer (runner/trace/layout.py) builds, not a copy of its code. Foxglove's Plot legend shows, for each
path, the value of its last point at or before the playback time (Studio 1.48, ``PlotLegendRow``), so
:meth:`Series.at` is that value.
"""

from __future__ import annotations

import json
import re
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from reports import trace_format as tf
from reports.trace_reader import Trace

_TF = re.compile(
    r'/tf\.transforms\[:\]\{child_frame_id=="(?P<body>[^"]+)"\}\.(?P<part>translation|rotation)\.(?P<c>[wxyz])'
)
_BODIES = re.compile(r"/bodies(?:/\d+)?\.(?P<body>.+)\.(?P<field>vel|angvel)\.(?P<c>[xyz])")
_JOINTS = re.compile(r"/joints(?:/\d+)?\.(?P<joint>.+)\.(?P<field>position|velocity|motor_force)")
_STATE = re.compile(r"/state\.(?P<var>\w+)")
_SENSORS = re.compile(r"/sensors\.(?P<field>\w+)")
_CONTACT = re.compile(r'/contacts\.pairs\[:\]\{a=="(?P<a>[^"]+)"\}\{b=="(?P<b>[^"]+)"\}\.normal_force')


@dataclass
class Series:
    """One plotted path: the quantity it shows (``box.pos.z``, ``box.vel.x``, ``slider.force``,
    ``state.door_open``, ``contact(box, door)``) and its points."""

    quantity: str
    times: np.ndarray
    values: np.ndarray

    def at(self, t: float) -> float | None:
        """The value of the last point at or before ``t`` (None before the first)."""
        i = int(np.searchsorted(self.times, t + 1e-9, side="right")) - 1
        return float(self.values[i]) if i >= 0 else None

    @property
    def constant(self) -> bool:
        finite = self.values[np.isfinite(self.values)]
        return finite.size == 0 or bool(np.all(finite == finite[0]))


@dataclass
class Plotted:
    """A row of a Plot panel's legend: its label (the path when it has none) and its series."""

    label: str
    path: str
    series: Series | None  # None: the path names nothing this trace holds


def plot_rows(layout: Path) -> Iterator[tuple[str, str]]:
    """(legend label, message path) of every path of every Plot panel of a layout file."""
    for panel, config in json.loads(layout.read_text(encoding="utf-8"))["configById"].items():
        if panel.startswith("Plot!"):
            for path in config["paths"]:
                yield path.get("label") or path["value"], path["value"]


def series(trace: Trace, path: str) -> Series | None:
    """The trace's series a message path plots (None when it names nothing in the trace)."""
    if m := _TF.fullmatch(path):
        body, c = m["body"], m["c"]
        if body not in trace.bodies:
            return None
        if m["part"] == "translation":
            return Series(f"{body}.pos.{c}", trace.times, trace.bodies[body].pos[:, tf.VEC_KEYS.index(c)])
        return Series(f"{body}.quat.{c}", trace.times, trace.bodies[body].quat[:, tf.QUAT_KEYS.index(c)])
    if m := _BODIES.fullmatch(path):
        body, field, c = m["body"], m["field"], m["c"]
        if body not in trace.bodies:
            return None
        return Series(f"{body}.{field}.{c}", trace.times, getattr(trace.bodies[body], field)[:, tf.VEC_KEYS.index(c)])
    if m := _JOINTS.fullmatch(path):
        joint, field = m["joint"], m["field"]
        if joint not in trace.joints:
            return None
        name = "force" if field == "motor_force" else field
        return Series(f"{joint}.{name}", trace.joint_times, getattr(trace.joints[joint], field))
    if m := _CONTACT.fullmatch(path):
        points = [(t, p["normal_force"]) for t, pairs in trace.contacts for p in pairs
                  if (p["a"], p["b"]) == (m["a"], m["b"])]  # fmt: skip
        times = np.array([t for t, _ in points], dtype=float)
        return Series(f"contact({m['a']}, {m['b']})", times, np.array([f for _, f in points], dtype=float))
    if m := _SENSORS.fullmatch(path):
        name = next((n for n in trace.sensors if tf.sensor_field(n) == m["field"]), None)
        return None if name is None else Series(name, trace.sensor_times, trace.sensors[name])
    if (m := _STATE.fullmatch(path)) and m["var"] in trace.state:
        values = [np.nan if v is None or isinstance(v, str) else float(v) for v in trace.state[m["var"]]]
        return Series(f"state.{m['var']}", trace.state_times, np.array(values, dtype=float))
    return None


def shows(quantity: str, plotted: list[Series]) -> bool:
    """Whether the plotted series show an asserted quantity (``trace.scenario["asserted"]``): a body's
    speed by its velocity's three components, a contact by either order of its pair; a body's energy
    has no field in the trace, so nothing shows it."""
    names = {s.quantity for s in plotted}
    if quantity.startswith("contact(") and quantity.endswith(")"):
        a, _, b = quantity[len("contact(") : -1].partition(", ")
        return f"contact({a}, {b})" in names or f"contact({b}, {a})" in names
    head, _, last = quantity.rpartition(".")
    if last == "speed":
        return all(f"{head}.vel.{c}" in names for c in "xyz")
    return quantity in names


def seek_times(plotted: list[Series], start: float, steps: np.ndarray, most: int = 4) -> list[float]:
    """Up to ``most`` playback times after ``start`` at which every series that is not constant shows a
    value other than its value at ``start``, chosen greedily (the time that changes the most series first)
    among 40 times spread over the trace and, for each series, the time it is farthest from its start
    value. Each is half-way between two recorded steps (``steps``, their times), so that which point the
    legend shows does not hang on how a step's time rounds."""
    later = steps[steps > start]
    middles = (later[:-1] + later[1:]) / 2
    if not len(middles):
        return []
    candidates = set(middles[np.unique(np.linspace(0, len(middles) - 1, 40).round().astype(int))].tolist())
    todo = [s for s in plotted if not s.constant]
    for s in todo:
        shown = np.array([np.nan if (v := s.at(t)) is None else v for t in middles])
        base = s.at(start)
        gap = np.abs(shown - (0.0 if base is None else base))
        if base is None:  # no point yet at the start: any point differs
            gap = np.where(np.isnan(shown), -1.0, 1.0)
        if np.nanmax(gap, initial=-1.0) > 0:
            candidates.add(float(middles[int(np.nanargmax(gap))]))
    ordered = sorted(candidates)
    out: list[float] = []
    while todo and len(out) < most:
        counts = [sum(s.at(t) != s.at(start) for s in todo) for t in ordered]
        best = int(np.argmax(counts))
        if counts[best] == 0:
            break
        t = ordered[best]
        out.append(t)
        todo = [s for s in todo if s.at(t) == s.at(start)]
    return out
