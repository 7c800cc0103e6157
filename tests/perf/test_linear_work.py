"""The runner's own work per step grows linearly with the number of bodies, measured by counting.

Python lines executed per step in the runner's code (runner/ and reports/, the trace formatting) are
counted with ``sys.settrace`` for 10, 20 and 40 bodies, each with a collision sphere, all of them
colliders and contact-event sources, all touching the ground. Linear work adds the same number of lines
per added body from 20 to 40 as from 10 to 20; a pairwise Python loop (every collider against every
node, every contact against every contact source) doubles it. Counting, unlike timing, is exact and
does not depend on the machine.
"""

from __future__ import annotations

import sys
from pathlib import Path
from types import FrameType
from typing import Any

import pytest

import runner.sim.run
from backends.fake import FakeBackend
from backends.types import Contact
from runner.language.load import load_scenario

ROOT = Path(__file__).resolve().parents[2]
COUNTED = (str(ROOT / "runner"), str(ROOT / "reports"))


class TouchingFake(FakeBackend):
    """The fake backend, with every body reported touching body 0 (the ground) after each step."""

    def contacts(self) -> list[Contact]:
        return [Contact(0, i, 4, 0.001, 10.0) for i in range(1, len(self.world.bodies))]


def scenario(tmp: Path, n: int) -> Path:
    nodes = "\n".join(f"    n{i}: {{body: crate_{i}, sphere: {{center: [0, 0, 0], radius: 0.3}}}}" for i in range(n))
    names = ", ".join(f"n{i}" for i in range(n))
    crates = ", ".join(f"crate_{i}" for i in range(n))
    text = f"""schema_version: 1
scenario: linear-work
world: {{gravity: [0, 0, -9.81], dt: 0.01, duration: 1}}
state: {{hits: 0}}
bodies:
  ground: {{plane: {{}}, motion: static}}
  crate: {{box: [0.2, 0.2, 0.2], density: 500, pos: [0, 0, 0.1], array: {{count: [{n}, 1, 1], spacing: [1, 0, 0]}}}}
collisions:
  nodes:
{nodes}
  from: [{names}]
  contacts_from: [{crates}]
on:
  crate_0-into-ground: [{{calc: {{hits: "state.hits + 1"}}}}]
assertions:
  - {{name: slow, always: max(crate.speed) < 100}}
  - {{name: low, at: end, value: min(crate.pos.z), max: 1}}
"""
    path = tmp / f"work_{n}.yaml"
    path.write_text(text)
    return path


def lines_run(path: Path, steps: int, out: Path, monkeypatch: pytest.MonkeyPatch) -> int:
    monkeypatch.setattr(runner.sim.run, "get_backend", lambda name: TouchingFake)
    loaded = load_scenario(path, None, (("world.duration", steps * 0.01),))
    count = 0

    def local(frame: FrameType, event: str, arg: Any) -> Any:
        nonlocal count
        if event == "line":
            count += 1
        return local

    def tracer(frame: FrameType, event: str, arg: Any) -> Any:
        return local if frame.f_code.co_filename.startswith(COUNTED) else None

    sys.settrace(tracer)
    try:
        result = runner.sim.run.run_loaded(loaded, "fake", out)
    finally:
        sys.settrace(None)
    assert result.steps == steps
    return count


def per_step(tmp: Path, n: int, monkeypatch: pytest.MonkeyPatch) -> float:
    path = scenario(tmp, n)
    short = lines_run(path, 4, tmp / "a", monkeypatch)
    long = lines_run(path, 8, tmp / "b", monkeypatch)
    return (long - short) / 4


def test_runner_lines_per_step_grow_linearly_with_bodies(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    work = {n: per_step(tmp_path, n, monkeypatch) for n in (10, 20, 40)}
    first = (work[20] - work[10]) / 10  # lines per added body, 10 -> 20
    second = (work[40] - work[20]) / 20  # lines per added body, 20 -> 40
    assert first > 0
    # linear: equal increments (the 25 % allows for sorting's log factor); pairwise loops: second = 2 x first
    assert second <= 1.25 * first, f"lines per step {work}: +{first:.0f}/body then +{second:.0f}/body"
