"""The trace writer in a second process, so that formatting and compressing the trace overlaps the run.

:class:`BackgroundTraceWriter` has :class:`~runner.trace.writer.TraceWriter`'s interface. Each call is sent
through a pipe to a child process that runs a real ``TraceWriter`` on it, in the same order, so the
file is byte for byte the one the in-process writer makes. A step travels as raw doubles (states,
joints, contacts packed with ``struct``, no pickling of arrays), and calls go in batches of
:data:`BATCH_STEPS` steps: the caller pays for packing a step's doubles instead of encoding and compressing
them (bench/results.md has both). The pipe's buffer bounds how far the child may lag, so memory stays flat.

Failures: opening errors (an existing file without ``force``, a bad folder) are raised by the
constructor, as in-process; a write error in the child is raised by the next ``finish()``. The child
ignores SIGINT and SIGTERM and obeys the pipe: an interrupted run finishes its trace as "interrupted"
through ``__exit__`` as before; if the run's process dies, the child sees the pipe close and leaves
the ``.partial`` file with every chunk it completed, as a killed in-process writer would (the batch
not yet sent, at most :data:`BATCH_STEPS` steps, is lost with the process).
"""

from __future__ import annotations

import multiprocessing
import signal
import struct
from collections.abc import Mapping, Sequence
from itertools import chain
from pathlib import Path
from types import TracebackType
from typing import Any

import numpy as np

from backends.types import BodyStates, Contact, ContactPoint, JointStates
from reports import trace_format as tf
from runner.errors import OutputError, OutputInUse, TraceError
from runner.trace.records import TraceMeta, finish_on_exit
from runner.trace.scene import SolidVisual
from runner.trace.writer import TraceWriter

__all__ = ["BATCH_STEPS", "BackgroundTraceWriter"]

#: steps gathered before the calls go through the pipe (fewer, larger writes)
BATCH_STEPS = 16
_CONTACT_FIELDS = 5  # a, b, points, depth, normal_force


def _pack_step(states: BodyStates, joints: JointStates, contacts: Sequence[Contact]) -> tuple[bytes, bytes, bytes]:
    rows = states.rows()
    jrows = np.concatenate((joints.position, joints.velocity, joints.motor_force)).astype(np.float64, copy=False)
    pairs = struct.pack(f"{_CONTACT_FIELDS * len(contacts)}d", *chain.from_iterable(contacts))
    return rows.tobytes(), jrows.tobytes(), pairs


def _unpack_step(rows: bytes, jrows: bytes, pairs: bytes) -> tuple[BodyStates, JointStates, list[Contact]]:
    r = np.frombuffer(rows, dtype=np.float64).reshape(-1, 13)
    j = np.frombuffer(jrows, dtype=np.float64).reshape(3, -1)
    c = np.frombuffer(pairs, dtype=np.float64).reshape(-1, _CONTACT_FIELDS).tolist()
    contacts = [Contact(int(a), int(b), int(k), d, f) for a, b, k, d, f in c]
    return BodyStates.from_rows(r), JointStates(j[0], j[1], j[2]), contacts


def _serve(conn: Any, path: Path, meta: TraceMeta, kwargs: dict[str, Any]) -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the run decides how the trace ends, through the pipe
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    try:
        writer = TraceWriter(path, meta, **kwargs)
    except BaseException as exc:  # noqa: BLE001 - every failure goes back to the caller
        conn.send(("error", type(exc).__name__, str(exc)))
        return
    conn.send(("ok", None, None))
    failure: tuple[str, str] | None = None
    while True:
        try:
            batch = conn.recv()
        except (EOFError, OSError):  # the run's process is gone: keep what was written
            writer._abandon()
            return
        for name, args in batch:
            if failure is None:
                try:
                    if name == "step":
                        t, rows, jrows, pairs, state = args
                        writer.step(t, *_unpack_step(rows, jrows, pairs), state)
                    elif name == "finish":
                        conn.send(("ok", None, str(writer.finish(*args))))
                        return
                    elif name == "abandon":
                        writer._abandon()
                        return
                    else:
                        getattr(writer, name)(*args)
                except BaseException as exc:  # noqa: BLE001
                    failure = (type(exc).__name__, str(exc))
                    writer._abandon()
            if failure is not None and name in ("finish", "abandon"):
                conn.send(("error", *failure))
                return


def _error_class(kind: str | None) -> type[Exception]:
    """The class of an error the writer process reported by name (a full disk stays an OutputError)."""
    classes: dict[str | None, type[Exception]] = {
        "ValueError": ValueError, "OutputError": OutputError, "OutputInUse": OutputInUse,
    }  # fmt: skip
    return classes.get(kind, TraceError)


