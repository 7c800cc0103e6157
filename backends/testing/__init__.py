"""The backend contract suite, shipped with the package so that an engine's own tests can run it, in this
repository (tests/backends/test_backend_contract.py) or outside it (tests/outside_engine/ shows how).

In the engine's test directory::

    # conftest.py: the suite's fixtures for the engines under test (registry names)
    from backends.testing import engine_fixtures
    backend_name, backend_cls, any_backend = engine_fixtures("myengine")

    # test_contract.py: the suite's tests, collected by pytest from this module
    from backends.testing.contract import *  # noqa: F403

A registered engine whose distribution is not installed is skipped with its install hint; one whose adapter
module cannot be imported fails with that import error. Tolerances default to ODE's analytic expectations
with float64 rounding room (``backends.testing.tolerances``); an engine that is owed more says so with
``add_tolerances``, derived from its numerics beside each line. Where an engine misses the truth, the test keeps
its bound and ``add_deviations`` lists it with the measured deviation and cause: the fixtures mark it
``xfail(strict=True)`` on that engine (``DEVIATIONS``). ``worlds`` builds the suite's small
CompiledWorlds. Importing this package does not import pytest; the fixtures and the tests do.
"""

from __future__ import annotations

from .fixtures import engine_fixtures
from .tolerances import DEVIATIONS, add_deviations, add_tolerances, tol

__all__ = ["DEVIATIONS", "add_deviations", "add_tolerances", "engine_fixtures", "tol"]
