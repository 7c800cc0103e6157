"""Fixtures of the shared backend suite (backends/testing): every listed backend of the registry, built-in or
registered through an entry point, but the opt-in ones (``BackendEntry.opt_in``: they run the contract suite,
test_backend_contract.py, and what names them). An engine whose distribution is not installed is skipped; one
whose adapter cannot be imported fails with its import error."""

from __future__ import annotations

from backends.registry import list_backends
from backends.testing import engine_fixtures

backend_name, backend_cls, any_backend = engine_fixtures(*(e.name for e in list_backends() if not e.opt_in))
