"""The PyBullet backend (the default): ODE semantics on PyBullet in DIRECT mode.

The adapter (and with it pybullet) is imported on first use of ``PyBulletBackend``, so that the engine-free
parts (``_options``) can be read without the engine.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ._backend import PyBulletBackend

__all__ = ["PyBulletBackend"]


def __getattr__(name: str) -> Any:
    if name == "PyBulletBackend":
        from ._quiet import import_pybullet

        import_pybullet()  # first, so that the engine's import banner is discarded
        from ._backend import PyBulletBackend

        return PyBulletBackend
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