def _context() -> Any:
    """forkserver (Linux): the writer forks from a server that imported the trace modules once, never
    from the run's process, which holds an engine and may have threads; spawn elsewhere."""
    if "forkserver" in multiprocessing.get_all_start_methods():
        ctx = multiprocessing.get_context("forkserver")
        ctx.set_forkserver_preload(["runner.trace.process"])
        return ctx
    return multiprocessing.get_context("spawn")


class BackgroundTraceWriter:
    """A :class:`~runner.trace.writer.TraceWriter` run by a child process (see the module docstring)."""

    def __init__(self, path: Path, meta: TraceMeta, **kwargs: Any) -> None:
        self.path = Path(path)
        self.partial_path = self.path.with_name(self.path.name + tf.PARTIAL_SUFFIX)
        ctx = _context()
        self._conn, child = ctx.Pipe()
        self._process = ctx.Process(target=_serve, args=(child, self.path, meta, kwargs))
        self._process.start()
        child.close()
        self._final: Path | None = None
        self._closed = False
        self._batch: list[tuple[str, tuple[Any, ...]]] = []
        self._batched_steps = 0
        status, kind, text = self._reply()
        if status == "error":
            self._process.join()
            self._closed = True
            raise _error_class(kind)(text)

    def _reply(self) -> tuple[str, str | None, str | None]:
        try:
            return self._conn.recv()
        except (EOFError, OSError) as exc:
            raise TraceError(f"the trace writer process for {self.path} ended unexpectedly") from exc

    def _send(self, name: str, *args: Any, now: bool = False) -> None:
        """Queue a call; the batch goes to the child after BATCH_STEPS steps, or at once with ``now``."""
        if self._closed:
            raise TraceError(f"trace {self.path} is already finished")
        self._batch.append((name, args))
        if name == "step":
            self._batched_steps += 1
        if now or self._batched_steps >= BATCH_STEPS:
            batch, self._batch, self._batched_steps = self._batch, [], 0
            try:
                self._conn.send(batch)
            except (BrokenPipeError, OSError) as exc:
                raise TraceError(f"the trace writer process for {self.path} ended unexpectedly") from exc

    # --- TraceWriter's interface ------------------------------------------------------------------

    def attach(self, name: str, data: bytes, media_type: str) -> None:
        self._send("attach", name, bytes(data), media_type)

    def scene(self, t: float, solids: Sequence[SolidVisual] = (), scales: Mapping[str, float] | None = None) -> None:
        self._send("scene", t, tuple(solids), dict(scales) if scales else None)

    def step(self, t: float, states: BodyStates, joints: JointStates, contacts: Sequence[Contact],
             state_vars: Mapping[str, bool | float | str]) -> None:  # fmt: skip
        self._send("step", t, *_pack_step(states, joints, contacts), dict(state_vars) if state_vars else {})

    def contact_points(self, t: float, points: Sequence[ContactPoint]) -> None:
        self._send("contact_points", t, list(points))

    def sensors(self, t: float, values: Sequence[float]) -> None:
        self._send("sensors", t, [float(v) for v in values])

    def event(self, t: float, name: str, source: str, detail: Mapping[str, Any] | None = None) -> None:
        self._send("event", t, name, source, dict(detail) if detail else None)

    def log(self, t: float, level: str, message: str, name: str = tf.LOGGER_SCENARIO) -> None:
        self._send("log", t, level, message, name)

    def sound(self, t: float, name: str, action: str, offset: float = 0.0, volume: float = 1.0) -> None:
        self._send("sound", t, name, action, offset, volume)

    def verdict(self, t: float, verdict: Mapping[str, Any]) -> None:
        self._send("verdict", t, dict(verdict))

    def verdicts(self, t: float, verdicts: Sequence[Mapping[str, Any]]) -> None:
        self._send("verdicts", t, [dict(v) for v in verdicts])

    def finish(self, status: str, summary: Mapping[str, Any]) -> Path:
        if self._final is not None:
            return self._final
        self._send("finish", status, dict(summary), now=True)
        self._closed = True
        reply, kind, text = self._reply()
        self._process.join()
        if reply == "error":
            raise _error_class(kind)(text or "")
        self._final = Path(text or self.path)
        return self._final

    def _abandon(self) -> None:
        if not self._closed:
            self._closed = True
            try:
                self._conn.send([*self._batch, ("abandon", ())])
            except OSError:
                pass
            self._process.join(5.0)

    def __enter__(self) -> BackgroundTraceWriter:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:  # fmt: skip
        if self._final is None and not self._closed:
            finish_on_exit(self, exc)
