"""Time what a run spends where, by wrapping methods of the backend class and the trace writer.

The wrappers only add ``time.perf_counter`` calls around the real methods (about 0.3 us per call, a few
calls per step: :func:`wrapper_cost` measures it), so a run keeps its behaviour and nearly its speed.
They are installed for the duration of a ``with`` block and removed after it; nothing in the product
is changed.
"""

from __future__ import annotations

import contextlib
import functools
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

#: Backend methods, by the part of the work they are.
ENGINE_STEP = ("step",)
ENGINE_READS = ("body_states", "joint_states", "contacts")
ENGINE_INPUTS = ("set_kinematic", "set_motor", "set_motors", "apply_force", "reset_body")
ENGINE_SETUP = ("__init__", "settings", "close")
#: TraceWriter methods (all of its public work).
TRACE_METHODS = ("__init__", "attach", "scene", "step", "event", "log", "sound", "verdict", "verdicts", "finish")


@dataclass
class Split:
    """Seconds and calls per method, keyed ``"<group>.<method>"``."""

    seconds: dict[str, float] = field(default_factory=dict)
    calls: dict[str, int] = field(default_factory=dict)

    def total(self, prefix: str, methods: tuple[str, ...] | None = None) -> float:
        return sum(
            s
            for k, s in self.seconds.items()
            if k.startswith(prefix + ".") and (methods is None or k.split(".", 1)[1] in methods)
        )

    def count(self, prefix: str) -> int:
        return sum(c for k, c in self.calls.items() if k.startswith(prefix + "."))


def _wrap(
    func: Callable[..., Any], key: str, split: Split, depth: list[int], clock: Callable[[], float] = time.perf_counter
) -> Callable[..., Any]:

    @functools.wraps(func)
    def timed(*args: Any, **kwargs: Any) -> Any:
        if depth[0]:  # a wrapped method called by another (e.g. __init__ -> set_motor): count the outer only
            return func(*args, **kwargs)
        depth[0] += 1
        start = clock()
        try:
            return func(*args, **kwargs)
        finally:
            split.seconds[key] = split.seconds.get(key, 0.0) + clock() - start
            split.calls[key] = split.calls.get(key, 0) + 1
            depth[0] -= 1

    return timed


@contextlib.contextmanager
def timed(
    targets: dict[str, tuple[type, tuple[str, ...]]], clock: Callable[[], float] = time.perf_counter
) -> Iterator[Split]:
    """Wrap ``{group: (class, method names)}`` while the block runs; yields the :class:`Split` (seconds of
    ``clock``: wall time by default, ``time.process_time`` for CPU time)."""
    split = Split()
    saved: list[tuple[type, str, Any]] = []
    depths: dict[str, list[int]] = {group: [0] for group in targets}
    try:
        for group, (cls, names) in targets.items():
            for name in names:
                original = cls.__dict__.get(name)
                inherited = getattr(cls, name, None)
                if inherited is None:
                    continue
                saved.append((cls, name, original))
                setattr(cls, name, _wrap(inherited, f"{group}.{name}", split, depths[group], clock))
        yield split
    finally:
        for cls, name, original in reversed(saved):
            if original is None:
                delattr(cls, name)
            else:
                setattr(cls, name, original)


def wrapper_cost(repeat: int = 200_000) -> float:
    """Seconds one wrapped call adds over a plain one."""

    class Probe:
        def f(self) -> None:
            return None

    probe = Probe()
    start = time.perf_counter()
    for _ in range(repeat):
        probe.f()
    plain = time.perf_counter() - start
    with timed({"probe": (Probe, ("f",))}):
        start = time.perf_counter()
        for _ in range(repeat):
            probe.f()
        wrapped = time.perf_counter() - start
    return max(0.0, (wrapped - plain) / repeat)
