"""The fake backend's :class:`~backends.batch.WorldBatch`: N fake worlds stepped by one call, for the runner's
lockstep and batched-sweep logic (tests only; the physics is :class:`~backends.fake.FakeBackend`'s).

Each view is a FakeBackend whose ``_step`` only consumes the step ``step_all`` took for it. ``step_all``
advances each active world by the fake engine's own step, with numpy's floating-point errors raised: an
overflow or an invalid operation in a world's step is that world's :class:`~backends.errors.EngineFailure`
(the batch's engine calling that world fatal, as a real batched engine reports a world gone unstable), and
the other worlds go on. Worlds batch when they have the same structure (the bodies and joints by name, kind
and motion, the step and substeps); masses, surfaces, starting states, gravity and inputs may differ.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .batch import WorldBatch
from .errors import EngineFailure
from .fake import FakeBackend
from .types import CompiledWorld


class _FakeView(FakeBackend):
    """One world of the batch: its ``step()`` consumes the step ``step_all`` took (or raises its failure)."""

    def _build(self) -> None:
        super()._build()
        self.taken: EngineFailure | None | bool = False  # False: not stepped since the last step()

    def engine_step(self) -> None:
        """The fake engine's own step of this world (what a single FakeBackend's ``step()`` runs)."""
        super()._step()

    def _step(self) -> None:
        taken, self.taken = self.taken, False
        if taken is False:
            raise RuntimeError(f"{self.name}: step() on a batched world that step_all() did not step")
        if isinstance(taken, EngineFailure):
            raise taken


def _structure(world: CompiledWorld) -> tuple[object, ...]:
    """What the batch's worlds must share: bodies and joints (names, kinds, motions), step and substeps."""
    bodies = tuple((b.name, b.motion.value) for b in world.bodies)
    joints = tuple((j.name, j.kind.value, j.body, j.other) for j in world.joints)
    return bodies, joints, world.dt, world.substeps


def _differences(a: CompiledWorld, b: CompiledWorld) -> str:
    """How world ``b`` differs in structure from ``a``, in words."""
    if len(a.bodies) != len(b.bodies):
        return f"{len(b.bodies)} bodies, where variant 0 has {len(a.bodies)}"
    if len(a.joints) != len(b.joints):
        return f"{len(b.joints)} joints, where variant 0 has {len(a.joints)}"
    if (a.dt, a.substeps) != (b.dt, b.substeps):
        return f"dt {b.dt:g} s x {b.substeps} substeps, where variant 0 has {a.dt:g} s x {a.substeps}"
    return "other bodies or joints (names, kinds or motions) than variant 0"


class FakeWorldBatch(WorldBatch):
    """N fake worlds (see the module docstring)."""

    backend = FakeBackend

    @classmethod
    def why_not(cls, worlds: Sequence[CompiledWorld]) -> str | None:
        if not worlds:
            return "no worlds to batch"
        first = _structure(worlds[0])
        for k, world in enumerate(worlds[1:], start=1):
            if _structure(world) != first:
                return f"variant {k} has {_differences(worlds[0], world)}"
        return None

    def __init__(self, worlds: Sequence[CompiledWorld]) -> None:
        super().__init__(worlds)
        refusal = self.why_not(self.worlds)
        if refusal is not None:
            raise ValueError(f"these worlds do not batch: {refusal}")
        self._views: list[_FakeView] = []
        try:
            for world in self.worlds:
                self._views.append(_FakeView(world))
        except BaseException:
            self.close()
            raise

    @property
    def views(self) -> Sequence[FakeBackend]:
        return self._views

    def step_all(self, active: Sequence[bool]) -> dict[int, EngineFailure]:
        if len(active) != len(self._views):
            raise ValueError(f"step_all: {len(active)} flags for {len(self._views)} worlds")
        failed: dict[int, EngineFailure] = {}
        for i, (view, on) in enumerate(zip(self._views, active, strict=True)):
            if not on or view.closed:
                continue
            try:
                with np.errstate(over="raise", invalid="raise", divide="raise"):
                    view.engine_step()
            except FloatingPointError as exc:
                failed[i] = EngineFailure(f"fake (batched): world {i} failed in step {view.steps + 1}: {exc}",
                                          backend=view.name)  # fmt: skip
                view.taken = failed[i]
            else:
                view.taken = None
        return failed

    def close(self) -> None:
        for view in self._views:
            view.close()
