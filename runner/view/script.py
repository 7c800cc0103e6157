"""``--script FILE``: inputs made without a person, for tests and unattended recordings.

A YAML list; each entry happens at a simulated time (``at``, seconds: at the first step boundary at or
after it, as a timed input) or a wall-clock time (``after``, seconds since the window opened), and does
one thing: ``event`` (a Panda3D button event name, handled exactly as the window's own button events:
``space``, ``mouse1``, ``shift-space``, ``f3`` to pause...), ``screenshot`` (a PNG path: the window as
drawn then) or ``close: true`` (the window closes; the rest of the run goes on headless). When the run
has ended and every entry is done, the window closes by itself.

    - {at: 1.2, event: space}
    - {at: 2.0, screenshot: /tmp/door-opening.png}
    - {after: 3.5, event: mouse1}
    - {at: 4.0, close: true}
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import yaml

from runner.errors import UsageError

__all__ = ["ScriptEntry", "load_script"]


@dataclass(frozen=True)
class ScriptEntry:
    at: float | None  # simulated seconds
    after: float | None  # wall seconds since the window opened
    event: str = ""
    screenshot: Path | None = None
    close: bool = False


def _number(value: object, where: str, key: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value) or value < 0:
        raise UsageError(f"{where}: `{key}` must be a number of seconds >= 0, found {value!r}")
    return float(value)


def load_script(path: Path) -> list[ScriptEntry]:
    """The entries of a script file, in file order (UsageError naming the entry if one is wrong)."""
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise UsageError(f"{path}: cannot read the script: {exc.strerror or exc}") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"{path}:{mark.line + 1}:{mark.column + 1}" if mark is not None else str(path)
        raise UsageError(f"{where}: not YAML: {getattr(exc, 'problem', exc)}") from None
    if not isinstance(data, list):
        raise UsageError(f"{path}: expected a list of entries, found {type(data).__name__}")
    out = []
    for i, item in enumerate(data, 1):
        where = f"{path}: entry {i}"
        if not isinstance(item, dict):
            raise UsageError(f"{where}: expected a mapping like {{at: 1.2, event: space}}, found {item!r}")
        unknown = set(item) - {"at", "after", "event", "screenshot", "close"}
        if unknown:
            raise UsageError(f"{where}: unknown key `{sorted(unknown)[0]}`; expected at or after, and event, "
                             "screenshot or close")  # fmt: skip
        if ("at" in item) == ("after" in item):
            raise UsageError(f"{where}: give exactly one of `at` (simulated seconds) and `after` (wall seconds)")
        does = [k for k in ("event", "screenshot", "close") if k in item]
        if len(does) != 1:
            raise UsageError(f"{where}: give exactly one of `event`, `screenshot` and `close`")
        event = item.get("event", "")
        if "event" in item and (not isinstance(event, str) or not event.strip()):
            raise UsageError(f"{where}: `event` must be a Panda3D event name such as space or mouse1")
        if "close" in item and item["close"] is not True:
            raise UsageError(f"{where}: `close` must be true")
        shot = item.get("screenshot")
        if "screenshot" in item and not isinstance(shot, str):
            raise UsageError(f"{where}: `screenshot` must be a file path")
        out.append(
            ScriptEntry(
                at=_number(item["at"], where, "at") if "at" in item else None,
                after=_number(item["after"], where, "after") if "after" in item else None,
                event=str(event),
                screenshot=Path(shot) if isinstance(shot, str) else None,
                close="close" in item,
            )
        )
    return out
