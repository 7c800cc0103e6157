"""The PyBullet backend (the default): ODE semantics on PyBullet in DIRECT mode."""

from __future__ import annotations

from ._backend import PyBulletBackend

__all__ = ["PyBulletBackend"]
