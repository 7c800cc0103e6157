"""Which keys and clicks become the scenario's input events, and which ones the viewer keeps for itself.

Panda3D names every button event (notes: panda3d-semantics §7): a press is the button's name with the
held modifiers in front (``space``, ``shift-space``, ``control-mouse1``), a held key repeats as
``<name>-repeat``, a release is ``<button>-up`` without modifiers (``space-up``). The window's
ButtonThrower throws exactly those names; the viewer hears all of them through its general button
events and passes on the ones the scenario names (a handler under ``on:`` or an event assertion), at
the next step boundary, as a timed input due there would be delivered. The viewer's own keys are the
function keys below and ``escape``; they never reach the scenario.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any, Final

from runner.language import model_assertions as A

__all__ = ["RESERVED", "HELP_LINES", "button_event", "named_events", "reserved_action"]

#: the viewer's keys (press names) and what they do
RESERVED: Final = {
    "escape": "close",
    "f1": "help",
    "f2": "solids",
    "f3": "pause",
    "f4": "step",
    "f5": "slower",
    "f6": "faster",
    "f7": "camera",
}

HELP_LINES: Final = (
    "Esc close (the rest of the run goes on headless)   F1 this help   F2 collision shapes",
    "F3 pause / resume   F4 one step (paused)   F5 slower   F6 faster   F7 the lab's camera",
    "right-drag orbit   wheel zoom   other keys and clicks: the scenario's input events",
)

_SUFFIX: Final = {"down": "", "repeat": "-repeat", "up": "-up"}


def button_event(kind: str, button: str) -> str:
    """The Panda3D event name of a ButtonThrower general event: ``kind`` is down, repeat or up, ``button``
    the name it carries (with the modifier prefix for down and repeat, the bare button for up)."""
    return button + _SUFFIX[kind]


def reserved_action(name: str) -> str | None:
    """The viewer's action for a press (None for the scenario's events); releases and repeats of a
    reserved key are swallowed too (action "")."""
    if name in RESERVED:
        return RESERVED[name]
    for suffix in ("-up", "-repeat"):
        if name.endswith(suffix) and name.removesuffix(suffix) in RESERVED:
            return ""
    return None


def named_events(handlers: Iterable[str], assertions: Iterable[Any]) -> frozenset[str]:
    """The events a scenario names: its handlers' events and those of its event assertions."""
    names = set(handlers)
    for a in assertions:
        if isinstance(a, A.EventAssertion):
            names.update(n for n in (a.event, a.before, a.after) if n)
    return frozenset(names)
