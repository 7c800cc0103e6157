"""Run conformance cases on one backend, in this process, and write one JSON line per case.

Started by :mod:`runner.conformance.pool` as ``python -m runner.conformance.worker JOB RESULTS``, one
process per backend. ``JOB`` is a JSON file ``{"backend": name, "cases": [{"id", "path", "variant"}]}``;
``RESULTS`` receives, per case, a ``{"case": id, "started": true}`` line before the run and a
``{"case": id, "result": {...}}`` line after it, each flushed at once, so that the parent knows which
case a crash or a hang interrupted. Nothing is written to stdout: engines print there.

A case's result keeps, for every assertion, the raw numbers behind its verdict (measured value, target,
tolerance), which the matrix needs to the last digit; verdicts only carry them formatted.
"""

from __future__ import annotations

import json
import math
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from backends.errors import BackendNotInstalled, EngineFailure, UnsupportedFeature
from backends.registry import check_capabilities, get_backend

from ..assertions import AssertionTracker, Verdict, tolerance
from ..errors import ScenarioValidationError
from ..expressions import Resolver
from ..program import build_program
from ..scenario import model_assertions as A
from ..scenario.load import load_scenario
from ..session import RunResult, Session


def _num(value: Any) -> float | None:
    """A finite float, or None (lists, booleans, text, NaN are not numbers for the matrix)."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    return float(value) if math.isfinite(value) else None


class RecordingTracker(AssertionTracker):
    """The runner's assertion tracker, also keeping (measured, target, tolerance) of numeric checks.

    It hooks the tracker's ``_sample`` and ``_extremum``; verdicts that carried these numbers themselves
    would make this subclass unnecessary.
    """

    def __init__(self, specs: Sequence[Any], expressions: Any, backend: str, dt: float) -> None:
        super().__init__(specs, expressions, backend, dt)
        self._index = {id(c.spec): i for i, c in enumerate(self.checks)}
        self.raw: dict[int, tuple[float | None, float | None, float | None]] = {}

    def number(self, value: Any, r: Resolver) -> float:
        return self._number(value, r)

    def _sample(self, s: Any, t: float, r: Resolver, contact: Any) -> Verdict:
        verdict = super()._sample(s, t, r, contact)
        if isinstance(s, A.ValueAssertion):
            measured = _num(self.expr[s.value].evaluate(r))
            if s.near is not None:
                target = self._number(s.near, r)
                tol = self._number(tolerance(s.tol, self.backend), r)
                self.raw[self._index[id(s)]] = (measured, target, tol)
            else:
                self.raw[self._index[id(s)]] = (measured, None, None)
        return verdict

    def _extremum(self, c: Any, r: Resolver) -> Verdict:
        verdict = super()._extremum(c, r)
        s = c.spec
        target = self._number(s.near, r)
        tol = self._number(tolerance(s.tol, self.backend), r)
        self.raw[self._index[id(s)]] = (_num(c.best), target, tol)
        return verdict


def _event_numbers(
    spec: Any, result: RunResult, tracker: RecordingTracker, r: Resolver
) -> tuple[float | None, float | None, float | None]:
    if isinstance(spec, A.EventAssertion):
        times = [t for t, name, _ in result.events if name == spec.event]
        if spec.first is not None:
            target = math.inf if spec.first == "end" else float(spec.first)
            tol = tracker.number(tolerance(spec.tol, tracker.backend), r)
            return (times[0] if times else None), _num(target), tol
        if isinstance(spec.count, int):
            return float(len(times)), float(spec.count), 0.0
        return None, None, None
    if isinstance(spec, A.SoundAssertion):
        times = [t for t, name in result.sounds if name == spec.sound]
        if spec.played_at is not None:
            tol = tracker.number(tolerance(spec.tol, tracker.backend), r)
            nearest = min(times, key=lambda t: abs(t - spec.played_at)) if times else None
            return nearest, float(spec.played_at), tol
        if isinstance(spec.count, int):
            return float(len(times)), float(spec.count), 0.0
    return None, None, None


def _checks(result: RunResult, tracker: RecordingTracker, resolver: Resolver) -> list[dict[str, Any]]:
    out = []
    for i, (check, verdict) in enumerate(zip(tracker.checks, result.verdicts, strict=True)):
        measured, target, tol = tracker.raw.get(i) or _event_numbers(check.spec, result, tracker, resolver)
        out.append(
            {
                "name": verdict.name,
                "passed": verdict.passed,
                "measured": measured,
                "target": target,
                "tol": tol,
                "measured_text": verdict.measured,
                "expected_text": verdict.expected,
                "time": _num(verdict.time),
                "message": verdict.message,
            }
        )
    return out


def _status(status: str, message: str, start: float, checks: list[dict[str, Any]] | None = None) -> dict[str, Any]:
    return {"status": status, "message": message, "checks": checks or [], "wall_seconds": time.perf_counter() - start}


def run_case(path: Path, variant: str | None, backend_name: str) -> dict[str, Any]:
    """Run one case on one backend; every failure becomes a status, never an exception.

    Statuses: passed, failed (an assertion), engine-failure (NaN, blow-up, engine error), unsupported (the
    backend lacks a feature the case needs), error (the case does not load, or the runner or an adapter
    raised something unexpected; the message names it).
    """
    start = time.perf_counter()
    try:
        loaded = load_scenario(path, variant)
        program = build_program(loaded)
        cls = get_backend(backend_name)
        check_capabilities(cls, program.world)
        backend = cls(program.world)
    except (UnsupportedFeature, BackendNotInstalled) as exc:
        return _status("unsupported", str(exc), start)
    except EngineFailure as exc:
        return _status("engine-failure", str(exc), start)
    except ScenarioValidationError as exc:
        return _status("error", str(exc), start)
    except Exception as exc:  # an adapter's bug must not lose the other cases: it shows in the matrix
        return _status("error", f"{type(exc).__name__}: {exc}", start)
    try:
        session = Session(program, backend)
        tracker = RecordingTracker(loaded.model.assertions, program.expressions, backend.name, program.world.dt)
        session.tracker = tracker
        result = session.run()
        return _status(result.status, "", start, _checks(result, tracker, session.resolver))
    except EngineFailure as exc:
        return _status("engine-failure", str(exc), start)
    except Exception as exc:  # as above
        return _status("error", f"{type(exc).__name__}: {exc}", start)
    finally:
        backend.close()


def main(argv: Sequence[str]) -> int:
    job = json.loads(Path(argv[0]).read_text())
    backend = job["backend"]
    with open(argv[1], "a", encoding="utf-8") as out:
        for case in job["cases"]:
            out.write(json.dumps({"case": case["id"], "started": True}) + "\n")
            out.flush()
            result = run_case(Path(case["path"]), case["variant"], backend)
            out.write(json.dumps({"case": case["id"], "result": result}, allow_nan=False) + "\n")
            out.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
