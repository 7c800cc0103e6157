"""The ODE reference backend: the Open Dynamics Engine through panda3d.ode (no ShowBase, no window)."""

from __future__ import annotations

from ._backend import OdeBackend

__all__ = ["OdeBackend"]
