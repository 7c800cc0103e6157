"""Who may write a case's output files: one run at a time, and never over a file this tool did not write.

A case writes, into its output folder, ``<stem>.mcap`` (through ``<stem>.mcap.partial``), and beside it
``<stem>.cost.json`` (its wall-clock cost) or ``<stem>.outcome.json`` (how its process ended, when the
trace cannot say). :func:`case_files` lists them.

**Exclusive output.** A run owns these names from start to finish through :class:`Claim`: an exclusive
``flock`` on ``.<stem>.mcap.lock`` in the same folder, taken before anything is written and released
(the lock file removed) when the case's last file is written. A second run for the same names finds the
lock held and fails at once with :class:`~runner.errors.OutputInUse` (exit 2), touching nothing; two
runs of different cases into one folder do not meet. The lock dies with its process, so a killed run
never blocks the next one (its lock file is taken over and removed). A file is published under its final
name by an atomic rename only.

**Re-running into previous outputs** needs no flag: the files of a case that this tool wrote are replaced
(removed when the claim is taken). A file it did not write is refused (:func:`foreign`), unless the user
asks with ``--force``. The tool recognises its own files by content, never by name alone:

* a trace (``.mcap``, ``.mcap.partial``): the MCAP magic, a header written by the Foxglove SDK's writer
  (:data:`reports.trace_format.SDK_LIBRARY`, or this tool's own name,
  :data:`reports.trace_format.LIBRARY`, in traces written before it), then this tool's ``scenario``
  metadata record; a ``.partial`` cut before that record counts as the tool's when its bytes are a
  prefix of the MCAP magic or it holds such a header;
* ``.outcome.json``: readable by :func:`reports.outcome.read_outcome` (format and outcome checked);
* ``.cost.json``: a JSON object naming this case's trace with a ``wall_seconds`` figure.
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import io
import json
import os
import struct
from collections.abc import Iterable
from pathlib import Path
from types import TracebackType

from reports import outcome as oc
from reports import trace_format as tf
from runner.errors import OutputError, OutputInUse, TraceError

__all__ = ["OUTPUT_ERRNOS", "RESOURCE_ERRNOS", "Claim", "case_files", "foreign", "is_own", "lock_path",
           "publish_trace", "refusal", "remove_own", "write_error"]  # fmt: skip

_MAGIC = b"\x89MCAP0\r\n"
_LIBRARIES = (tf.SDK_LIBRARY, tf.LIBRARY)

#: errno values of a resource fault while writing: the disk (or quota) is full, the device failed
RESOURCE_ERRNOS = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EIO, errno.EFBIG})
#: errno values of an output that cannot take what the tool writes (exit 74): a resource fault, or a file
#: system that is read-only or a folder not writable for this user (only where an output is written: the
#: same errno while reading an input is bad input)
OUTPUT_ERRNOS = RESOURCE_ERRNOS | {errno.EROFS, errno.EACCES, errno.EPERM}


def write_error(exc: OSError, what: str) -> TraceError:
    """``exc`` (raised while writing ``what``) in the tree: :class:`OutputError` for a resource fault (exit
    74), else :class:`TraceError` (a path that cannot be used, exit 2)."""
    cls = OutputError if exc.errno in OUTPUT_ERRNOS else TraceError
    return cls(f"cannot write {what}: {exc.strerror or exc}")


def case_files(trace: Path) -> list[Path]:
    """Every file a case may leave beside ``trace`` (its final name): trace, partial trace, cost, outcome."""
    return [trace, trace.with_name(trace.name + tf.PARTIAL_SUFFIX), oc.cost_path(trace), oc.outcome_path(trace)]


def lock_path(trace: Path) -> Path:
    return trace.with_name(f".{trace.name}.lock")


#: opcodes of the MCAP records read here, and mcap's StreamReader's default limit on a record's length
_HEADER, _METADATA, _RECORD_LIMIT = 0x01, 0x0C, 4 * 2**30
#: bytes read for the quick look at a trace's first two records
_HEAD_BYTES = 1 << 16


def _string(data: bytes, at: int) -> tuple[str, int]:
    """The length-prefixed UTF-8 string at ``at``, and where it ends; ValueError if it is not whole there."""
    if at + 4 > len(data):
        raise ValueError("cut")
    (n,) = struct.unpack_from("<I", data, at)
    if at + 4 + n > len(data):
        raise ValueError("cut")
    return str(data[at + 4 : at + 4 + n], "utf-8"), at + 4 + n


def _record(data: bytes, at: int, opcode: int) -> tuple[int, int]:
    """(where the content of the record at ``at`` starts, where the record ends) when it is whole in ``data`` and
    has ``opcode``; ValueError otherwise."""
    if at + 9 > len(data) or data[at] != opcode:
        raise ValueError("not that record")
    (length,) = struct.unpack_from("<Q", data, at + 1)
    if length > _RECORD_LIMIT or at + 9 + length > len(data):
        raise ValueError("too long or cut")
    return at + 9, at + 9 + length


def _own_trace_quick(path: Path) -> bool | None:
    """:func:`_own_trace`'s answer for a whole header and scenario record at the start of the file, read by hand
    (what mcap's StreamReader reads there, without importing it and its decompressors: a run over its previous
    trace pays for it at start-up); None where the file is anything else, for mcap's reader to decide."""
    try:
        with open(path, "rb") as f:
            data = f.read(_HEAD_BYTES)
        if not data.startswith(_MAGIC):
            return None
        start, end = _record(data, len(_MAGIC), _HEADER)
        _, at = _string(data, start)
        library, at = _string(data, at)
        if not library.startswith(_LIBRARIES):
            return False
        if library.startswith(tf.LIBRARY):
            return True
        start, end = _record(data, max(end, at), _METADATA)
        name, at = _string(data, start)
        if at + 4 > end:
            return None
        (size,) = struct.unpack_from("<I", data, at)
        keys, at, stop = set(), at + 4, at + 4 + size
        while at < stop:
            key, at = _string(data, at)
            _, at = _string(data, at)
            keys.add(key)
    except (OSError, ValueError):
        return None
    if at > end:  # the map ran past its record: mcap's reader reads on, into the next record
        return None
    return name == tf.METADATA_SCENARIO and tf.KEY_TRACE_FORMAT in keys


