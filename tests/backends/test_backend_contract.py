"""The shared backend suite on every engine of the registry: ODE's semantics, checked against analytic
values. The tests ship with the package (backends/testing/contract_*.py) so that an engine outside this
repository runs the same ones (tests/outside_engine/); this module collects them for the engines here."""

from __future__ import annotations

from backends.registry import list_backends
from backends.testing import engine_fixtures
from backends.testing.contract import *  # noqa: F403

#: every listed engine, opt-in ones included (conftest.py's lists leave those out of the other suites)
backend_name, backend_cls, any_backend = engine_fixtures(*(e.name for e in list_backends()))


def test_a_backend_without_joint_reactions_refuses_a_world_that_reads_one_up_front() -> None:
    """The runner's side of ``joint:reaction``: a world that reads a reaction is refused before the build by an
    engine that does not declare it (the fake backend, for the runner's logic)."""
    from dataclasses import replace

    import pytest

    from backends.errors import UnsupportedFeature
    from backends.testing import worlds as w
    from backends.testing.worlds import make_backend

    world = replace(w.lab_door(), reaction_joints=(w.lab_door().joints[0].name,))
    with pytest.raises(UnsupportedFeature, match="needs joint:reaction, which backend `fake` does not support"):
        make_backend("fake", world)
