"""The summary that ``scenario inspect TRACE`` prints: what ran, how it ended, what the trace holds."""

from __future__ import annotations

import io
import json
from pathlib import Path
from typing import Any

from rich.console import Console, Group
from rich.table import Table
from rich.text import Text

from reports import trace_format as tf
from reports.quantities import specs
from reports.trace_reader import Trace, read_trace

__all__ = ["render_inspect", "summary", "summary_text"]

_STATUS_STYLE = {
    tf.STATUS_PASSED: "bold green",
    tf.STATUS_FAILED: "bold red",
    tf.STATUS_ERROR: "bold red",
    tf.STATUS_ENGINE_FAILURE: "bold red",
    tf.STATUS_INTERRUPTED: "bold yellow",
    tf.STATUS_INCOMPLETE: "bold yellow",
}


def _short(value: Any, limit: int = 60) -> str:
    text = value if isinstance(value, str) else json.dumps(value, separators=(",", ":"))
    return text if len(text) <= limit else text[: limit - 1] + "…"


def _size(n: int) -> str:
    if n < 1024:
        return f"{n} B"
    return f"{n / 1024:.1f} KiB" if n < 1024 * 1024 else f"{n / 1024 / 1024:.1f} MiB"


def _overview(trace: Trace) -> Table:
    sc, res = trace.scenario, trace.result
    table = Table(show_header=False, box=None, pad_edge=False)
    table.add_column(style="bold")
    table.add_column()
    backend = sc.get(tf.KEY_BACKEND, "?")
    if sc.get(tf.KEY_BACKEND_VERSION):
        backend += f" {sc[tf.KEY_BACKEND_VERSION]}"
    status = Text(trace.status, style=_STATUS_STYLE.get(trace.status, "bold"))
    error = trace.summary.get("error") if res else None
    if error:
        status.append(f"  ({_short(error, 80)})", style="")
    steps = len(trace.times)
    span = f"{trace.times[0]:g} s to {trace.times[-1]:g} s" if steps else "no steps recorded"
    tool = f"physics-scenarios {sc.get(tf.KEY_TOOL_VERSION, '?')}, trace format {sc.get(tf.KEY_TRACE_FORMAT, '?')}"
    source = f"{sc.get(tf.KEY_SCENARIO_PATH, '?')} (sha256 {sc.get(tf.KEY_SCENARIO_SHA256, '?')[:12]})"
    rows: list[tuple[str, str | Text]] = [
        ("scenario", sc.get(tf.KEY_NAME, "?")),
        ("variant", sc.get(tf.KEY_VARIANT, "?")),
        ("backend", backend),
        ("status", status),
        ("steps", f"{steps} ({span})"),
        ("dt", f"{sc.get(tf.KEY_DT, '?')} s, {sc.get(tf.KEY_SUBSTEPS, '?')} substep(s)"),
        ("duration", f"{trace.duration:g} s simulated (scenario: {sc.get(tf.KEY_DURATION, '?')} s)"),
        ("scenario file", source),
        ("tool", tool),
    ]
    if not trace.complete:
        how = f"read up to its last complete chunk; stopped at: {trace.stop_reason}" if trace.recovered else "no footer"
        rows.append(("file", Text(f"unfinished ({how})", style="yellow")))
    elif trace.recovered:  # finished, with a damaged record skipped
        rows.append(("file", Text(f"damaged (read every other record; {trace.stop_reason})", style="yellow")))
    for key, value in rows:
        table.add_row(key, Text(value) if isinstance(value, str) else value)
    return table


def _channels(trace: Trace) -> Table:
    table = Table(title="Channels", title_justify="left")
    table.add_column("topic")
    table.add_column("schema")
    table.add_column("messages", justify="right")
    for info in trace.channels.values():
        table.add_row(Text(info.topic), Text(info.schema), str(info.count))
    return table


def _events(trace: Trace, limit: int) -> Table:
    table = Table(title=f"Events ({len(trace.events)})", title_justify="left")
    table.add_column("t (s)", justify="right")
    table.add_column("event", no_wrap=True)
    table.add_column("source", overflow="fold")
    for e in trace.events[:limit]:
        table.add_row(f"{e.t:.4f}", Text(e.name), Text(e.source))
    if len(trace.events) > limit:
        table.add_row("…", f"{len(trace.events) - limit} more", "")
    return table


