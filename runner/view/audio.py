"""The scenario's sounds through Panda3D's audio (OpenAL), started and stopped as the trace records them.

A sound starts at the offset and volume the run gives it (``SoundInterval`` semantics, notes
panda3d-semantics §3 and §8: ``setVolume`` then ``setTime`` then ``play()``, a replay restarts it) and
loops when the run loops it. Without an audio device Panda3D hands out silent sounds, so the window
works the same, quietly.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

__all__ = ["SoundPlayer"]


class SoundPlayer:
    """The sounds of one scenario (name -> WAV file), loaded once through ``base``'s sound-effect manager."""

    def __init__(self, base: Any, files: dict[str, Path]) -> None:
        self.sounds: dict[str, Any] = {}
        if not getattr(base, "sfxManagerList", None):
            return
        from panda3d.core import Filename

        for name, path in files.items():
            sound = base.loader.loadSfx(Filename.fromOsSpecific(str(path)))
            if sound is not None:
                self.sounds[name] = sound

    def play(self, name: str, offset: float, volume: float, loop: bool) -> None:
        sound = self.sounds.get(name)
        if sound is None:
            return
        sound.setVolume(volume)
        sound.setLoop(loop)
        sound.setTime(offset)  # acts at the next play(), which stops it first (a replay restarts)
        sound.play()

    def stop(self, name: str) -> None:
        sound = self.sounds.get(name)
        if sound is not None:
            sound.stop()

    def stop_all(self) -> None:
        for sound in self.sounds.values():
            sound.stop()
