"""Handlers for keys and clicks: Panda3D's button event names (panda3d-semantics §7) can happen (from the
keyboard in `scenario view`), so a handler for one is accepted; a near-miss is still refused."""

from __future__ import annotations

from pathlib import Path

import pytest

from runner.errors import ScenarioValidationError
from runner.language.buttons import is_button_event
from runner.language.load import load_scenario

BUTTONS = ["space", "a", "3", "[", "f12", "mouse1", "wheel_up", "arrow_left", "space-up", "a-repeat",
           "shift-space", "control-mouse1", "shift-control-a", "shift-control-alt-meta-f1", "escape"]  # fmt: skip
NOT_BUTTONS = ["spaec", "f17", "mouse6", "A", "shift-", "-up", "control-shift-a", "shift-space-up", "box-into-door",
               "ab", "space-down", ""]  # fmt: skip


@pytest.mark.parametrize("name", BUTTONS)
def test_button_names_panda3d_throws(name: str) -> None:
    assert is_button_event(name)


@pytest.mark.parametrize("name", NOT_BUTTONS)
def test_other_names_are_not_buttons(name: str) -> None:
    assert not is_button_event(name)


SOURCE = """schema_version: 1
scenario: keys
world: {{dt: 0.01, duration: 1}}
bodies:
  box: {{box: [0.1, 0.1, 0.1], mass: 1, pos: [0, 0, 1]}}
on:
  {event}: [{{log: pressed}}]
"""


def test_a_handler_for_a_key_loads_and_a_misspelt_one_does_not(tmp_path: Path) -> None:
    good = tmp_path / "good.yaml"
    good.write_text(SOURCE.format(event="shift-space"))
    assert "shift-space" in load_scenario(good, None, ()).model.on
    bad = tmp_path / "bad.yaml"
    bad.write_text(SOURCE.format(event="spacee"))
    with pytest.raises(ScenarioValidationError, match="on.spacee: a handler for an event that can never happen"):
        load_scenario(bad, None, ())