def _verdicts(trace: Trace) -> Table:
    table = Table(title=f"Verdicts ({len(trace.verdicts)})", title_justify="left")
    table.add_column("decided (s)", justify="right")
    table.add_column("assertion", no_wrap=True)
    table.add_column("result", no_wrap=True)
    table.add_column("measured", overflow="fold")
    table.add_column("expected", overflow="fold")
    for v in trace.verdicts:
        status = v.status
        result = {"passed": Text("pass", "green"), "failed": Text("FAIL", "bold red"),
                  "known limit": Text("known limit", "yellow")}.get(status or "", Text("?"))  # fmt: skip
        measured = _short(v.data[tf.VERDICT_MEASURED]) if tf.VERDICT_MEASURED in v.data else ""
        expected = _short(v.data[tf.VERDICT_EXPECTED]) if tf.VERDICT_EXPECTED in v.data else ""
        decided = v.data.get("time")
        when = f"{decided:.4f}" if isinstance(decided, int | float) and not isinstance(decided, bool) else "-"
        table.add_row(when, Text(v.name), result, Text(measured), Text(expected))
    return table


def _attachments(trace: Trace) -> Table:
    table = Table(title="Attachments", title_justify="left")
    table.add_column("name")
    table.add_column("media type")
    table.add_column("size", justify="right")
    for a in trace.attachments:
        table.add_row(Text(a.name), Text(a.media_type), _size(a.size))
    return table


def _robots(trace: Trace) -> list[Table]:
    """Per robot (the bodies and joints named `<robot>.<member>`): its links' masses, and its joints' kinds,
    limits and axes (world frame, at the start) from the trace's specs, names as the model file spells them."""
    members: dict[str, tuple[list[dict[str, Any]], list[dict[str, Any]]]] = {}
    for k, key in enumerate((tf.KEY_BODY_SPECS, tf.KEY_JOINT_SPECS)):
        for spec in specs(trace, key):
            robot, dot, member = str(spec.get("name", "")).partition(".")
            if dot:
                members.setdefault(robot, ([], []))[k].append({**spec, "member": member})
    out = []
    for robot, (links, joints) in members.items():
        table = Table(title=f"Robot {robot}: links ({len(links)})", title_justify="left")
        table.add_column("link")
        table.add_column("mass (kg)", justify="right")
        for link in links:
            table.add_row(Text(link["member"]), _mass(link))
        out.append(table)
        table = Table(title=f"Robot {robot}: joints ({len(joints)})", title_justify="left")
        for column in ("joint", "kind", "limits", "axis (world, at the start)"):
            table.add_column(column)
        for joint in joints:
            table.add_row(*_joint_cells(joint))
        out.append(table)
    return out


def _mass(link: dict[str, Any]) -> str:
    mass = link.get("mass")
    if link.get("motion") == "static":
        return "static"
    return f"{mass:.6g}" if isinstance(mass, int | float) else "?"


def _joint_cells(joint: dict[str, Any]) -> list[Any]:
    lo, hi, kind = joint.get("lo"), joint.get("hi"), str(joint.get("kind", "?"))
    unit = {"hinge": " rad", "slider": " m"}.get(kind, "")
    shown = [f"{v:.6g}" if isinstance(v, int | float) else default for v, default in ((lo, "-inf"), (hi, "inf"))]
    limits = "" if lo is None and hi is None else f"{shown[0]} .. {shown[1]}{unit}"
    axis = joint.get("axis") if kind in ("hinge", "slider") else None
    return [Text(joint["member"]), kind, limits, " ".join(f"{c:.6g}" for c in axis) if isinstance(axis, list) else ""]


def summary(trace: Trace, max_events: int = 50) -> Group:
    """A rich renderable summarising ``trace``."""
    parts: list[Any] = [Text(str(trace.path), style="bold underline"), _overview(trace), _channels(trace)]
    parts += _robots(trace)
    if trace.events:
        parts.append(_events(trace, max_events))
    if trace.verdicts:
        parts.append(_verdicts(trace))
    if trace.attachments:
        parts.append(_attachments(trace))
    return Group(*parts)


def summary_text(trace: Trace, width: int = 100, max_events: int = 50) -> str:
    """The same summary as plain text (no colour), for logs, tests and ``--json``-less pipes."""
    buffer = io.StringIO()
    console = Console(file=buffer, width=width, color_system=None, force_terminal=False, highlight=False, emoji=False)
    console.print(summary(trace, max_events))
    return buffer.getvalue()


def render_inspect(path: str | Path, recover: bool = False, max_events: int = 50) -> Group:
    """Read ``path`` (``recover=True`` for an unfinished one) and summarise it.

    Raises :class:`reports.trace_reader.TraceReadError` when the file cannot be read.
    """
    return summary(read_trace(path, recover=recover), max_events)
