"""The shared backend suite on every engine of the registry: ODE's semantics, checked against analytic
values. The tests ship with the package (backends/testing/contract_*.py) so that an engine outside this
repository runs the same ones (tests/outside_engine/); this module collects them for the engines here."""

from __future__ import annotations

from backends.testing.contract import *  # noqa: F403
