"""A run's audio track: the scenario's sounds (attached to the trace) mixed at their trigger times.

Each ``start`` record on /sounds plays the attached ``sounds/<name>.wav`` from ``offset`` seconds at
``volume``, until the sound ends, a ``stop`` record for it, or the next start of the same sound. The
mix is mono 16-bit PCM at the highest rate among the sounds used (at most 44.1 kHz; other sounds are
resampled linearly), as long as the run plus the tail of the last sound, scaled down only if it would
clip. Pure numpy and the standard library's ``wave``; the same trace gives the same bytes.
"""

from __future__ import annotations

import io
import struct
import wave
from collections.abc import Sequence

import numpy as np

from reports.trace_reader import SoundRecord, Trace

__all__ = ["decode_wav", "encode_wav", "mix_sounds", "trace_audio"]

MAX_RATE = 44100
MAX_SECONDS = 600.0


def decode_wav(data: bytes) -> tuple[np.ndarray, int]:
    """(mono samples in [-1, 1], rate) of a PCM WAV file; ``ValueError`` if it is not one."""
    try:
        with wave.open(io.BytesIO(data), "rb") as w:
            channels, width, rate, n = w.getnchannels(), w.getsampwidth(), w.getframerate(), w.getnframes()
            raw = w.readframes(n)
    except (wave.Error, EOFError, RuntimeError, ValueError, OverflowError, struct.error) as exc:
        raise ValueError(f"not a PCM WAV file: {exc or type(exc).__name__}") from exc
    if rate <= 0 or channels <= 0:  # a crafted attachment: mixing divides by the rate
        raise ValueError(f"not a PCM WAV file: a sample rate of {rate} Hz, {channels} channels")
    if width == 1:
        samples = (np.frombuffer(raw, dtype=np.uint8).astype(float) - 128.0) / 128.0
    elif width == 2:
        samples = np.frombuffer(raw, dtype="<i2").astype(float) / 32768.0
    elif width == 4:
        samples = np.frombuffer(raw, dtype="<i4").astype(float) / 2147483648.0
    else:
        raise ValueError(f"unsupported WAV sample width {width} bytes")
    if channels > 1:
        samples = samples[: len(samples) - len(samples) % channels].reshape(-1, channels).mean(axis=1)
    return samples, rate


def encode_wav(samples: np.ndarray, rate: int) -> bytes:
    """Mono 16-bit PCM WAV of ``samples`` in [-1, 1]."""
    pcm = np.clip(np.rint(samples * 32767.0), -32768, 32767).astype("<i2")
    buffer = io.BytesIO()
    with wave.open(buffer, "wb") as w:
        w.setnchannels(1)
        w.setsampwidth(2)
        w.setframerate(rate)
        w.writeframes(pcm.tobytes())
    return buffer.getvalue()


def _resample(samples: np.ndarray, rate: int, target: int) -> np.ndarray:
    if rate == target or samples.size == 0:
        return samples
    n = int(round(samples.size * target / rate))
    return np.interp(np.arange(n) * (rate / target), np.arange(samples.size), samples)


def mix_sounds(records: Sequence[SoundRecord], sounds: dict[str, tuple[np.ndarray, int]], end_time: float
               ) -> tuple[np.ndarray, int] | None:  # fmt: skip
    """The mix of ``records`` over ``sounds`` (name -> (samples, rate)); None if nothing plays."""
    starts = [r for r in records if r.action == "start" and r.name in sounds]
    if not starts:
        return None
    rate = min(MAX_RATE, max(sounds[r.name][1] for r in starts))
    clips = {name: _resample(s, r, rate) for name, (s, r) in sounds.items()}
    plays: list[tuple[float, str, float, float, float]] = []  # start, name, offset, volume, stop
    for i, r in enumerate(records):
        if r.action != "start" or r.name not in clips:
            continue
        stop = next((q.t for q in records[i + 1 :] if q.name == r.name and q.t >= r.t), float("inf"))
        plays.append((r.t, r.name, r.offset, r.volume, stop))
    length = max([end_time] + [t + max(clips[n].size / rate - off, 0.0) for t, n, off, _, _ in plays])
    total = int(round(min(length, end_time + 5.0, MAX_SECONDS) * rate))
    out = np.zeros(total)
    for t, name, offset, volume, stop in plays:
        clip = clips[name][max(int(round(offset * rate)), 0) :]
        at = int(round(t * rate))
        n = min(clip.size, total - at, int(round((stop - t) * rate)) if np.isfinite(stop) else clip.size)
        if n > 0 and at >= 0:
            out[at : at + n] += volume * clip[:n]
    peak = float(np.max(np.abs(out))) if out.size else 0.0
    if peak > 1.0:
        out /= peak
    return out, rate


def trace_audio(trace: Trace) -> bytes | None:
    """The WAV mix of ``trace``'s sounds, or None when it plays none."""
    sounds: dict[str, tuple[np.ndarray, int]] = {}
    for a in trace.attachments:
        if a.name.startswith("sounds/") and a.name.endswith(".wav"):
            try:
                sounds[a.name[len("sounds/") : -len(".wav")]] = decode_wav(a.data)
            except ValueError:
                continue
    end = float(trace.times[-1]) if trace.times.size else 0.0
    mixed = mix_sounds(trace.sounds, sounds, end)
    return None if mixed is None else encode_wav(*mixed)