def _own_trace(path: Path) -> bool:
    quick = _own_trace_quick(path)
    return quick if quick is not None else _own_trace_read(path)


def _own_trace_read(path: Path) -> bool:
    """Whether ``path`` is the tool's trace (the module docstring), read by mcap's StreamReader."""
    from mcap.records import Header, Metadata  # mcap's reader (with its decompressors) only where a file is read
    from mcap.stream_reader import StreamReader

    from reports.trace_chunks import read_damage

    damage = read_damage()
    unread: tuple[type[Exception], ...] = (OSError, StopIteration, *damage)
    try:
        with open(path, "rb") as f:
            head = f.read(len(_MAGIC))
            if path.name.endswith(tf.PARTIAL_SUFFIX) and _MAGIC.startswith(head):
                if len(head) < len(_MAGIC):
                    return True
            if head != _MAGIC:
                return False
            f.seek(0)
            records = iter(StreamReader(f, skip_magic=False).records)
            header = next(records, None)
            if not isinstance(header, Header) or not header.library.startswith(_LIBRARIES):
                return False
            if header.library.startswith(tf.LIBRARY):
                return True
            partial = path.name.endswith(tf.PARTIAL_SUFFIX)
            try:
                record = next(records, None)
            except damage:  # a damaged second record (a chunk that does not inflate): not this tool's record
                return partial
    except unread:
        return path.name.endswith(tf.PARTIAL_SUFFIX) and _partial_header(path)
    if record is None:
        return partial
    if not isinstance(record, Metadata):
        return False
    return record.name == tf.METADATA_SCENARIO and tf.KEY_TRACE_FORMAT in record.metadata


def _partial_header(path: Path) -> bool:
    """A partial trace cut inside its header record: the magic, then this tool's name in the first bytes."""
    try:
        with open(path, "rb") as f:
            head = f.read(256)
    except OSError:
        return False
    return head.startswith(_MAGIC) and (any(n.encode() in head for n in _LIBRARIES) or len(head) < 64)


def _own_json(path: Path, trace: Path) -> bool:
    if path == oc.outcome_path(trace):
        try:
            oc.read_outcome(path)
        except ValueError:
            return False
        return True
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError):
        return False
    return isinstance(data, dict) and data.get("trace") == trace.name and "wall_seconds" in data


def is_own(path: Path, trace: Path) -> bool:
    """``path`` (one of :func:`case_files` of ``trace``) holds a file this tool wrote. Only regular files
    count: a folder, a FIFO or a symbolic link under one of these names is never the tool's."""
    if path.is_symlink() or not path.is_file():
        return False
    if path.name.endswith((tf.FILE_SUFFIX, tf.FILE_SUFFIX + tf.PARTIAL_SUFFIX)):
        return _own_trace(path)
    return _own_json(path, trace)


def foreign(traces: Iterable[Path]) -> list[Path]:
    """The files under the output names of these cases that exist and that this tool did not write."""
    return [p for t in traces for p in case_files(t) if (p.exists() or p.is_symlink()) and not is_own(p, t)]


