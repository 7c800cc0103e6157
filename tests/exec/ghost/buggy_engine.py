"""A test-only adapter with a bug: its third step raises TypeError (a bug in this tool, never the engine's)."""

from __future__ import annotations

from backends.fake import FakeBackend


class BuggyBackend(FakeBackend):
    name = "buggy"
    _steps = 0

    def step(self) -> None:
        self._steps += 1
        if self._steps == 3:
            raise TypeError("unsupported operand type(s) for +: 'float' and 'NoneType'")
        super().step()
