"""A small animated-GIF encoder (GIF89a, LZW), written here so the reports need no imaging library.

Frames are 2-D arrays of palette indices. After the first frame only the rectangle that changed is
stored, with unchanged pixels transparent (disposal "do not dispose"), and identical frames are merged
by lengthening the previous frame's delay, so an animation where little moves stays small. LZW follows
the GIF spec (variable code width from min_code_size + 1 up to 12 bits, a clear code when the table is
full); the output is deterministic.
"""

from __future__ import annotations

import struct
from collections.abc import Sequence

import numpy as np

__all__ = ["encode_gif", "lzw_encode"]


def lzw_encode(data: bytes, min_code_size: int) -> bytes:
    """GIF-flavoured LZW of ``data`` (each byte < 2**min_code_size), packed LSB first."""
    clear, eoi = 1 << min_code_size, (1 << min_code_size) + 1
    out = bytearray()
    size = min_code_size + 1
    acc, nbits = clear, size  # the stream starts with a clear code
    if not data:
        acc |= eoi << nbits
        nbits += size
        while nbits > 0:
            out.append(acc & 0xFF)
            acc >>= 8
            nbits -= 8
        return bytes(out)
    table: dict[int, int] = {}
    get = table.get
    nxt = eoi + 1
    limit = 1 << size
    prefix = data[0]
    for byte in data[1:]:
        key = (prefix << 8) | byte
        code = get(key)
        if code is not None:
            prefix = code
            continue
        acc |= prefix << nbits  # emit the prefix (written out inline: this loop runs once per pixel)
        nbits += size
        if nbits >= 16:
            out += (acc & 0xFFFF).to_bytes(2, "little")
            acc >>= 16
            nbits -= 16
        table[key] = nxt
        if nxt == limit and size < 12:
            size += 1
            limit <<= 1
        nxt += 1
        if nxt == 4096:
            acc |= clear << nbits
            nbits += size
            table.clear()
            nxt, size = eoi + 1, min_code_size + 1
            limit = 1 << size
        prefix = byte
    for code in (prefix, eoi):
        acc |= code << nbits
        nbits += size
    while nbits > 0:
        out.append(acc & 0xFF)
        acc >>= 8
        nbits -= 8
    return bytes(out)


def _blocks(data: bytes) -> bytes:
    parts = [bytes([len(data[i : i + 255])]) + data[i : i + 255] for i in range(0, len(data), 255)]
    return b"".join(parts) + b"\x00"


def _image(pixels: np.ndarray, left: int, top: int, delay: int, transparent: int | None, bits: int) -> bytes:
    h, w = pixels.shape
    flags = (1 << 2) | (1 if transparent is not None else 0)  # disposal 1: keep; transparency flag
    gce = b"\x21\xf9\x04" + struct.pack("<BHB", flags, delay, transparent or 0) + b"\x00"
    desc = b"\x2c" + struct.pack("<HHHHB", left, top, w, h, 0)
    min_size = max(2, bits)
    return gce + desc + bytes([min_size]) + _blocks(lzw_encode(pixels.astype(np.uint8).tobytes(), min_size))


def encode_gif(frames: Sequence[np.ndarray], palette: Sequence[tuple[int, int, int]], delay_cs: int,
               loop: bool = True) -> bytes:  # fmt: skip
    """An animated GIF of ``frames`` (H x W palette indices), ``delay_cs`` hundredths of a second each.

    ``palette`` holds at most 255 colours: one index is kept free for transparency.
    """
    if not frames:
        raise ValueError("an animation needs at least one frame")
    if not 1 <= len(palette) <= 255:
        raise ValueError(f"a palette of 1 to 255 colours is needed, got {len(palette)}")
    h, w = frames[0].shape
    if any(f.shape != (h, w) for f in frames):
        raise ValueError("every frame must have the same size")
    bits = max(1, int(np.ceil(np.log2(len(palette) + 1))))
    transparent = len(palette)
    table = list(palette) + [(0, 0, 0)] * ((1 << bits) - len(palette))
    out = bytearray(b"GIF89a")
    out += struct.pack("<HHBBB", w, h, 0x80 | 0x70 | (bits - 1), 0, 0)
    out += b"".join(struct.pack("BBB", *c) for c in table)
    if loop:
        out += b"\x21\xff\x0bNETSCAPE2.0\x03\x01\x00\x00\x00"
    images: list[list[object]] = [[frames[0], 0, 0, delay_cs, None]]
    previous = frames[0]
    for frame in frames[1:]:
        changed = frame != previous
        if not changed.any():
            images[-1][3] = int(images[-1][3]) + delay_cs  # type: ignore[call-overload]
            continue
        rows, cols = np.flatnonzero(changed.any(axis=1)), np.flatnonzero(changed.any(axis=0))
        r0, r1, c0, c1 = rows[0], rows[-1] + 1, cols[0], cols[-1] + 1
        patch = frame[r0:r1, c0:c1].copy()
        patch[~changed[r0:r1, c0:c1]] = transparent
        images.append([patch, int(c0), int(r0), delay_cs, transparent])
        previous = frame
    for pixels, left, top, delay, transp in images:
        out += _image(pixels, left, top, min(int(delay), 65535), transp, bits)  # type: ignore[arg-type,call-overload]
    out += b"\x3b"
    return bytes(out)
