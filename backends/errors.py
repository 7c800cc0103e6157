"""The project's exception tree (root and backend branch).

The tree lives at the bottom layer so that backends can raise it without importing the runner::

    PhysicsScenariosError                 root of everything this tool raises on purpose
    ├── ScenarioError                     (runner.errors) bad input: exit code 2
    │   ├── ScenarioValidationError       a field, with file:line:column
    │   └── UsageError                    bad command-line use
    ├── BackendError                      exit code 3
    │   ├── BackendNotInstalled           engine missing; carries an install hint
    │   ├── UnknownBackend                name not in the registry (exit 2)
    │   ├── UnsupportedFeature            the scenario needs a capability the backend lacks (exit 2)
    │   └── EngineFailure                 the engine raised its own error, reported a fatal state, or blew up
    ├── TraceError                        (runner.errors) a trace cannot be written or read
    └── InternalError                     a bug in this tool, not in the input or the engine: exit code 70
        └── ContractViolation             a backend's contract misused (backends/base.py, "Edge cases")

Engine exceptions are translated at the adapter boundary (backends/base.py, every contract method): only the
types the engine itself raises (``Backend.engine_errors``) become :class:`EngineFailure`; a bug in an adapter
stays the exception it is.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any


class PhysicsScenariosError(Exception):
    """Root of every error this tool raises on purpose."""


class BackendError(PhysicsScenariosError):
    """A backend could not be loaded, built or stepped."""


class UnknownBackend(BackendError):
    """The backend name is not in the registry."""


class BackendNotInstalled(BackendError):
    """The backend's engine is not importable; the message says how to install it."""


class UnsupportedFeature(BackendError):
    """The scenario needs a capability that the backend does not declare (``missing``: which ones, when known)."""

    missing: frozenset[Any] = frozenset()


class EngineFailure(BackendError):
    """The engine raised, or its state became invalid (NaN, inf, unbounded velocity).

    ``body``, ``time`` and ``last_good`` are filled in when known so the CLI can name them.
    """

    def __init__(
        self,
        message: str,
        *,
        backend: str | None = None,
        body: str | None = None,
        time: float | None = None,
        last_good: dict[str, object] | None = None,
    ) -> None:
        super().__init__(message)
        self.backend = backend
        self.body = body
        self.time = time
        self.last_good = last_good


class InternalError(PhysicsScenariosError):
    """A bug in this tool (a broken invariant, an adapter fault): never the user's input or the engine's doing."""


class ContractViolation(InternalError):
    """A backend method called in a way its contract forbids (see backends/base.py)."""


#: Python's own subclasses of exception types an engine may also raise (dartpy: RuntimeError): never the
#: engine's doing, so never translated.
_PYTHON_ONLY: tuple[type[BaseException], ...] = (RecursionError, NotImplementedError)


def engine_failure(backend: str, doing: str, exc: BaseException) -> EngineFailure:
    """The EngineFailure for ``exc``, an exception of the engine's own types caught at the adapter boundary.

    An exception of those types that Python itself raises (``_PYTHON_ONLY``) is re-raised as it is.
    """
    if isinstance(exc, _PYTHON_ONLY):
        raise exc
    return EngineFailure(f"{backend}: {doing} failed: {type(exc).__name__}: {exc}", backend=backend)


@contextmanager
def map_engine_errors(backend: str, doing: str, catch: tuple[type[BaseException], ...]) -> Iterator[None]:
    """Translate the engine's own exceptions (``catch``) raised inside into :class:`EngineFailure`.

    Anything else (a TypeError from a bug in an adapter, a KeyboardInterrupt) passes through unchanged.
    """
    try:
        yield
    except catch as exc:
        raise engine_failure(backend, doing, exc) from exc
