"""Run one conformance case on one backend, in this process: the job a worker of runner.exec runs.

:mod:`runner.conformance.pool` sends :func:`job` to worker processes (:mod:`runner.exec.pool`), one
engine per process; what an engine prints goes to the worker's log, whose tail explains a crash.

A case's result keeps, for every assertion, the raw numbers behind its verdict (measured value, target,
tolerance: ``Verdict.value/target/tolerance``), which the matrix needs to the last digit.
"""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Any

from backends.errors import BackendNotInstalled, EngineFailure, UnsupportedFeature
from backends.registry import check_capabilities, get_backend
from runner.compile.program import build_program
from runner.errors import ScenarioValidationError
from runner.language.load import load_scenario
from runner.sim.session import RunResult, Session


def _num(value: Any) -> float | None:
    """A finite float, or None (lists, booleans, text, NaN are not numbers for the matrix)."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    return float(value) if math.isfinite(value) else None


def _default_tolerance(spec: Any, session: Session) -> float | None:
    """The default tolerance of an assertion whose `tol` names backends (None otherwise): what the
    matrix compares a backend's override and its measured error with."""
    tol = getattr(spec, "tol", None)
    if not isinstance(tol, dict):
        return None
    default = tol.get("default", 0.0)
    if isinstance(default, str):
        return _num(session.program.expressions[default].number(session.resolver))
    return float(default)


def _checks(result: RunResult, session: Session) -> list[dict[str, Any]]:
    specs = {a.name: a for a in session.program.loaded.model.assertions}
    return [
        {
            "name": v.name,
            "passed": v.passed != (v.known_limit is not None),  # the check itself, at its tolerance
            "measured": _num(v.value),
            "target": _num(v.target),
            "tol": _num(v.tolerance),
            "measured_text": v.measured,
            "expected_text": v.expected,
            "time": _num(v.time),
            "message": v.message,
            "default_tol": _default_tolerance(specs.get(v.name), session),
        }
        for v in result.verdicts
    ]


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
        result = session.run()
        return _status(result.status, "", start, _checks(result, session))
    except EngineFailure as exc:
        return _status("engine-failure", str(exc), start)
    except Exception as exc:  # as above
        return _status("error", f"{type(exc).__name__}: {exc}", start)
    finally:
        backend.close()


def job(path: str, variant: str | None, backend_name: str, report: object = None) -> dict[str, Any]:
    """One case, as a job of :class:`runner.exec.pool.Pool` (``report``: progress, unused here)."""
    return run_case(Path(path), variant, backend_name)
