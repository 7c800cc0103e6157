"""A trace file's MCAP records, front to back, framed by their lengths (no summary section needed): a damaged
record is yielded as a :class:`Damage` at its byte offset when recovering, else it raises
:class:`~reports.trace_model.TraceReadError`. Chunks are opened by :mod:`reports.trace_chunks`.
"""

from __future__ import annotations

import io
import struct
import zlib
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import IO, Any

from mcap.data_stream import ReadDataStream
from mcap.opcode import Opcode
from mcap.records import Attachment, Channel, Chunk, Footer, Header, Message, Metadata, Schema

from reports.trace_chunks import chunk_records
from reports.trace_model import TraceReadError

__all__ = ["MAX_CHUNK_BYTES", "Damage", "read_records"]


#: Bounded before the work: a chunk's uncompressed size (the writer closes chunks at 1 MiB; one 130 KB zstd
#: chunk declaring 2 GB was inflated whole)
MAX_CHUNK_BYTES = 256 * 1024 * 1024

_MAGIC = b"\x89MCAP0\r\n"
_READERS: dict[int, Callable[[ReadDataStream, int], Any]] = {
    Opcode.HEADER: lambda s, n: Header.read(s),
    Opcode.FOOTER: lambda s, n: Footer.read(s),
    Opcode.SCHEMA: lambda s, n: Schema.read(s),
    Opcode.CHANNEL: lambda s, n: Channel.read(s),
    Opcode.MESSAGE: Message.read,
    Opcode.CHUNK: lambda s, n: Chunk.read(s),
    Opcode.ATTACHMENT: lambda s, n: Attachment.read(s),
    Opcode.METADATA: lambda s, n: Metadata.read(s),
}  # the other records (indexes, statistics) hold nothing the reader needs


class Damage(Exception):
    """A record that cannot be read, at its byte offset: skipped when recovering, else the trace is refused."""

    def __init__(self, offset: int, what: str) -> None:
        super().__init__(f"damaged at byte {offset}: {what}")
        self.offset = offset


def _record(opcode: int, body: bytes) -> list[Any]:
    """The records of one record's bytes (a chunk's, decompressed and checked); raises on damage."""
    read = _READERS.get(opcode)
    if read is None:
        return []
    if opcode == Opcode.ATTACHMENT and len(body) >= 4:
        crc = struct.unpack_from("<I", body, len(body) - 4)[0]
        if crc and crc != zlib.crc32(body[:-4]):
            raise ValueError("the attachment fails its CRC")
    if opcode == Opcode.CHUNK:
        size = struct.unpack_from("<Q", body, 16)[0] if len(body) >= 24 else 0
        if size > MAX_CHUNK_BYTES:
            raise ValueError(f"a chunk declares {size} bytes uncompressed (at most {MAX_CHUNK_BYTES} are read)")
    record = read(ReadDataStream(io.BytesIO(body)), len(body))
    if isinstance(record, Chunk):
        return chunk_records(record)
    return [record]


def read_records(f: IO[bytes], size: int, recover: bool, path: Path) -> Iterator[Any]:
    """The records, front to back; a damaged one is yielded as a :class:`Damage`. A record whose bytes are
    whole but unreadable (a flipped bit in a chunk: its CRC or its compression fails) is skipped and
    reading goes on after it; a record cut off, or claiming more bytes than the file holds, ends the
    reading (nothing after it can be framed). Without ``recover`` the first damage raises."""
    if f.read(len(_MAGIC)) != _MAGIC:
        raise TraceReadError(f"{path} is not a physics-scenarios trace (not an MCAP file)")
    offset = len(_MAGIC)
    while True:
        head = f.read(9)
        if not head:  # the end of the file without its footer: unfinished (the caller refuses it unless recover)
            if recover:
                yield Damage(offset, "the file ends here, before its footer (unfinished)")
            return
        damage: Damage | None = None
        if len(head) < 9:
            damage = Damage(offset, "the file ends inside a record")
        else:
            opcode, length = struct.unpack("<BQ", head)
            if length > size - offset - 9:
                damage = Damage(offset, f"a record of {length} bytes; the file holds {size - offset - 9} more")
        if damage is None:
            body = f.read(length)
            try:
                records = _record(opcode, body)
            except Exception as exc:  # noqa: BLE001 - whatever a damaged record raises (zstd, CRC, struct...)
                found = Damage(offset, str(exc)[:300] or type(exc).__name__)
                if not recover:
                    raise TraceReadError(f"{path} is {found}; read what it holds with recover=True "
                                         "(`scenario inspect --recover`)") from exc  # fmt: skip
                yield found
                offset += 9 + length
                continue
            yield from records
            if opcode == Opcode.FOOTER:
                return
            offset += 9 + length
            continue
        if not recover:
            raise TraceReadError(f"{path} is {damage} (unfinished?); read what it holds with recover=True "
                                 "(`scenario inspect --recover`)")  # fmt: skip
        yield damage
        return
