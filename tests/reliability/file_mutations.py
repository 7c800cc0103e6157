"""Hostile input files other than scenarios, for tests/reliability/test_fuzz_files.py (hypothesis strategies).

* model files (URDF, MJCF): a small valid model (the repository's and pybullet_data's, no meshes) with 1-4
  mutations: a number made NaN, inf, huge, negative or zero; a name given to another element; an element
  dropped or duplicated; an attribute's value garbled or removed; the text cut;
* WAV files: a valid PCM file with header fields rewritten (rate 0, channels 0, width 0 or 3, huge sizes)
  or cut;
* golden files: a recording's text with a token made NaN, inf, huge, negative, a superscript or text, a
  token or line dropped or duplicated, the text cut or bits flipped;
* traces: an MCAP trace with bits flipped, cut, a byte range overwritten, a record's length made huge, or
  a crafted chunk inserted after the header (a zstd bomb declaring a small size, a huge declared size).
"""

from __future__ import annotations

import re
import struct
import zlib
from dataclasses import dataclass
from functools import cache

from hypothesis import strategies as st

NUMBERS = ["nan", "NaN", "inf", "-inf", "1e308", "1e999", "-1e308", "-1", "0", "-0", "1e-320", "9" * 400, "0x10",
           "1,2", "", " ", "\N{SUPERSCRIPT TWO}", "1e", "--1"]  # fmt: skip
_NUMBER = re.compile(r"-?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?")
_ATTRIBUTE = re.compile(r'(\w+)="([^"]*)"')
_ELEMENT = re.compile(r"<(\w+)\b[^<>]*/>|<(\w+)\b[^<>]*>.*?</\2>", re.S)
_NAME = re.compile(r'\bname="([^"]*)"')


@dataclass(frozen=True)
class Mutated:
    data: bytes
    how: str


def _pick(draw: st.DrawFn, items: list[re.Match[str]]) -> re.Match[str] | None:
    return items[draw(st.integers(0, len(items) - 1))] if items else None


@st.composite
def model_text(draw: st.DrawFn, seed: str) -> Mutated:
    """A model file (URDF or MJCF text) with 1-4 mutations."""
    text, how = seed, []
    for _ in range(draw(st.integers(1, 4))):
        kind = draw(st.sampled_from(["number", "number", "name", "drop", "duplicate", "garble", "unquote", "cut"]))
        if kind == "number":
            m = _pick(draw, [m for a in _ATTRIBUTE.finditer(text) for m in _NUMBER.finditer(a.group(2))
                             if a.group(1) not in ("name",)])  # fmt: skip
            if m is not None:
                new = draw(st.sampled_from(NUMBERS))
                text = text[: m.start()] + new + text[m.end() :]
                how.append(f"number {m.group()!r} -> {new!r}")
        elif kind == "name":
            names = list(_NAME.finditer(text))
            if len(names) > 1:
                a, b = draw(st.sampled_from(names)), draw(st.sampled_from(names))
                text = text[: a.start(1)] + b.group(1) + text[a.end(1) :]
                how.append(f"name {a.group(1)!r} -> {b.group(1)!r}")
        elif kind in ("drop", "duplicate"):
            m = _pick(draw, list(_ELEMENT.finditer(text)))
            if m is not None:
                new = "" if kind == "drop" else m.group() * 2
                text = text[: m.start()] + new + text[m.end() :]
                how.append(f"{kind} <{m.group(1) or m.group(2)}>")
        elif kind == "garble":
            m = _pick(draw, list(_ATTRIBUTE.finditer(text)))
            if m is not None:
                new = draw(st.sampled_from(["", "&amp;", "<", "1 2", "a b c d e f", "\x00", "é" * 50, "$(x)"]))
                text = text[: m.start(2)] + new.replace("<", "&lt;") + text[m.end(2) :]
                how.append(f"garble {m.group(1)}")
        elif kind == "unquote":
            m = _pick(draw, list(_ATTRIBUTE.finditer(text)))
            if m is not None:
                text = text[: m.start()] + text[m.end() :]
                how.append(f"remove {m.group(1)}")
        else:
            at = draw(st.integers(0, len(text)))
            text = text[:at]
            how.append(f"cut at {at}")
    return Mutated(text.encode("utf-8", "surrogatepass"), "; ".join(how) or "unchanged")


def wav_bytes(rate: int = 8000, channels: int = 1, width: int = 2, frames: int = 400) -> bytes:
    """A valid PCM WAV file (a ramp)."""
    data = bytes((i * 7) & 0xFF for i in range(frames * channels * width))
    fmt = struct.pack("<HHIIHH", 1, channels, rate, rate * channels * width, channels * width, 8 * width)
    body = b"WAVE" + b"fmt " + struct.pack("<I", len(fmt)) + fmt + b"data" + struct.pack("<I", len(data)) + data
    return b"RIFF" + struct.pack("<I", len(body)) + body


#: (offset, struct format, field) of a canonical 44-byte header
WAV_FIELDS = [(4, "<I", "riff size"), (20, "<H", "format"), (22, "<H", "channels"), (24, "<I", "rate"),
              (28, "<I", "byte rate"), (32, "<H", "block align"), (34, "<H", "bits"), (16, "<I", "fmt size"),
              (40, "<I", "data size")]  # fmt: skip


