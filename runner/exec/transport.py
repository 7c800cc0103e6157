"""What crosses a process boundary: exceptions with their class and message, and run results, as plain data.

A child process (a local worker, a Ray task) never sends Python objects of the runner back; it sends
JSON-able dictionaries made here, and the parent rebuilds them:

* :func:`encode_error` / :func:`decode_error`: an exception travels as its module, class name, message
  and the plain attributes the CLI uses (``issues`` of a validation error, ``body``/``time``/``last_good``
  of an engine failure). The parent rebuilds *the same class* (any class of the project's tree, wherever it
  is defined) without calling its ``__init__``, so ``str(exc)`` is the child's message. The class is found
  among the modules this process has loaded, walking the child's MRO: a class whose module is not loaded
  here is rebuilt as its nearest loaded base (an ``ExpressionError`` as a ``ScenarioError``), which has
  the same exit code; nothing is imported by name. An exception from outside the tree (a ``TypeError``: a
  bug) comes back as :class:`~runner.errors.InternalError` naming the original class and carrying the
  child's traceback; an OSError keeps its errno.
* :func:`result_to_json` / :func:`result_from_json`: a :class:`~runner.sim.session.RunResult`.
"""

from __future__ import annotations

import dataclasses
import sys
import traceback
from typing import Any

from backends.errors import PhysicsScenariosError
from runner.errors import InternalError, Issue
from runner.sim.assertions import Verdict
from runner.sim.session import RunResult

__all__ = ["decode_error", "encode_error", "result_from_json", "result_to_json"]

_PLAIN = (str, int, float, bool, type(None))


def _plain(value: Any) -> bool:
    if isinstance(value, _PLAIN):
        return True
    if isinstance(value, list | tuple):
        return all(_plain(v) for v in value)
    if isinstance(value, dict):
        return all(isinstance(k, str) and _plain(v) for k, v in value.items())
    return False


def encode_error(exc: BaseException) -> dict[str, Any]:
    """``exc`` as plain data (see the module docstring)."""
    cls = type(exc)
    attrs = {k: v for k, v in vars(exc).items() if k != "issues" and _plain(v)}
    data: dict[str, Any] = {
        "module": cls.__module__,
        "qualname": cls.__qualname__,
        "mro": [[c.__module__, c.__qualname__] for c in cls.__mro__],
        "message": str(exc),
        "attrs": attrs,
        "traceback": "".join(traceback.format_exception(exc)),
    }
    issues = getattr(exc, "issues", None)
    if isinstance(issues, list) and all(isinstance(i, Issue) for i in issues):
        data["issues"] = [dataclasses.asdict(i) for i in issues]
    if isinstance(exc, OSError):
        data["errno"] = exc.errno
        data["strerror"] = exc.strerror
        data["filename"] = exc.filename if isinstance(exc.filename, str) else None
    return data


def _project_class(mro: list[list[str]]) -> type[PhysicsScenariosError] | None:
    """The first class of ``mro`` that is loaded here and belongs to the project's tree."""
    for module, qualname in mro:
        found: Any = sys.modules.get(module)
        for part in qualname.split("."):
            found = getattr(found, part, None)
        if isinstance(found, type) and issubclass(found, PhysicsScenariosError):
            return found
    return None


def decode_error(data: dict[str, Any]) -> BaseException:
    """The exception :func:`encode_error` described, rebuilt in this process."""
    module, qualname, message = str(data["module"]), str(data["qualname"]), str(data["message"])
    cls = _project_class(data.get("mro") or [[module, qualname]])
    if cls is not None:
        exc: BaseException = cls.__new__(cls)
        BaseException.__init__(exc, message)
        vars(exc).update(data.get("attrs", {}))
        if "issues" in data:
            vars(exc)["issues"] = [Issue(**i) for i in data["issues"]]
        return exc
    if data.get("errno") is not None and module == "builtins":
        os_error = OSError(int(data["errno"]), str(data.get("strerror") or message), data.get("filename"))
        return os_error
    bug = InternalError(f"{qualname}: {message}" if message else qualname)
    bug.remote_traceback = str(data.get("traceback", ""))  # type: ignore[attr-defined]
    return bug


def result_to_json(result: RunResult) -> dict[str, Any]:
    return {
        "scenario": result.scenario,
        "variant": result.variant,
        "backend": result.backend,
        "status": result.status,
        "verdicts": [v.as_dict() for v in result.verdicts],
        "end_time": result.end_time,
        "steps": result.steps,
        "events": [list(e) for e in result.events],
        "sounds": [list(s) for s in result.sounds],
        "wall_seconds": result.wall_seconds,
        "trace": result.trace,
        "failure": result.failure,
        "extra": result.extra,
        "engine_messages": result.engine_messages,
    }


def result_from_json(data: dict[str, Any]) -> RunResult:
    names = {f.name for f in dataclasses.fields(Verdict)}
    verdicts = [Verdict(**{k: v for k, v in d.items() if k in names}) for d in data["verdicts"]]
    return RunResult(
        scenario=data["scenario"],
        variant=data["variant"],
        backend=data["backend"],
        status=data["status"],
        verdicts=verdicts,
        end_time=data["end_time"],
        steps=data["steps"],
        events=[(float(t), str(n), str(s)) for t, n, s in data["events"]],
        sounds=[(float(t), str(n)) for t, n in data["sounds"]],
        wall_seconds=data["wall_seconds"],
        trace=data["trace"],
        failure=data["failure"],
        extra=data["extra"],
        engine_messages=int(data.get("engine_messages", 0)),
    )
