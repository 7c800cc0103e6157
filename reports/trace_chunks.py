"""A trace's chunks opened within bounds: inflated to no more than the size they declare, and read as the
records a chunk may hold (schemas, channels, messages) only.

mcap's own ``breakup_chunk`` trusts a chunk: zstd data whose frames state a larger size than the chunk
declares are inflated whole (a 40 KB chunk of 16 frames of zeros declaring 100 bytes became 1 GiB), lz4
data are inflated with no bound at all, and inflated zeros read as millions of empty records of opcode 0,
one Python loop each (minutes for one chunk). Here the inflation stops one byte past the declared size
(more is damage), the inflated bytes must have the declared size and CRC, and a record other than a
schema, channel or message (opcode 0 included) is damage at once. A protobuf schema must build into a
descriptor pool (:func:`check_schema`): the scene and the report build one from it.
"""

from __future__ import annotations

import io
import struct
import zlib
from typing import Any

from mcap.data_stream import ReadDataStream
from mcap.opcode import Opcode
from mcap.records import Channel, Chunk, Message, Schema

__all__ = ["check_schema", "chunk_records", "inflate", "read_damage"]

_PIECE = 1 << 20


def read_damage() -> tuple[type[Exception], ...]:
    """What mcap's own readers (``StreamReader``, ``make_reader``) raise on a damaged file: mcap's errors, a cut
    record's (``EOFError``, ``struct.error``, ``ValueError``) and, on a damaged compressed chunk, its
    decompressors' own: zstandard's ``ZstdError`` and lz4's ``RuntimeError`` (checked: a chunk of garbage
    behind a valid header raises each, not an mcap error)."""
    from mcap.exceptions import McapError
    from zstandard import ZstdError

    return McapError, EOFError, ValueError, struct.error, ZstdError, RuntimeError


def inflate(chunk: Chunk) -> bytes:
    """The chunk's records as bytes, at most its declared size; ``ValueError`` when they are not that size."""
    declared = chunk.uncompressed_size
    if chunk.compression == "":
        data = chunk.data
    elif chunk.compression == "zstd":
        import zstandard

        reader = zstandard.ZstdDecompressor().stream_reader(io.BytesIO(chunk.data), read_across_frames=True)
        pieces: list[bytes] = []
        total = 0
        while total <= declared:
            piece = reader.read(min(_PIECE, declared + 1 - total))
            if not piece:
                break
            pieces.append(piece)
            total += len(piece)
        data = b"".join(pieces)
    elif chunk.compression == "lz4":
        import lz4.frame

        data = lz4.frame.LZ4FrameDecompressor().decompress(chunk.data, max_length=declared + 1)
    else:
        raise ValueError(f"a chunk compressed with {chunk.compression[:40]!r} (zstd, lz4 or none are read)")
    if len(data) != declared:
        more = "more than" if len(data) > declared else f"{len(data)} bytes, not"
        raise ValueError(f"a chunk inflates to {more} the {declared} bytes it declares")
    if chunk.uncompressed_crc and zlib.crc32(data) != chunk.uncompressed_crc:
        raise ValueError("a chunk fails its CRC")
    return data


_READ = {Opcode.SCHEMA: lambda s, n: Schema.read(s), Opcode.CHANNEL: lambda s, n: Channel.read(s),
         Opcode.MESSAGE: Message.read}  # fmt: skip


def chunk_records(chunk: Chunk) -> list[Any]:
    """The schemas, channels and messages of ``chunk``; ``ValueError`` at the first record that is not one."""
    data = inflate(chunk)
    out: list[Any] = []
    at = 0
    while at < len(data):
        if len(data) - at < 9:
            raise ValueError(f"a chunk ends inside a record at its byte {at}")
        opcode, length = struct.unpack_from("<BQ", data, at)
        read = _READ.get(opcode)
        if read is None:
            raise ValueError(f"a chunk holds a record of opcode {opcode} at its byte {at}")
        if length > len(data) - at - 9:
            raise ValueError(f"a chunk's record of {length} bytes at its byte {at} runs past its end")
        body = data[at + 9 : at + 9 + length]
        out.append(read(ReadDataStream(io.BytesIO(body)), length))
        at += 9 + length
    return out


def check_schema(schema: Schema) -> None:
    """A protobuf schema whose descriptors do not build (a flipped bit) is damage: ``ValueError``."""
    if schema.encoding != "protobuf":
        return
    from google.protobuf import descriptor_pb2, descriptor_pool
    from google.protobuf.message import DecodeError

    try:
        files = descriptor_pb2.FileDescriptorSet.FromString(schema.data)
        pool = descriptor_pool.DescriptorPool()
        pending = list(files.file)
        while pending:  # each file after the files it depends on
            done = {f.name for f in files.file if f not in pending}
            added = [f for f in pending if all(d in done for d in f.dependency)]
            if not added:
                raise ValueError("it does not carry every file it depends on")
            for f in added:
                pool.Add(f)
            pending = [f for f in pending if f not in added]
        pool.FindMessageTypeByName(schema.name)
    except (DecodeError, TypeError, KeyError, ValueError) as exc:
        raise ValueError(f"the schema {schema.name[:80]!r} is damaged: {str(exc)[:200]}") from None
