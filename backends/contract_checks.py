"""The checks every public method of the backend contract (:class:`backends.base.Backend`) makes before it
calls the engine: the backend is open, the body or joint index is in the world; a failed check is a
:class:`~backends.errors.ContractViolation` (the runner never makes such a call for any scenario).
"""

from __future__ import annotations

from typing import ClassVar, NoReturn

import numpy as np

from .errors import ContractViolation
from .types import CompiledWorld, JointSpec, Motion

__all__ = ["ContractChecks", "held_by_joints", "is_index"]


class ContractChecks:
    """The checks of :class:`backends.base.Backend`, which sets the attributes they read."""

    name: ClassVar[str]
    world: CompiledWorld
    _closed: bool
    _motion: list[Motion]

    def _open(self, method: str) -> None:
        if self._closed:
            self._refuse(f"{method}() called after close()")

    def _refuse(self, what: str) -> NoReturn:
        raise ContractViolation(f"{self.name}: {what} (backends/base.py, the contract)")

    def _motion_of(self, body: int, method: str) -> Motion:
        if not (is_index(body) and 0 <= body < len(self._motion)):
            self._refuse(f"{method}: no body {body!r} (the world has {len(self._motion)})")
        return self._motion[body]

    def _joint(self, joint: int, method: str) -> JointSpec:
        joints = self.world.joints
        if not (is_index(joint) and 0 <= joint < len(joints)):
            self._refuse(f"{method}: no joint {joint!r} (the world has {len(joints)})")
        return joints[joint]


def is_index(value: object) -> bool:
    """A Python or numpy integer (not a bool, not a float that happens to be whole)."""
    return (type(value) is int) or isinstance(value, np.integer)


def held_by_joints(world: CompiledWorld) -> dict[int, str]:
    """Body index -> the name of a joint that holds it (either end, the environment excluded)."""
    index = {b.name: i for i, b in enumerate(world.bodies)}
    held: dict[int, str] = {}
    for joint in world.joints:
        for name in (joint.body, joint.other):
            if name is not None and name in index:
                held.setdefault(index[name], joint.name)
    return held
