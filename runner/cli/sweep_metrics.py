"""`scenario sweep`'s metrics (``--metric EXPR``): refused before anything runs when they cannot be read from a
trace, evaluated on each case's last recorded state once the cases are done."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from runner.errors import UsageError


def final_values(loaded: Any, trace_path: Path, expressions: Sequence[str], backend: str) -> dict[str, Any]:
    """Each expression evaluated on the last recorded state of a trace that ``backend`` wrote (bodies, joints,
    state variables, contacts and event counts, ``eps`` its precision's; ``playing()`` has no recorded state
    and is refused)."""
    import numpy as np

    from backends.registry import entry
    from backends.types import BodyStates, JointStates
    from reports.trace_reader import TraceReadError, read_trace
    from runner.compile.program import build_program
    from runner.errors import TraceError
    from runner.language.expressions import compile_expression
    from runner.sim.resolver import Snapshot, StateResolver

    program = build_program(loaded)
    world = program.world
    try:
        trace = read_trace(trace_path)
    except TraceReadError as exc:
        raise TraceError(f"metrics: {exc}") from exc
    snap = Snapshot()
    if not trace.times.size:
        raise UsageError(f"metrics: the trace {trace_path.name} recorded no step")
    snap.time = float(trace.times[-1])
    rows = np.array([np.concatenate([s.pos[-1], s.quat[-1], s.vel[-1], s.angvel[-1]])
                     for s in (trace.bodies[b.name] for b in world.bodies)]).reshape(len(world.bodies), 13)  # fmt: skip
    snap.bodies = BodyStates.from_rows(rows)
    j = [trace.joints[x.name] for x in world.joints]
    snap.joints = JointStates(*(np.array([getattr(s, f)[-1] for s in j], dtype=float) for f in
                                ("position", "velocity", "motor_force")))  # fmt: skip
    state = {k: v[-1] for k, v in trace.state.items()}
    last = trace.contacts[-1] if trace.contacts and math.isclose(trace.contacts[-1][0], snap.time) else (0.0, [])
    touching = {frozenset((p["a"], p["b"])) for p in last[1]}

    def refuse(args: Sequence[Any]) -> Any:
        raise UsageError("metrics: playing() has no recorded state; use a state variable instead")

    functions: dict[str, Callable[[Sequence[Any]], Any]] = {
        "contact": lambda a: frozenset((str(a[0]), str(a[1]))) in touching,
        "count": lambda a: sum(e.name == str(a[0]) for e in trace.events),
        "playing": refuse,
    }
    eps = entry(backend).precision.eps
    resolver = StateResolver(world, program.groups, state, dict(loaded.model.params), snap, functions, eps=eps)
    out: dict[str, Any] = {}
    for text in expressions:
        try:
            out[text] = compile_expression(text).evaluate(resolver)
        except (KeyError, ValueError, TypeError, ZeroDivisionError) as exc:
            raise UsageError(f"metric `{text}` cannot be evaluated: {exc}") from exc
    return out


def check_metrics(texts: list[str], model: Any) -> None:
    """Refuse, before anything runs, a metric that does not parse or reads what a trace does not hold."""
    from runner.language.expressions import compile_expression
    from runner.language.names import readable_names

    valid = set(readable_names(model))
    for text in texts:
        try:
            expr = compile_expression(text)
        except ValueError as exc:
            raise UsageError(f"Invalid `--metric {text}`: {exc}") from exc
        unknown = sorted(n for n in expr.names if n not in valid) + sorted(expr.calls - {"contact", "count"})
        if unknown:
            raise UsageError(f"Invalid `--metric {text}`: it reads {', '.join(unknown)}, which no trace holds "
                             f"(names: bodies, joints, state., param., time; functions: contact, count)")  # fmt: skip
