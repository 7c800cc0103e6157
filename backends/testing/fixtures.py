"""The contract suite's pytest fixtures, made for a given list of engines (``engine_fixtures``)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from ..base import Backend
from ..registry import distribution_installed, entry, get_backend, import_adapter
from .tolerances import deviation


def available(name: str) -> str:
    """``name`` if its engine can run here. A distribution that is not installed skips (with the install
    hint); a registry line or entry point that is wrong, or an adapter that cannot be imported, fails with its
    own error: a typo must not pass as a skipped suite."""
    import pytest

    item = entry(name)  # UnknownBackend, BrokenBackend: fail
    if not distribution_installed(name):
        pytest.skip(f"engine not installed: {item.hint}")
    import_adapter(name)  # ImportError from the adapter: fail
    return name


def mark_deviation(request: Any, backend: str) -> None:
    """Mark the requesting test ``xfail(strict=True)`` where ``tolerances.DEVIATIONS`` has its line for
    ``backend``: the check keeps its derived tolerance and the run shows the measured deviation and cause."""
    import pytest

    node = request.node
    callspec = getattr(node, "callspec", None)
    params = "-".join(p for p in (callspec.id.split("-") if callspec else []) if p != backend)
    reason = deviation(getattr(node, "originalname", node.name), params, backend)
    if reason is not None:
        node.add_marker(pytest.mark.xfail(strict=True, reason=f"{backend}: {reason}"))


def engine_fixtures(*names: str, edge_cases_also: Sequence[str] = ("fake",)) -> tuple[Callable[..., Any], ...]:
    """The fixtures ``backend_name``, ``backend_cls`` and ``any_backend`` over ``names``; ``any_backend`` (the
    edge cases every backend settles identically) also runs ``edge_cases_also`` (the runner's fake backend).
    Assign them at the top of a conftest.py or test module under those names."""
    import pytest

    @pytest.fixture(name="backend_name", params=list(names))
    def backend_name(request: pytest.FixtureRequest) -> str:
        name = available(request.param)
        mark_deviation(request, name)
        return name

    @pytest.fixture(name="backend_cls")
    def backend_cls(backend_name: str) -> type[Backend]:
        return get_backend(backend_name)

    @pytest.fixture(name="any_backend", params=[*names, *(n for n in edge_cases_also if n not in names)])
    def any_backend(request: pytest.FixtureRequest) -> str:
        return available(request.param)

    return backend_name, backend_cls, any_backend