@st.composite
def wav(draw: st.DrawFn) -> Mutated:
    data = bytearray(wav_bytes(draw(st.sampled_from([8000, 44100])), draw(st.integers(1, 2)),
                               draw(st.sampled_from([1, 2, 4]))))  # fmt: skip
    how = []
    for _ in range(draw(st.integers(1, 3))):
        kind = draw(st.sampled_from(["field", "field", "field", "cut", "flip"]))
        if kind == "field":
            offset, fmt, name = draw(st.sampled_from(WAV_FIELDS))
            top = 2 ** (8 * struct.calcsize(fmt)) - 1
            value = draw(st.sampled_from([0, 1, 3, 5, 7, top, top // 2, 2**15, 192000, 10**6]))
            if offset + struct.calcsize(fmt) <= len(data):  # not past a cut
                struct.pack_into(fmt, data, offset, min(value, top))
                how.append(f"{name} = {min(value, top)}")
        elif kind == "cut":
            at = draw(st.integers(0, len(data)))
            del data[at:]
            how.append(f"cut at {at}")
        elif data:
            at = draw(st.integers(0, len(data) - 1))
            data[at] ^= 1 << draw(st.integers(0, 7))
            how.append(f"flip a bit at {at}")
    return Mutated(bytes(data), "; ".join(how))


@st.composite
def golden_text(draw: st.DrawFn, seed: str) -> Mutated:
    lines, how = seed.splitlines(), []
    for _ in range(draw(st.integers(1, 4))):
        kind = draw(st.sampled_from(["token", "token", "token", "drop token", "duplicate token", "drop line",
                                     "duplicate line", "cut", "flip"]))  # fmt: skip
        if not lines:
            break
        i = draw(st.integers(0, len(lines) - 1))
        tokens = lines[i].split(" ")
        j = draw(st.integers(0, len(tokens) - 1))
        if kind == "token":
            tokens[j] = draw(st.sampled_from([*NUMBERS, "atol=nan", "rtol=-1", "atol=inf", "[" * 5000, "\"x",
                                              "1e300", "-5"]))  # fmt: skip
        elif kind == "drop token":
            del tokens[j]
        elif kind == "duplicate token":
            tokens.insert(j, tokens[j])
        elif kind == "drop line":
            del lines[i]
            how.append(f"drop line {i + 1}")
            continue
        elif kind == "duplicate line":
            lines.insert(i, lines[i])
            how.append(f"duplicate line {i + 1}")
            continue
        elif kind == "cut":
            lines = lines[:i] + [lines[i][: draw(st.integers(0, len(lines[i])))]]
            how.append(f"cut in line {i + 1}")
            continue
        else:
            raw = bytearray(lines[i].encode())
            if raw:
                raw[draw(st.integers(0, len(raw) - 1))] ^= 1 << draw(st.integers(0, 7))
            lines[i] = raw.decode("utf-8", "replace")
            how.append(f"flip a bit in line {i + 1}")
            continue
        lines[i] = " ".join(tokens)
        how.append(f"{kind} {j} in line {i + 1}: {lines[i][:60]}")
    return Mutated(("\n".join(lines) + "\n").encode(), "; ".join(how))


def _record(opcode: int, body: bytes) -> bytes:
    return bytes([opcode]) + struct.pack("<Q", len(body)) + body


def _string(text: str) -> bytes:
    return struct.pack("<I", len(text)) + text.encode()


@cache
def _bomb() -> bytes:
    """zstd frames that inflate to 1 GiB of zeros (about 40 KB compressed)."""
    import zstandard

    return zstandard.ZstdCompressor(level=1).compress(bytes(64 * 1024 * 1024)) * 16


def chunk(declared: int, payload: bytes, compression: str = "zstd") -> bytes:
    """An MCAP chunk record declaring ``declared`` uncompressed bytes around ``payload``."""
    body = struct.pack("<QQQI", 0, 0, declared, zlib.crc32(b"")) + _string(compression)
    return _record(0x06, body + struct.pack("<Q", len(payload)) + payload)


def _header_end(data: bytes) -> int:
    return 8 + 9 + struct.unpack_from("<Q", data, 9)[0] if len(data) >= 17 else len(data)


@st.composite
def trace_bytes(draw: st.DrawFn, seed: bytes) -> Mutated:
    data, how = bytearray(seed), []
    for _ in range(draw(st.integers(1, 3))):
        kind = draw(st.sampled_from(["flip", "flip", "cut", "overwrite", "length", "bomb", "huge chunk",
                                     "chunk garbage"]))  # fmt: skip
        if not data:
            break
        at = draw(st.integers(0, len(data) - 1))
        if kind == "flip":
            for _ in range(draw(st.integers(1, 8))):
                spot = draw(st.integers(0, len(data) - 1))
                data[spot] ^= 1 << draw(st.integers(0, 7))
            how.append("flip bits")
        elif kind == "cut":
            del data[at:]
            how.append(f"cut at {at}")
        elif kind == "overwrite":
            size = draw(st.integers(1, 64))
            data[at : at + size] = draw(st.binary(min_size=size, max_size=size))
            how.append(f"overwrite {size} bytes at {at}")
        elif kind == "length":
            value = draw(st.sampled_from([2**63, 2**64 - 1, 2**40, 2**31, 0]))
            data[at + 1 : at + 9] = struct.pack("<Q", value)
            how.append(f"a length of {value} at {at + 1}")
        else:
            if kind == "bomb":
                piece = chunk(draw(st.sampled_from([100, 4096, 2**20])), _bomb())
            elif kind == "huge chunk":
                piece = chunk(draw(st.sampled_from([2**62, 2**40, 300 * 2**20])), b"\x00" * 64)
            else:
                piece = chunk(64, draw(st.binary(min_size=0, max_size=64)), draw(st.sampled_from(["zstd", "lz4", ""])))
            end = _header_end(bytes(data))
            data[end:end] = piece
            how.append(f"{kind} after the header")
    return Mutated(bytes(data), "; ".join(how))
