"""A minimal GIF decoder for the tests: frames as full palette-index images (disposal "keep" only)."""

from __future__ import annotations

import struct

import numpy as np


def _lzw_decode(data: bytes, min_size: int, count: int) -> list[int]:
    clear, eoi = 1 << min_size, (1 << min_size) + 1
    pos = 0
    size = min_size + 1
    table: list[list[int]] = []
    out: list[int] = []
    prev: list[int] | None = None

    def reset() -> list[list[int]]:
        return [[i] for i in range(clear)] + [[], []]

    table = reset()
    total_bits = len(data) * 8
    while pos + size <= total_bits:
        code = 0
        for k in range(size):
            bit = (data[(pos + k) >> 3] >> ((pos + k) & 7)) & 1
            code |= bit << k
        pos += size
        if code == clear:
            table, size, prev = reset(), min_size + 1, None
            continue
        if code == eoi:
            break
        if prev is None:
            entry = table[code]
        elif code < len(table):
            entry = table[code]
            table.append(prev + [entry[0]])
        elif code == len(table):
            entry = prev + [prev[0]]
            table.append(entry)
        else:
            raise ValueError(f"bad LZW code {code} (table {len(table)})")
        out += entry
        prev = entry
        if len(table) == (1 << size) and size < 12:
            size += 1
    if len(out) < count:
        raise ValueError(f"LZW data holds {len(out)} pixels, expected {count}")
    return out[:count]


def decode_gif(data: bytes) -> tuple[list[np.ndarray], list[int], list[tuple[int, int, int]]]:
    """(frames, delays in 1/100 s, global palette) of an animated GIF written by reports.gif."""
    if data[:6] != b"GIF89a":
        raise ValueError("not a GIF89a file")
    w, h, flags, _, _ = struct.unpack("<HHBBB", data[6:13])
    n = 2 ** ((flags & 7) + 1)
    palette = [tuple(data[13 + 3 * i : 16 + 3 * i]) for i in range(n)]
    pos = 13 + 3 * n
    canvas = np.zeros((h, w), dtype=np.uint8)
    frames, delays = [], []
    delay, transparent = 0, None
    while pos < len(data):
        block = data[pos]
        if block == 0x3B:
            break
        if block == 0x21:
            label = data[pos + 1]
            pos += 2
            if label == 0xF9:
                packed, delay, tindex = struct.unpack("<BHB", data[pos + 1 : pos + 5])
                transparent = tindex if packed & 1 else None
            while data[pos] != 0:
                pos += data[pos] + 1
            pos += 1
            continue
        if block != 0x2C:
            raise ValueError(f"unexpected block 0x{block:02x} at {pos}")
        left, top, iw, ih, _ = struct.unpack("<HHHHB", data[pos + 1 : pos + 10])
        min_size = data[pos + 10]
        pos += 11
        chunks = bytearray()
        while data[pos] != 0:
            chunks += data[pos + 1 : pos + 1 + data[pos]]
            pos += data[pos] + 1
        pos += 1
        pixels = np.array(_lzw_decode(bytes(chunks), min_size, iw * ih), dtype=np.uint8).reshape(ih, iw)
        region = canvas[top : top + ih, left : left + iw]
        if transparent is None:
            region[:] = pixels
        else:
            region[pixels != transparent] = pixels[pixels != transparent]
        frames.append(canvas.copy())
        delays.append(delay)
        transparent = None
    return frames, delays, palette  # type: ignore[return-value]
