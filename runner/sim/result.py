"""What one run of one scenario variant gives back (runner.sim.session), to every command."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from runner.sim.assertions import Verdict


@dataclass
class RunResult:
    """What one run gave: its status, verdicts, events, sounds, steps and timing."""

    scenario: str
    variant: str
    backend: str
    status: str  # passed | failed | engine-failure | interrupted
    verdicts: list[Verdict]
    end_time: float
    steps: int
    events: list[tuple[float, str, str]]
    sounds: list[tuple[float, str]]
    wall_seconds: float
    trace: str | None = None
    failure: str | None = None
    extra: dict[str, Any] = field(default_factory=dict)
    engine_messages: int = 0  # lines the engine printed about itself (Backend.drain_messages), in the trace log

    @property
    def passed(self) -> bool:
        return self.status == "passed"
