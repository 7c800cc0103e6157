"""How each engine imported a scenario's robots, read in a worker before any step (``scenario compare``).

:func:`import_job` is a job of :class:`runner.exec.pool.Pool`, like :func:`runner.exec.cases.run_case`: in the
worker it loads the case, compiles it, builds the engine's world (the registry's capability check first, as
``scenario run`` does) and returns what ``Backend.imported_model()`` read back from the engine, with what the
runner itself adds on that engine (its motor's damping and friction loss, its caps on effort and velocity:
runner.sim.joint_dynamics), as the plain data of :mod:`reports.imports`. :func:`read_imports` runs one job per
(case, backend) and turns each ending (a read, a refusal, an error, a crash) into that data.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from reports import imports as im
from runner.exec.cases import Case
from runner.exec.exits import classify
from runner.exec.pool import CRASHED, RETURNED, TIMED_OUT, Ending, Job, Pool
from runner.exec.transport import decode_error, encode_error

__all__ = ["file_digits", "import_job", "read_imports"]

#: seconds one engine may take to import and build a case's world
IMPORT_TIMEOUT = 300.0
_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def file_digits(paths: Sequence[str]) -> int:
    """The most significant digits any number in the model files is written with (a file states nothing more
    finely than that): the file's own precision, of the import comparison's tolerance."""
    best = 1
    for path in paths:
        try:
            text = Path(path).read_text(errors="replace")
        except OSError:
            continue
        for attr in re.findall(r'="([^"]*)"', text):
            for token in _NUMBER.findall(attr):
                mantissa = re.split(r"[eE]", token)[0].lstrip("+-").replace(".", "").lstrip("0")
                best = max(best, len(mantissa))
    return min(best, 17)


def import_job(case: Case, report: Any = None) -> dict[str, Any]:
    """In the worker: build ``case``'s world on its backend and read it back (module docstring)."""
    del report
    try:
        return _read(case)
    except Exception as exc:  # noqa: BLE001 - every error crosses to the parent with its class
        return {"status": "error", "error": encode_error(exc)}


def _read(case: Case) -> dict[str, Any]:
    from backends.errors import UnsupportedFeature
    from backends.registry import check_capabilities, get_backend
    from runner.compile.program import build_program
    from runner.language.load import load_scenario
    from runner.sim.joint_dynamics import driven_joints, native_joints

    loaded = case.loaded if case.loaded is not None else load_scenario(Path(case.path), case.variant, case.overrides)
    program = build_program(loaded)
    cls = get_backend(case.backend)
    world = program.world
    try:
        check_capabilities(cls, world)
        refusal = None
    except UnsupportedFeature as exc:  # the engine would not *run* it; it may still import it: show what it read
        refusal = exc
    try:
        with cls(world) as backend:
            model = backend.imported_model()
            skip = driven_joints(loaded.model) | native_joints(world, backend)
    except Exception:
        if refusal is not None:  # it cannot even build the world: the refusal is the answer
            raise refusal from None
        raise
    read: dict[str, Any] = {"status": im.READ if model is not None else im.NOT_REPORTED,
                            "eps": cls.precision.eps, "version": cls.engine_version()}  # fmt: skip
    if refusal is not None:
        needs = ", ".join(sorted(str(getattr(c, "value", c)) for c in refusal.missing)) or str(refusal)
        read["runs"] = f"imported, but `scenario run` refuses this world on it (needs {needs})"
    if model is None:
        return read
    runner = {}
    for spec in world.joints:
        moving = spec.kind.value in ("slider", "hinge") and spec.name not in skip
        d = spec.dynamics
        runner[spec.name] = {
            "damping": d.damping if moving and not cls.native_damping else 0.0,
            "frictionloss": d.frictionloss if moving else 0.0,
            "effort": d.effort if d.effort is not None and math.isfinite(d.effort) else None,
            "velocity": d.velocity if d.velocity is not None and math.isfinite(d.velocity) else None,
        }
    reach = {b.name: math.hypot(*b.pos) + math.hypot(*b.com) for b in world.bodies}
    read.update(im.model_data(model, runner, reach))
    return read


def read_imports(cases: Sequence[Case], jobs: int = 1) -> list[dict[str, Any]]:
    """One engine read (:mod:`reports.imports`) per case, in the order given."""
    out: dict[int, dict[str, Any]] = {}

    def end(index: int, ending: Ending) -> None:
        out[index] = _ending(cases[index], ending)

    todo = [Job(import_job, (c,), c.backend, IMPORT_TIMEOUT, cost=c.cost) for c in cases]
    with Pool(max(1, min(jobs, len(cases)))) as pool:
        pool.run(todo, end)
    return [out[i] for i in range(len(cases))]


def _ending(case: Case, ending: Ending) -> dict[str, Any]:
    base = {"backend": case.backend}
    payload = ending.payload or {}
    if ending.how == RETURNED and payload.get("status") in (im.READ, im.NOT_REPORTED):
        return {**base, **payload}
    if ending.how == RETURNED and payload.get("status") == "error":
        exit = classify(decode_error(payload["error"]))
        status = im.REFUSED if int(exit.code) == 2 else im.FAILED
        return {**base, "status": status, "message": exit.message or exit.label}
    if ending.how == CRASHED:
        return {**base, "status": im.FAILED, "message": f"crashed (signal {ending.signal}) while building"}
    if ending.how == TIMED_OUT:
        return {**base, "status": im.FAILED, "message": f"timed out after {ending.timeout:g} s while building"}
    return {**base, "status": im.FAILED, "message": f"ended without a result ({ending.how})"}