def remove_own(trace: Path, force: bool = False) -> None:
    """Remove what an earlier run of this case left (only the tool's own files, unless ``force``)."""
    for path in case_files(trace):
        if (path.exists() or path.is_symlink()) and (force or is_own(path, trace)):
            try:
                path.unlink()
            except IsADirectoryError as exc:
                raise TraceError(f"cannot replace {path}: it is a folder") from exc
            except OSError as exc:
                raise write_error(exc, f"over {path}") from exc


class Claim:
    """The right to write one case's files (see the module docstring). A context manager; ``release()``
    is idempotent. Taking it also clears the case's earlier outputs (:func:`remove_own`), unless ``clear``
    is false."""

    def __init__(self, trace: Path, *, force: bool = False, clear: bool = True) -> None:
        self.trace = Path(trace)
        self.path = lock_path(self.trace)
        self._fd: int | None = None
        self._take()
        if not clear:  # taken again after the run, to add its outcome file beside what it left
            return
        try:
            remove_own(self.trace, force)
            left = foreign([self.trace])
            if left:
                raise TraceError(refusal(left))
        except BaseException:
            self.release()
            raise

    def _take(self) -> None:
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise write_error(exc, f"the trace folder {self.path.parent}") from exc
        while True:
            try:
                fd = os.open(self.path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o644)
            except OSError as exc:
                raise write_error(exc, f"the trace folder {self.path.parent}") from exc
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                owner = os.pread(fd, 32, 0).decode(errors="replace").strip()
                os.close(fd)
                who = f" (pid {owner})" if owner.isdigit() else ""
                raise OutputInUse(
                    f"another scenario run{who} is writing {self.trace}; wait for it to end, or choose another --out"
                ) from None
            try:
                same = os.path.samestat(os.fstat(fd), os.stat(self.path))
            except FileNotFoundError:  # its owner removed it as we opened it: take the next one
                same = False
            if same:
                self._fd = fd
                with contextlib.suppress(OSError):  # the pid is for the message only: a full disk may refuse it
                    os.ftruncate(fd, 0)
                    os.pwrite(fd, str(os.getpid()).encode(), 0)
                return
            os.close(fd)

    def release(self) -> None:
        if self._fd is None:
            return
        fd, self._fd = self._fd, None
        with contextlib.suppress(OSError):
            self.path.unlink()  # still holding the lock: a newcomer either waits on this inode or makes its own
        os.close(fd)

    def __enter__(self) -> Claim:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
                 ) -> None:  # fmt: skip
        self.release()


def refusal(paths: list[Path]) -> str:
    """The message refusing to overwrite ``paths`` (files the tool did not write)."""
    names = ", ".join(str(p) for p in paths[:3]) + (f" and {len(paths) - 3} more" if len(paths) > 3 else "")
    verb = "was" if len(paths) == 1 else "were"
    return (
        f"{names} {verb} not written by scenario and would be overwritten; move {'it' if len(paths) == 1 else 'them'}, "
        "choose another --out folder, or pass --force to overwrite"
    )


def _record_ends(data: bytes) -> list[int]:
    """Offsets in ``data`` (an MCAP file) at which a whole record ends, read by mcap's own stream reader."""
    from mcap.stream_reader import StreamReader

    from reports.trace_chunks import read_damage

    stops: tuple[type[Exception], ...] = (StopIteration, *read_damage())
    stream = io.BytesIO(data)
    ends = [len(_MAGIC)] if data.startswith(_MAGIC) else []
    records = iter(StreamReader(stream, skip_magic=False).records)
    while True:
        try:
            next(records)
        except stops:
            return ends
        ends.append(stream.tell())


def publish_trace(target: Path, data: bytes) -> None:
    """Write a trace made elsewhere (a Ray worker) under ``target`` as a local run would: through
    ``<final>.partial``, cut back to the last whole record if the disk fills (then
    :class:`~runner.errors.OutputError`), and renamed to ``target`` only when whole."""
    final = target.name.endswith(tf.FILE_SUFFIX)
    partial = target.with_name(target.name + tf.PARTIAL_SUFFIX) if final else target
    good = 0
    try:
        with open(partial, "wb", buffering=0) as f:
            for end in [*_record_ends(data), len(data)]:
                if end > good:
                    view = memoryview(data)[good:end]
                    while view:
                        view = view[f.write(view) :]
                    good = end
    except OSError as exc:
        with contextlib.suppress(OSError):
            os.truncate(partial, good)
        raise write_error(exc, f"trace {partial}") from exc
    if final:
        os.replace(partial, target)
