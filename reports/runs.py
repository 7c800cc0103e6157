"""The runs a report covers, read from files only: traces (finished or partial), outcome and cost files.

A run is named by its final trace path ``<scenario>__<variant>__<backend>.mcap``. Beside it may lie the
``.mcap.partial`` a crash left, the ``.outcome.json`` the isolating parent wrote when the process did
not finish (:mod:`reports.outcome`), and the ``.cost.json`` with its wall-clock cost (written by the
runner beside every finished trace). Any of these files, or a folder holding them, names the run; its
other files are found beside it.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from reports import outcome as oc
from reports import trace_format as tf
from reports.trace_reader import Trace, TraceReadError, read_trace

__all__ = ["ReportError", "Run", "load_runs", "run_files"]


class ReportError(Exception):
    """The inputs of a report cannot be used (not a trace, two traces of one run, nothing to report)."""


_LABELS = {
    tf.STATUS_PASSED: "passed",
    tf.STATUS_FAILED: "failed",
    tf.STATUS_ENGINE_FAILURE: "engine failure",
    tf.STATUS_INTERRUPTED: "interrupted",
    tf.STATUS_ERROR: "error",
    tf.STATUS_INCOMPLETE: "incomplete (trace cut off)",
}


@dataclass
class Run:
    scenario: str
    variant: str
    backend: str
    backend_version: str
    status: str  # a trace status (passed, failed, engine-failure, ...) or an outcome (crashed, timed-out, ...)
    label: str  # what a reader sees: "passed", "crashed (signal 11)", "timed out", ...
    detail: str = ""
    trace: Trace | None = None
    trace_name: str | None = None  # file name only, so a report does not depend on where files lie
    outcome: oc.RunOutcome | None = None
    wall_seconds: float | None = None
    engine_settings: dict[str, Any] = field(default_factory=dict)

    @property
    def key(self) -> tuple[str, str, str]:
        return (self.scenario, self.variant, self.backend)

    @property
    def passed(self) -> bool:
        return self.status == tf.STATUS_PASSED

    @property
    def has_steps(self) -> bool:
        return self.trace is not None and self.trace.times.size > 0


def run_files(paths: Iterable[Path]) -> list[Path]:
    """The run keys (final trace paths) named by ``paths``: files of a run, or folders holding them."""
    keys: dict[Path, None] = {}
    for path in paths:
        path = Path(path)
        if path.is_dir():
            found = [oc.trace_key(p) for p in sorted(path.iterdir()) if p.is_file()]
            for key in found:
                if key is not None:
                    keys[key] = None
            continue
        key = oc.trace_key(path)
        if key is None:
            raise ReportError(
                f"{path} is not a trace: expected a .mcap, .mcap.partial, .outcome.json or .cost.json file, "
                "or a folder holding them"
            )
        if not path.exists():
            raise ReportError(f"{path} does not exist")
        keys[key] = None
    if not keys:
        raise ReportError("no traces to report on")
    return list(keys)


def _wall_seconds(key: Path, trace: Trace | None) -> float | None:
    """The run's wall time: from its cost file, else from the trace's result summary (older traces)."""
    path = oc.cost_path(key)
    if path.exists():
        try:
            value = json.loads(path.read_text(encoding="utf-8")).get("wall_seconds")
        except (OSError, UnicodeDecodeError, json.JSONDecodeError, AttributeError) as exc:
            raise ReportError(f"{path} is not a readable cost file: {exc}") from exc
    elif trace is not None:
        value = trace.summary.get("wall_seconds")
    else:
        value = None
    if isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value) and value > 0:
        return float(value)
    return None


def _load(key: Path) -> Run:
    partial = key.with_name(key.name + tf.PARTIAL_SUFFIX)
    outcome_file = oc.outcome_path(key)
    outcome = None
    if outcome_file.exists():
        try:
            outcome = oc.read_outcome(outcome_file)
        except ValueError as exc:
            raise ReportError(str(exc)) from exc
    trace_file = key if key.exists() else partial if partial.exists() else None
    trace = None
    if trace_file is not None:
        try:
            trace = read_trace(trace_file, recover=trace_file == partial)
        except TraceReadError as exc:
            if outcome is None:
                raise ReportError(str(exc)) from exc
            trace_file = None  # a crash before anything readable was written: the outcome says it all
    if trace is None and outcome is None:
        raise ReportError(f"nothing to report for {key.name}: no trace and no outcome file")
    meta = trace.scenario if trace is not None else {}
    if outcome is not None:
        status, label, detail = outcome.outcome, outcome.label, outcome.detail
    else:
        status = trace.status if trace is not None else tf.STATUS_INCOMPLETE
        label = _LABELS.get(status, status)
        summary = trace.summary if trace is not None else {}
        detail = str(summary.get("failure") or summary.get("error") or "")
    try:
        settings = json.loads(meta.get(tf.KEY_ENGINE_SETTINGS, "{}"))
    except json.JSONDecodeError:
        settings = {}
    return Run(
        scenario=meta.get(tf.KEY_NAME) or (outcome.scenario if outcome else "?"),
        variant=meta.get(tf.KEY_VARIANT) or (outcome.variant if outcome else "?"),
        backend=meta.get(tf.KEY_BACKEND) or (outcome.backend if outcome else "?"),
        backend_version=meta.get(tf.KEY_BACKEND_VERSION) or (outcome.backend_version if outcome else ""),
        status=status,
        label=label,
        detail=detail,
        trace=trace,
        trace_name=trace_file.name if trace_file is not None else None,
        outcome=outcome,
        wall_seconds=_wall_seconds(key, trace) if trace_file == key else None,
        engine_settings=settings if isinstance(settings, dict) else {},
    )


def load_runs(paths: Iterable[Path]) -> list[Run]:
    """Read every run named by ``paths``; two files for one (scenario, variant, backend) are refused."""
    runs: dict[tuple[str, str, str], Run] = {}
    for key in run_files(paths):
        run = _load(key)
        if run.key in runs:
            raise ReportError(
                f"two runs of {' · '.join(run.key)}: {runs[run.key].trace_name} and {run.trace_name}; "
                "report on one folder of traces at a time"
            )
        runs[run.key] = run
    return list(runs.values())
