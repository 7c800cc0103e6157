"""Checks of what a valid scenario means, beyond names: no silent mistakes.

Each check reports through ``bad(path, message, at_key=False)`` (runner.language.refs collects them):

* interval cycles through any number of intervals (``a`` inlines ``b`` inlines ``a``);
* a handler for an event that can never happen (the rule assertions on events already follow);
* triggers named like the start event;
* times after the end of the run (``at``, windows, ``first``, ``played_at``...): such a check could only fail
  or never be reached, an input could never be delivered;
* ``backend_options`` for a backend that does not exist, or keys the backend does not accept (checked here so
  that ``validate`` refuses what ``run`` refuses).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Iterator
from typing import Any

from runner.language import model_assertions as A
from runner.language import model_behaviour as B
from runner.language.buttons import is_button_event
from runner.language.model import Scenario
from runner.language.model_walk import walk_steps
from runner.language.yaml_source import Path

Bad = Callable[..., None]
TIME_EPS = 1e-9


def unknown(kind: str, name: str, known: Iterable[str]) -> str:
    import difflib  # here: only an unknown name needs it

    known = sorted(known)
    close = difflib.get_close_matches(name, known, n=1, cutoff=0.6)
    hint = f"did you mean `{close[0]}`?" if close else f"defined: {', '.join(known) or 'none'}"
    return f"unknown {kind} `{name}`; {hint}"


# ---- interval cycles -----------------------------------------------------------------------------
def _inlined(definition: B.Step, ival: str) -> Iterator[tuple[str, Path]]:
    for step, path in walk_steps(definition, ("intervals", ival)):
        if step.interval is not None:
            yield step.interval, path + ("interval",)


def check_interval_cycles(model: Scenario, bad: Bad) -> None:
    """An interval that inlines itself through any chain of `interval:` steps cannot be built."""
    edges = {ival: list(_inlined(d, ival)) for ival, d in model.intervals.items()}
    done: set[str] = set()
    reported: set[frozenset[str]] = set()

    def visit(ival: str, chain: list[str]) -> None:
        for target, path in edges.get(ival, []):
            if target in chain:
                cycle = chain[chain.index(target) :] + [target]
                if frozenset(cycle) not in reported:
                    reported.add(frozenset(cycle))
                    text = " -> ".join(f"`{c}`" for c in cycle)
                    what = f"intervals {text} form a cycle"
                    if len(cycle) == 2:
                        what = f"interval `{target}` contains itself"
                    bad(path, f"{what}; an interval cannot inline itself")
            elif target in edges and target not in done:
                visit(target, [*chain, target])
        done.add(ival)

    for ival in model.intervals:
        if ival not in done:
            visit(ival, [ival])


# ---- events ----------------------------------------------------------------------------------------
def check_handlers(model: Scenario, bad: Bad, events: set[str]) -> None:
    for event in model.on:
        if event not in events and not is_button_event(event):  # a key or click in `scenario view` can send it
            bad(("on", event), f"a handler for an event that can never happen: {unknown('event', event, events)}", True)
    for name in model.triggers:
        if name == "start":
            bad(("triggers", name), "`start` is the event sent before the first step; name the trigger otherwise", True)


# ---- times ------------------------------------------------------------------------------------------
def _times(model: Scenario) -> Iterator[tuple[Any, Path]]:
    """Every point in time the scenario states (not durations), with where."""
    for i, item in enumerate(model.inputs):
        yield item.at, ("inputs", i, "at")
    for i, a in enumerate(model.assertions):
        where: Path = ("assertions", i)
        for field in ("at", "first", "played_at", "stopped_at", "time"):
            value = getattr(a, field, None)
            if value is not None:
                yield value, where + (field,)
        if isinstance(a, A.BecomesAssertion) and a.near is not None:
            yield a.near, where + ("near",)
        for field in ("during", "within", "time_within"):
            window = getattr(a, field, None)
            if window is not None:
                yield window[0], where + (field, 0)
                yield window[1], where + (field, 1)


def check_times(model: Scenario, bad: Bad) -> None:
    duration = model.world.duration
    for value, path in _times(model):
        if isinstance(value, int | float) and value > duration + TIME_EPS:
            what = "an input" if path[0] == "inputs" else "a time"
            bad(path, f"{what} at {value:g} s is after the end of the run (world.duration {duration:g} s)")
    for i, a in enumerate(model.assertions):
        for field in ("during", "within", "time_within"):
            window = getattr(a, field, None)
            if window is None:
                continue
            lo = math.inf if window[0] == "end" else window[0]
            hi = math.inf if window[1] == "end" else window[1]
            if lo > hi:
                bad(("assertions", i, field), f"expected a window [start, end] with start <= end, found {list(window)}")


# ---- backend options -------------------------------------------------------------------------------
def check_backend_options(model: Scenario, bad: Bad) -> None:
    if not model.backend_options:
        return
    from backends.errors import BackendError
    from backends.registry import KNOWN_BACKENDS, get_backend, is_installed

    names = [n for n, e in KNOWN_BACKENDS.items() if not e.hidden]
    for backend, options in model.backend_options.items():
        if backend not in KNOWN_BACKENDS:
            bad(("backend_options", backend), unknown("backend", backend, names), True)
            continue
        if not is_installed(backend):
            continue  # its keys cannot be known; `run` on it stops with the install hint
        try:
            accepted = get_backend(backend).Options.keys()
        except BackendError:
            continue
        for key in options:
            if key not in accepted:
                import difflib  # here: only an unknown option needs it

                close = difflib.get_close_matches(key, list(accepted), n=1, cutoff=0.6)
                hint = f"did you mean `{close[0]}`?" if close else f"accepted: {', '.join(sorted(accepted)) or 'none'}"
                bad(("backend_options", backend, key), f"unknown option `{key}` of backend `{backend}`; {hint}", True)
