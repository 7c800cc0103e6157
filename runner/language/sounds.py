"""Sound files: WAV only, read with the standard library (length, format, samples)."""

from __future__ import annotations

import stat
import struct
from dataclasses import dataclass
from pathlib import Path

from runner.language.files import special_file_kind

MAX_SOUND_SECONDS = 600.0
MAX_SOUND_BYTES = 50_000_000  # every sound is attached to every trace


@dataclass(frozen=True)
class SoundInfo:
    """A sound file's format and length, as its header gives them."""

    path: Path
    length: float  # seconds
    sample_rate: int
    channels: int
    sample_width: int  # bytes


class SoundFileError(ValueError):
    """Not a readable WAV file (the message says why)."""


def read_info(path: Path) -> SoundInfo:
    import wave  # here: only a scenario with sounds reads one

    try:
        status = path.stat()
    except FileNotFoundError:
        raise SoundFileError("file not found") from None
    except (OSError, ValueError) as exc:
        raise SoundFileError(f"not a WAV file ({exc})") from None
    if not stat.S_ISREG(status.st_mode):  # never opened: reading a FIFO or a device could block forever
        raise SoundFileError(f"expected a regular file, found {special_file_kind(status.st_mode)}")
    size = status.st_size
    if size > MAX_SOUND_BYTES:
        raise SoundFileError(f"larger than {MAX_SOUND_BYTES} bytes ({size} bytes)")
    try:
        with wave.open(str(path), "rb") as w:
            frames, rate = w.getnframes(), w.getframerate()
            info = SoundInfo(path, frames / rate if rate else 0.0, rate, w.getnchannels(), w.getsampwidth())
    except FileNotFoundError:
        raise SoundFileError("file not found") from None
    except (wave.Error, EOFError, OSError, RuntimeError, ValueError, OverflowError, struct.error) as exc:
        # the standard library's chunk reader raises a bare RuntimeError on a chunk size past the file's end
        raise SoundFileError(f"not a WAV file ({exc or type(exc).__name__})") from None
    if info.sample_rate <= 0 or info.channels <= 0 or info.sample_width <= 0:  # compare divides by the rate
        raise SoundFileError(
            f"a sample rate of {info.sample_rate} Hz, {info.channels} channels of {info.sample_width} bytes: "
            "expected at least 1 of each"
        )
    if info.length > MAX_SOUND_SECONDS:
        raise SoundFileError(f"longer than {MAX_SOUND_SECONDS:.0f} s ({info.length:.1f} s)")
    return info
