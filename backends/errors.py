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
    │   └── EngineFailure                 the engine raised, crashed or blew up (NaN, inf, runaway)
    ├── TraceError                        (runner.errors) a trace cannot be written or read
    └── InternalError                     a bug in this tool, not in the input or the engine: exit code 70
        └── ContractViolation             a backend's contract misused (docs/architecture.md, the contract)

Engine exceptions are translated at the adapter boundary with :func:`map_engine_errors`.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager


class PhysicsScenariosError(Exception):
    """Root of every error this tool raises on purpose."""


class BackendError(PhysicsScenariosError):
    """A backend could not be loaded, built or stepped."""


class UnknownBackend(BackendError):
    """The backend name is not in the registry."""


class BackendNotInstalled(BackendError):
    """The backend's engine is not importable; the message says how to install it."""


class UnsupportedFeature(BackendError):
    """The scenario needs a capability that the backend does not declare."""


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


@contextmanager
def map_engine_errors(backend: str, doing: str) -> Iterator[None]:
    """Translate any non-project exception raised inside into :class:`EngineFailure`."""
    try:
        yield
    except PhysicsScenariosError:
        raise
    except (KeyboardInterrupt, SystemExit, MemoryError):
        raise
    except Exception as exc:  # noqa: BLE001 - the boundary: every engine error is translated
        raise EngineFailure(f"{backend}: {doing} failed: {type(exc).__name__}: {exc}", backend=backend) from exc
