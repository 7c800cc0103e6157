"""The trace's file while it is written: ``<path>.partial``, opened with the overwrite rules, and the
unbuffered sink the SDK's MCAP writer writes it through.

The sink keeps the first failed write (the SDK only logs it) so that the writer re-raises it; a failed
write is cut back to the last whole record, so the ``.partial`` stays readable (docs/reliability.md).
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path

from runner.errors import TraceError
from runner.trace import output

__all__ = ["TraceSink", "open_partial"]


class TraceSink:
    """An unbuffered file: the mcap writer hands it whole records, so nothing waits in Python.

    A write that fails (disk full, I/O error) is undone: the file is cut back to the end of the last
    whole write, so a ``.partial`` left by the failure ends on a record boundary and is read to its end
    by ``inspect --recover``; every later write fails at once (:class:`~runner.errors.OutputError`)."""

    def __init__(self, path: Path, exclusive: bool) -> None:
        self._path = path
        self._file = open(path, "xb" if exclusive else "wb", buffering=0)
        self._pos = 0
        self.failed: TraceError | None = None
        self._discard = False

    def write(self, data: bytes | memoryview) -> int:
        if self._discard:  # abandoned: the SDK writer's last words go nowhere
            return len(memoryview(data))
        if self.failed is not None:
            raise self.failed
        view = memoryview(data).cast("B")
        total = len(view)
        try:
            while view:
                view = view[self._file.write(view) :]
        except OSError as exc:
            with contextlib.suppress(OSError):
                os.ftruncate(self._file.fileno(), self._pos)
            self.failed = output.write_error(exc, f"trace {self._path}")
            raise self.failed from exc
        self._pos += total
        return total

    def tell(self) -> int:
        return self._pos

    def seek(self, offset: int, whence: int = os.SEEK_SET) -> int:
        """Where the file is: the SDK writes with ``disable_seeking`` and only asks for the position."""
        if (whence, offset) not in ((os.SEEK_CUR, 0), (os.SEEK_SET, self._pos)):
            raise OSError(f"the trace sink does not seek (asked {offset}, {whence})")
        return self._pos

    def check(self) -> None:
        """Raise the first failed write, which the SDK only logs."""
        if self.failed is not None and not self._discard:
            raise self.failed

    def discard(self) -> None:
        """Ignore every later write (an abandoned trace keeps what is in the file)."""
        self._discard = True

    def flush(self) -> None:
        """Nothing is buffered here."""

    def close(self, sync: bool) -> None:
        if self._file.closed:
            return
        try:
            if sync:
                os.fsync(self._file.fileno())
        finally:
            self._file.close()


def open_partial(path: Path, partial_path: Path, force: bool) -> TraceSink:
    """The sink of a new trace at ``partial_path``; ``force=False`` refuses an existing trace or partial trace."""
    if not force and path.exists():
        raise TraceError(f"{path} already exists; pass --force to overwrite it")
    if not force and partial_path.exists():
        raise TraceError(
            f"{partial_path} (an unfinished trace) already exists; read it with "
            f"`scenario inspect --recover {partial_path}` or pass --force to overwrite it"
        )
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        return TraceSink(partial_path, exclusive=not force)
    except OSError as exc:
        raise output.write_error(exc, f"trace {partial_path}") from exc
