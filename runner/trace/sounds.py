"""The scenario's sounds as audio samples, for /audio (``foxglove.RawAudio``).

The writer gets each sound file as an attachment (``sounds/<name>.wav``); a ``start`` on /sounds then
writes, at its time, the sound from its offset to its end with its volume applied, as 16-bit PCM. A
``stop`` does not cut what was written (the Sound record on /sounds says when it stopped).
"""

from __future__ import annotations

import io

import numpy as np

__all__ = ["SoundBank"]

_PREFIX, _SUFFIX = "sounds/", ".wav"


class SoundBank:
    """16-bit PCM of the attached sounds, by name."""

    def __init__(self) -> None:
        self._pcm: dict[str, tuple[np.ndarray, int]] = {}

    def add(self, attachment: str, data: bytes) -> None:
        """Keep ``data`` if ``attachment`` is a sound file this format plays (16-bit PCM WAV); else ignore it."""
        if not (attachment.startswith(_PREFIX) and attachment.endswith(_SUFFIX)):
            return
        import wave  # here: only a scenario with sounds has one

        try:
            with wave.open(io.BytesIO(data), "rb") as w:
                if w.getsampwidth() != 2 or w.getcomptype() != "NONE":
                    return
                frames = np.frombuffer(w.readframes(w.getnframes()), dtype="<i2")
                self._pcm[attachment[len(_PREFIX) : -len(_SUFFIX)]] = (
                    frames.reshape(-1, w.getnchannels()), w.getframerate()
                )
        except (wave.Error, EOFError, ValueError):
            return

    def clip(self, name: str, offset: float, volume: float) -> tuple[np.ndarray, int] | None:
        """(frames, sample rate) of ``name`` from ``offset`` seconds at ``volume``; None if unknown or empty."""
        found = self._pcm.get(name)
        if found is None:
            return None
        pcm, rate = found
        start = max(0, round(offset * rate))
        part = pcm[start:]
        if not len(part):
            return None
        if volume != 1.0:
            part = np.clip(np.rint(part * float(volume)), -32768, 32767).astype("<i2")
        return part, rate
