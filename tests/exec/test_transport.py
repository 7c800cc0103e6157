"""runner.exec.transport and exits: an exception crosses a process boundary with its class, message and the
fields the CLI uses, and gets the same exit code and first line as where it was raised."""

from __future__ import annotations

import errno
import json

import pytest

from backends.errors import BackendNotInstalled, ContractViolation, EngineFailure, UnknownBackend, UnsupportedFeature
from runner.errors import (
    BudgetExceeded,
    ExitCode,
    InternalError,
    Issue,
    OutputError,
    OutputInUse,
    ScenarioError,
    ScenarioValidationError,
    TraceError,
)
from runner.exec.exits import classify, most_severe
from runner.exec.transport import decode_error, encode_error
from runner.interrupts import Terminated
from runner.language.expressions import EvaluationError

CASES = [
    (ScenarioValidationError([Issue("a.yaml", 3, 5, "world.dt", "expected a number; found 'x'")]), 2),
    (EvaluationError("cannot evaluate \"box.pos.z + 'a' > 0\": arithmetic needs numbers"), 2),
    (UnknownBackend("Unknown backend `nope`."), 2),
    (UnsupportedFeature("needs joint-limits"), 2),
    (OutputInUse("another scenario run (pid 7) is writing out/x.mcap"), 2),
    (TraceError("out/x.mcap was not written by scenario"), 2),
    (BackendNotInstalled("Backend `mujoco` is not installed."), 3),
    (EngineFailure("body `rocket` reached a speed above 10000", body="rocket", time=0.51, last_good={"time": 0.5}), 3),
    (BudgetExceeded("stopped at t=0.07 s on dart: each step costs 0.18 s", time=0.07), 3),
    (OutputError("cannot write trace out/x.mcap.partial: No space left on device"), 74),
    (ContractViolation("set_kinematic on a dynamic body"), 70),
]


@pytest.mark.parametrize("exc,code", CASES, ids=[type(e).__name__ for e, _ in CASES])
def test_an_error_crosses_with_its_class_message_and_fields(exc: Exception, code: int) -> None:
    data = json.loads(json.dumps(encode_error(exc)))  # plain data, as a pipe or Ray carries it
    back = decode_error(data)
    assert type(back) is type(exc) and str(back) == str(exc)
    assert vars(back) == vars(exc) or isinstance(exc, ScenarioValidationError)
    assert classify(back) == classify(exc) and classify(back).code == code
    if isinstance(exc, ScenarioValidationError):
        assert back.issues == exc.issues  # type: ignore[attr-defined]


def test_a_class_this_process_has_not_loaded_comes_back_as_its_nearest_loaded_base() -> None:
    data = encode_error(EvaluationError("x"))
    data["mro"] = [["runner.not_loaded_here", "SomeError"], *data["mro"][1:]]
    data["module"], data["qualname"] = "runner.not_loaded_here", "SomeError"
    back = decode_error(data)
    assert isinstance(back, ScenarioError) and classify(back).code == 2


def test_a_bug_comes_back_as_an_internal_error_with_its_traceback() -> None:
    try:
        float("nan") + None  # type: ignore[operator]  # noqa: B018 - the bug
    except TypeError as exc:
        back = decode_error(json.loads(json.dumps(encode_error(exc))))
    assert isinstance(back, InternalError) and str(back).startswith("TypeError: unsupported operand")
    assert "Traceback (most recent call last)" in back.remote_traceback  # type: ignore[attr-defined]
    assert classify(back).headline.startswith("internal error, please report: TypeError:")


def test_an_os_error_keeps_its_errno() -> None:
    back = decode_error(encode_error(OSError(errno.ENOSPC, "No space left on device", "out/x")))
    assert isinstance(back, OSError) and back.errno == errno.ENOSPC
    assert classify(back).code == 74 and classify(back).headline == "output error: out/x: No space left on device"
    assert classify(PermissionError(errno.EACCES, "Permission denied", "out")).code == 2


def test_interruptions_and_the_order_of_severity() -> None:
    assert classify(Terminated()).code == 143 and classify(KeyboardInterrupt()).code == 130
    assert most_severe([0, 1, 3, 2]) == ExitCode.BAD_INPUT
    assert most_severe([1, 3]) == ExitCode.ENGINE_FAILURE and most_severe([0, 0]) == ExitCode.OK
    assert most_severe([2, 74, 70]) == ExitCode.INTERNAL_ERROR and most_severe([3, 143]) == ExitCode.TERMINATED


def test_an_interruption_wrapped_while_it_was_raised_is_still_an_interruption() -> None:
    """Python wraps an exception raised while a class is built (``__set_name__``: RuntimeError), pybind11 one
    raised while its module initialises (ImportError): a signal that lands there is still an interruption."""
    for outer in (RuntimeError("Error calling __set_name__ on 'Field' instance"), ImportError("initialization failed")):
        try:
            try:
                raise Terminated()
            except KeyboardInterrupt as inner:
                raise outer from inner
        except Exception as exc:  # noqa: BLE001
            assert classify(exc).code == 143 and classify(exc).label == "terminated"
