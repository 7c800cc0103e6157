"""Batched engines: many worlds of one model advanced by one engine call (issue 33, docs/batch.md).

A sweep whose variants differ only in what an engine batches (initial states, inputs, forces and the per-world
model parameters the engine holds per world: masses, surfaces...) runs them as the worlds of one
:class:`WorldBatch`. Each world is driven by its own runner session through its own :class:`Backend` view (the
ordinary contract: inputs, reads), and every session of the batch steps in lockstep::

    for each session: inputs for this step (set_motor, apply_force, ...)      # the view stores them per world
    batch.step_all(active)                                                   # one engine call for all worlds
    for each session: view.step()  -> returns at once (its world has stepped), or raises that world's failure
                      body_states(), joint_states(), contacts() ...          # this world's slice

So a view's ``step()`` never advances the engine itself: it consumes the step ``step_all`` took for its world
(and raises the :class:`~backends.errors.EngineFailure` that world met in it, if any). Calling ``step()`` on a
view whose world was not stepped since its last ``step()`` is a programming error (RuntimeError).

The verdicts of a variant run in a batch are the verdicts of the same variant run alone on the same backend
(one world): the batch is an execution strategy, not a different engine.
"""

from __future__ import annotations

import abc
from collections.abc import Sequence
from typing import ClassVar

from .base import Backend
from .errors import EngineFailure
from .types import CompiledWorld


class WorldBatch(abc.ABC):
    """N worlds built from N compiled worlds that differ only in what the engine batches."""

    #: The backend whose semantics the worlds have (its registry name): a view is that backend's view.
    backend: ClassVar[type[Backend]]

    @classmethod
    @abc.abstractmethod
    def why_not(cls, worlds: Sequence[CompiledWorld]) -> str | None:
        """None when ``worlds`` can be one batch; otherwise the reason, in words a user reads (the sweep
        runs them separately and prints it), e.g. "variant 3 has 5 bodies, variant 0 has 4"."""

    def __init__(self, worlds: Sequence[CompiledWorld]) -> None:
        self.worlds = list(worlds)

    @property
    @abc.abstractmethod
    def views(self) -> Sequence[Backend]:
        """One backend per world, in the order of ``worlds``."""

    @abc.abstractmethod
    def step_all(self, active: Sequence[bool]) -> dict[int, EngineFailure]:
        """Advance every world whose ``active`` flag is set by ``world.dt`` (inactive ones: ended sessions,
        never read again, may be advanced too); returns the worlds that failed in this step, by index."""

    @abc.abstractmethod
    def close(self) -> None:
        """Free the engine's memory (views included); idempotent."""

    def __enter__(self) -> WorldBatch:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
