"""The one place a scenario's surface becomes the backends' ``Surface``: the world's default, a pair's
``surfaces:`` entry, a robot link's ``surface`` (tests/compile/test_pair_surfaces_to_engines.py follows a pair
through compile to each engine's own contact parameters)."""

from __future__ import annotations

from backends.types import Surface
from runner.language.model_base import Surface as ScenarioSurface


def compiled_surface(surface: ScenarioSurface) -> Surface:
    """ODE's contact surface, field by field by name (Surface is keyword-only)."""
    return Surface(bounce=surface.bounce, bounce_vel=surface.bounce_vel, mu=surface.mu)
