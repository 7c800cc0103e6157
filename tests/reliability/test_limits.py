"""Limits, each with a clear, located message, and checked before anything large is built.

File size (MAX_FILE_BYTES), bodies once arrays are expanded (MAX_BODIES), steps (MAX_STEPS), sound
length (MAX_SOUND_SECONDS) exist; the bytes of a sound file, the timed inputs once repeats are
expanded, and the body pairs of group surfaces are bounded too (each can otherwise make a file of a few
hundred bytes build millions of objects: measured 65 s and 2.2 GB for 100 arrays of 10,000 before the
body limit refused them). Every refusal here must come within a second (0.01-0.04 s measured).
"""

from __future__ import annotations

import re
import struct
import time
import wave
from pathlib import Path

import pytest

from runner.errors import ScenarioValidationError
from runner.language.load import load_scenario
from runner.language.refs import MAX_BODIES, MAX_STEPS
from runner.language.sounds import MAX_SOUND_SECONDS
from runner.language.yaml_source import MAX_FILE_BYTES

HEAD = "schema_version: 1\nscenario: t\nworld: {dt: 0.04, duration: 1}\nbodies:\n"
FAST = 1.0  # seconds: generous for a loaded 2-core machine; the checks take 0.001-0.04 s


def refused(path: Path) -> tuple[list[str], float]:
    start = time.perf_counter()
    with pytest.raises(ScenarioValidationError) as info:
        load_scenario(path, None)
    return [str(i) for i in info.value.issues], time.perf_counter() - start


def located(issues: list[str], path: Path, line: int, pattern: str) -> bool:
    return any(i.startswith(f"{path}:{line}:") and re.search(pattern, i) for i in issues)


def test_file_size(tmp_path: Path) -> None:
    path = tmp_path / "big.yaml"
    filler = "#" + "x" * 99 + "\n"
    path.write_text(HEAD + "  b: {sphere: 1, density: 1}\n" + filler * (MAX_FILE_BYTES // len(filler) + 1))
    assert path.stat().st_size > MAX_FILE_BYTES
    issues, took = refused(path)
    assert took < FAST
    assert any(f"file larger than {MAX_FILE_BYTES} bytes" in i for i in issues), issues
    assert all(re.match(rf"{re.escape(str(path))}:[1-9]\d*:[1-9]\d*:", i) for i in issues), issues


def test_bodies_in_one_array(tmp_path: Path) -> None:
    path = tmp_path / "t.yaml"
    path.write_text(HEAD + f"  b: {{sphere: 0.1, density: 1, array: {{count: {MAX_BODIES + 1}}}}}\n")
    issues, _ = refused(path)
    assert located(issues, path, 5, rf"less than or equal to {MAX_BODIES}"), issues


def test_bodies_over_many_arrays_refused_before_expanding(tmp_path: Path) -> None:
    path = tmp_path / "t.yaml"
    arrays = "".join(f"  a{i}: {{sphere: 0.1, density: 1, array: {{count: 10000}}}}\n" for i in range(20))
    path.write_text(HEAD + arrays)
    issues, took = refused(path)
    assert located(issues, path, 5, rf"at most {MAX_BODIES} bodies \(arrays expanded\), found 200000"), issues
    assert took < FAST, f"{took:.2f} s: the arrays were expanded before the limit was checked"


def test_steps(tmp_path: Path) -> None:
    path = tmp_path / "t.yaml"
    path.write_text(HEAD.replace("duration: 1", "duration: 1e6") + "  b: {sphere: 0.1, density: 1}\n")
    issues, took = refused(path)
    assert located(issues, path, 3, rf"at most {MAX_STEPS} steps \(duration / dt\), found 25000000"), issues
    assert took < FAST


def test_timed_inputs_refused_before_expanding(tmp_path: Path) -> None:
    path = tmp_path / "t.yaml"
    inputs = "".join(f"  - {{at: 0, event: e{i}, repeat: {{every: 1e-5, count: 100000}}}}\n" for i in range(20))
    path.write_text(HEAD + "  b: {sphere: 0.1, density: 1}\ninputs:\n" + inputs)
    issues, took = refused(path)
    assert located(issues, path, 7, r"at most \d+ timed inputs"), issues
    assert took < FAST


def test_group_surfaces_refused_before_expanding(tmp_path: Path) -> None:
    path = tmp_path / "t.yaml"
    path.write_text(
        HEAD
        + "  a: {sphere: 0.1, density: 1, array: {count: 2000}}\n"
        + "  b: {sphere: 0.1, density: 1, pos: [5, 0, 0], array: {count: 2000}}\n"
        + "surfaces:\n  - {bodies: [a, b], mu: 1}\n"
    )  # 4,000,000 pairs from 150 bytes
    issues, took = refused(path)
    assert located(issues, path, 8, r"at most \d+ body pairs"), issues
    assert took < FAST


def sound_file(path: Path, rate: int, channels: int, width: int, data_bytes: int) -> Path:
    """A PCM WAV whose data chunk claims ``data_bytes``; the file is sparse (no disk space used)."""
    header = b"RIFF" + struct.pack("<I", 36 + data_bytes) + b"WAVE"
    header += b"fmt " + struct.pack("<IHHIIHH", 16, 1, channels, rate, rate * channels * width, channels * width,
                                    8 * width)  # fmt: skip
    header += b"data" + struct.pack("<I", data_bytes)
    with open(path, "wb") as f:
        f.write(header)
        f.truncate(len(header) + data_bytes)
    return path


def sound_scenario(folder: Path) -> Path:
    path = folder / "t.yaml"
    path.write_text(HEAD + "  b: {sphere: 0.1, density: 1}\nsounds:\n  bang: long.wav\n")
    return path


def test_sound_length(tmp_path: Path) -> None:
    with wave.open(str(tmp_path / "long.wav"), "wb") as w:  # 601 one-byte frames at 1 Hz: 601 s, 645 bytes
        w.setnchannels(1)
        w.setsampwidth(1)
        w.setframerate(1)
        w.writeframes(b"\x80" * int(MAX_SOUND_SECONDS + 1))
    path = sound_scenario(tmp_path)
    issues, _ = refused(path)
    assert located(issues, path, 7, rf"longer than {MAX_SOUND_SECONDS:.0f} s \(601\.0 s\)"), issues


def test_sound_bytes(tmp_path: Path) -> None:
    """33 s of 8-channel 32-bit 192 kHz audio: short enough, but 200 MB, attached to every trace."""
    sound_file(tmp_path / "long.wav", 192_000, 8, 4, 200_000_000)
    path = sound_scenario(tmp_path)
    issues, took = refused(path)
    assert located(issues, path, 7, r"larger than \d+ bytes"), issues
    assert took < FAST
