"""Fixtures of the shared backend suite: every listed backend, skipped with a reason when unavailable."""

from __future__ import annotations

import importlib.util

import pytest

from backends.base import Backend
from backends.registry import entry, get_backend, is_installed, list_backends


@pytest.fixture(params=[e.name for e in list_backends()])
def backend_name(request: pytest.FixtureRequest) -> str:
    """The name of each non-hidden registered backend whose engine and adapter are importable."""
    name: str = request.param
    item = entry(name)
    if not is_installed(name):
        pytest.skip(f"engine not installed: {item.hint}")
    adapter = item.target.partition(":")[0]
    if importlib.util.find_spec(adapter) is None:
        pytest.skip(f"adapter not written yet: {adapter}")
    return name


@pytest.fixture
def backend_cls(backend_name: str) -> type[Backend]:
    return get_backend(backend_name)


@pytest.fixture(params=[*(e.name for e in list_backends()), "fake"])
def any_backend(request: pytest.FixtureRequest) -> str:
    """Every engine backend and the fake one: for the edge cases the contract settles for all of them."""
    name: str = request.param
    if not is_installed(name):
        pytest.skip(f"engine not installed: {entry(name).hint}")
    return name
