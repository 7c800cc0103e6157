"""Why an engine departs, where the data show a documented behaviour: the static sag of a soft joint.

An engine whose settings carry ``erp`` and ``cfm`` (ODE's) solves every constraint row softly: the row
is a spring and damper, kp = ERP / (h CFM) (ODE's manual, "Soft constraint and constraint force
mixing"). In steady state the row's velocity is 0, so its correction ERP e / h balances CFM F: a body
held by a joint to the environment under a steady load F sits e = F h CFM / ERP off what the joint
allows (docs/backends/ode.md, :data:`LINK`).

For each engine named as departing (reports.consensus) and each body held by a slider, hinge or fixed
joint to the environment, at the run's last step:

* the load F is the body's weight (its mass from the trace's body specs, gravity from the scenario file
  attached to the trace, a variant's ``set`` and ``--set`` applied) plus the normal forces of the
  contacts touching it at that step, taken along gravity (a body resting on it); for a slider only the
  part across its axis loads the locked rows;
* h is dt / substeps; the measured deviation is the body's distance from what the joint allows.

The cause is stated when the measured deviation lies within :data:`MARGIN` of the prediction (the
relation is exact for a body at rest; the margin leaves room for a settling row, which relaxes by
1 - ERP per step, and for float32 positions) and the sag is at least a tenth of the position threshold
(a smaller one cannot account for a departure beyond it).
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import yaml

from reports import trace_format as tf
from reports.quantities import specs
from reports.runs import Run
from reports.trace_reader import Trace

__all__ = ["LINK", "MARGIN", "gravity", "joint_sag"]

LINK = "docs/backends/ode.md#deviations-from-textbook-physics-odes-own-kept"
MARGIN = 0.01
_HELD = ("slider", "hinge", "fixed")
_DEFAULT_GRAVITY = (0.0, 0.0, -9.81)  # docs/language.md: world.gravity's default


def _vector(value: Any) -> np.ndarray | None:
    if isinstance(value, list | tuple) and len(value) == 3 and all(isinstance(v, int | float) for v in value):
        return np.asarray(value, float)
    return None


def gravity(trace: Trace) -> np.ndarray | None:
    """The run's gravity (m/s²) from the scenario file attached to its trace, or None if it cannot be read."""
    try:
        data = yaml.safe_load(trace.attachment(trace.scenario.get(tf.KEY_SCENARIO_PATH, "")))
    except (KeyError, yaml.YAMLError):
        return None
    if not isinstance(data, dict):
        return None
    world = data.get("world")
    found: Any = world.get("gravity", list(_DEFAULT_GRAVITY)) if isinstance(world, dict) else _DEFAULT_GRAVITY
    variants = data.get("variants")
    variant = variants.get(trace.scenario.get(tf.KEY_VARIANT, "")) if isinstance(variants, dict) else None
    if isinstance(variant, dict) and isinstance(variant.get("set"), dict):
        found = variant["set"].get("world.gravity", found)
    try:
        overrides = json.loads(trace.scenario.get("overrides", "[]"))
    except json.JSONDecodeError:
        return None
    for item in overrides if isinstance(overrides, list) else []:
        if isinstance(item, list) and len(item) == 2 and item[0] == "world.gravity":
            found = item[1]
    return _vector(found)


def _contact_load(trace: Trace, body: str) -> float:
    """The normal forces (N) of the contacts touching ``body`` at the trace's last step."""
    end = float(trace.times[-1])
    for t, pairs in reversed(trace.contacts):
        if abs(t - end) > 1e-9:
            return 0.0
        return sum(float(p.get("normal_force") or 0.0) for p in pairs if body in (p.get("a"), p.get("b")))
    return 0.0


def _number(settings: dict[str, Any], key: str) -> float | None:
    v = settings.get(key)
    return float(v) if isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) and v > 0 else None


def _final(q: dict[str, Any], backend: str) -> float | None:
    s = q["series"].get(backend)
    values = [v for v in (s["deviation"] if s else []) if v is not None]
    return values[-1] if values else None


def _sag(run: Run, joint: dict[str, Any], body: dict[str, Any], q: dict[str, Any]) -> dict[str, Any] | None:
    trace = run.trace
    erp, cfm = _number(run.engine_settings, "erp"), _number(run.engine_settings, "cfm")
    g = gravity(trace) if trace is not None else None
    measured = _final(q, run.backend)
    if trace is None or erp is None or cfm is None or g is None or measured is None or not run.has_steps:
        return None
    g_norm = float(np.linalg.norm(g))
    if g_norm == 0.0:
        return None
    weight = float(body.get("mass") or 0.0) * g + _contact_load(trace, body["name"]) * g / g_norm
    if joint["kind"] == "slider":
        axis = np.asarray(joint.get("axis") or (1.0, 0.0, 0.0), float)
        axis = axis / (np.linalg.norm(axis) or 1.0)
        weight = weight - (weight @ axis) * axis
    load = float(np.linalg.norm(weight))
    h = float(trace.scenario[tf.KEY_DT]) / max(1, int(trace.scenario.get(tf.KEY_SUBSTEPS, "1") or 1))
    predicted = load * h * cfm / erp
    if predicted < q["threshold"] / 10 or abs(measured - predicted) > MARGIN * predicted:
        return None
    return {"kind": "joint-sag", "backend": run.backend, "body": body["name"], "joint": joint["name"],
            "quantity": q["id"], "label": q["label"], "measured": round(measured, 9), "predicted": round(predicted, 9),
            "load": round(load, 6), "h": h, "erp": erp, "cfm": cfm, "margin": MARGIN, "link": LINK}  # fmt: skip


def joint_sag(runs: Sequence[Run], quantities: Sequence[dict[str, Any]], backends: Sequence[str]) -> dict[str, Any]:
    """backend -> the soft-joint sag that explains it (see the module docstring), for each of ``backends``
    where one does."""
    out: dict[str, Any] = {}
    by_id = {q["id"]: q for q in quantities}
    for run in runs:
        if run.backend not in backends or run.trace is None:
            continue
        bodies = {s["name"]: s for s in specs(run.trace, tf.KEY_BODY_SPECS)}
        for joint in specs(run.trace, tf.KEY_JOINT_SPECS):
            body = bodies.get(str(joint.get("body")))
            q = by_id.get(f"{joint.get('body')}:joint-distance")
            if joint.get("other") is not None or joint.get("kind") not in _HELD or body is None or q is None:
                continue
            found = _sag(run, joint, body, q)
            if found is not None:
                out[run.backend] = found
                break
    return out
