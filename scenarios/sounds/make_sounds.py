"""Generate the lab's two sounds, deterministically: a short thud and a door slam (16-bit mono WAV).

Run: python scenarios/sounds/make_sounds.py  (writes thud.wav and close.wav beside this file).
"""

from __future__ import annotations

import math
import struct
import wave
from pathlib import Path

RATE = 22050


def _write(path: Path, samples: list[float]) -> None:
    peak = max(abs(s) for s in samples) or 1.0
    frames = b"".join(struct.pack("<h", int(round(32000 * s / peak))) for s in samples)
    with wave.open(str(path), "wb") as w:
        w.setnchannels(1)
        w.setsampwidth(2)
        w.setframerate(RATE)
        w.writeframes(frames)


def _noise(n: int, seed: int) -> list[float]:
    """A fixed pseudo-random sequence (a linear congruential generator: same bytes everywhere)."""
    out, state = [], seed
    for _ in range(n):
        state = (1103515245 * state + 12345) % 2**31
        out.append(state / 2**30 - 1.0)
    return out


def thud(seconds: float = 0.35) -> list[float]:
    n = int(seconds * RATE)
    noise = _noise(n, 7)
    out = []
    for i in range(n):
        t = i / RATE
        body = math.sin(2 * math.pi * (70 + 60 * math.exp(-t * 30)) * t) * math.exp(-t * 14)
        out.append(body + 0.25 * noise[i] * math.exp(-t * 60))
    return out


def close(seconds: float = 0.6) -> list[float]:
    n = int(seconds * RATE)
    noise = _noise(n, 11)
    out = []
    for i in range(n):
        t = i / RATE
        slam = 0.6 * noise[i] * math.exp(-t * 25)
        ring = math.sin(2 * math.pi * 180 * t) * math.exp(-t * 6) + 0.4 * math.sin(2 * math.pi * 410 * t) * math.exp(
            -t * 9
        )
        out.append(slam + 0.5 * ring)
    return out


if __name__ == "__main__":
    here = Path(__file__).resolve().parent
    _write(here / "thud.wav", thud())
    _write(here / "close.wav", close())
    print(f"wrote {here / 'thud.wav'} and {here / 'close.wav'}")
