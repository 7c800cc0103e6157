"""Panda3D's names for keyboard and mouse button events (panda3d-semantics §7), without Panda3D.

A handler ``on: {space: ...}`` can fire when a user presses the key in ``scenario view`` even if no timed
input sends it, so a button's event name is an event that can happen. The names are ButtonThrower's: a
printable key as its lowercase character (``a``, ``3``, ``[``), the named keys and mouse buttons below; a
press or repeat may carry the modifiers ShowBase adds, in its order (``shift-``, ``control-``, ``alt-``,
``meta-``: ``shift-control-a``); ``-repeat`` and ``-up`` suffixes (a release never has modifiers).
"""

from __future__ import annotations

import re
import string
from typing import Final

__all__ = ["is_button_event"]

_NAMED: Final = frozenset(
    "escape enter tab backspace delete insert home end page_up page_down arrow_left arrow_right arrow_up "
    "arrow_down shift control alt meta lshift rshift lcontrol rcontrol lalt ralt caps_lock num_lock scroll_lock "
    "print_screen pause menu help space mouse1 mouse2 mouse3 mouse4 mouse5 wheel_up wheel_down wheel_left "
    "wheel_right".split()
    + [f"f{i}" for i in range(1, 17)]
)
_PRINTABLE: Final = frozenset(string.ascii_lowercase + string.digits + "`-=[]\\;',./")
_MODIFIERS: Final = re.compile(r"^(shift-)?(control-)?(alt-)?(meta-)?")


def _button(name: str) -> bool:
    return name in _NAMED or (len(name) == 1 and name in _PRINTABLE)


def is_button_event(event: str) -> bool:
    """Whether ``event`` is a name Panda3D throws for a keyboard or mouse button (``space``,
    ``shift-mouse1``, ``a-repeat``, ``space-up``)."""
    if event.endswith("-up") and len(event) > 3:
        return _button(event[:-3])
    base = event[:-7] if event.endswith("-repeat") and len(event) > 7 else event
    if _button(base):
        return True
    modifiers = _MODIFIERS.match(base)
    rest = base[modifiers.end() :] if modifiers else base
    return rest != base and _button(rest)
