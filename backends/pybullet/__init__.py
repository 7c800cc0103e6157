"""The PyBullet backend (the default): ODE semantics on PyBullet in DIRECT mode."""

from __future__ import annotations

from ._quiet import import_pybullet

import_pybullet()  # first, so that the engine's import banner is discarded

from ._backend import PyBulletBackend  # noqa: E402 - must follow the quiet import

__all__ = ["PyBulletBackend"]
