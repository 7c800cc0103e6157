"""The outside engine's own test: the contract suite shipped in physics-scenarios (backends.testing), run on
the backend it registers through the entry point. Skipped when the package is not installed (pip install -e
tests/outside_engine); a failure instead where SCENARIO_REQUIRE_OUTSIDE_ENGINE=1 (CI, .ci/run)."""

from __future__ import annotations

import os
from importlib.metadata import PackageNotFoundError, distribution

import pytest

_MISSING = "scenario-outside-engine is not installed: pip install -e tests/outside_engine"
try:
    distribution("scenario-outside-engine")
except PackageNotFoundError:
    if os.environ.get("SCENARIO_REQUIRE_OUTSIDE_ENGINE") == "1":
        pytest.fail(_MISSING, pytrace=False)
    pytest.skip(_MISSING, allow_module_level=True)

from backends.registry import entry, get_backend, list_backends  # noqa: E402
from backends.testing import engine_fixtures  # noqa: E402
from backends.testing.contract import *  # noqa: E402, F403

backend_name, backend_cls, any_backend = engine_fixtures("outside", edge_cases_also=())


def test_the_engine_is_registered_through_its_entry_point() -> None:
    item = entry("outside")
    assert item.package == "scenario-outside-engine" and item.target == "outside_engine.engine:OutsideBackend"
    assert get_backend("outside").__module__ == "outside_engine.engine"
    assert "outside" in [e.name for e in list_backends(include_hidden=True)]
    assert "outside" not in [e.name for e in list_backends()]  # hidden: a test engine without contacts
