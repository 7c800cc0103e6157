"""An MCAP file whose compressed chunk is damaged, where the tool reads MCAP with mcap's own readers: deciding
whether an output file is its own (a re-run into a folder), publishing a trace made elsewhere, and reading a
trace's scene for its pictures.

Found by this suite: mcap's readers inflate a chunk with zstandard or lz4, whose errors on damaged data are
their own (zstandard's ``ZstdError``, lz4's ``RuntimeError``), not mcap's; a re-run into a folder holding a
Foxglove SDK recording whose first chunk was damaged ended with a ZstdError traceback (exit 1) instead of the
refusal of a file this tool did not write (exit 2).
"""

from __future__ import annotations

import struct
import subprocess
import sys
from pathlib import Path

import pytest

from reports import trace_format as tf
from reports.scene3d.scene_channel import read_scene_updates
from runner.trace.output import is_own, publish_trace

MAGIC = b"\x89MCAP0\r\n"
#: bytes that no decompressor inflates: a zstd frame's magic number followed by garbage, or garbage alone
DAMAGED = {"zstd": b"\x28\xb5\x2f\xfd" + b"garbage " * 8, "lz4": b"garbage " * 8}

SOURCE = """\
schema_version: 1
scenario: fall
world: {gravity: [0, 0, -9.81], dt: 0.01, duration: 0.1}
bodies:
  ball: {sphere: 0.1, density: 1000, pos: [0, 0, 2]}
assertions:
  - {name: falls, at: end, value: ball.vel.z, near: -g*0.1, tol: 1e-9}
"""


def _string(text: str) -> bytes:
    data = text.encode()
    return struct.pack("<I", len(data)) + data


def _record(opcode: int, body: bytes) -> bytes:
    return bytes([opcode]) + struct.pack("<Q", len(body)) + body


def damaged_recording(compression: str) -> bytes:
    """The MCAP magic, a header as the Foxglove SDK writes it, then a chunk (opcode 6) whose data do not inflate:
    start and end times, its declared size and CRC, its compression, its data (the MCAP specification's order)."""
    header = _record(0x01, _string("") + _string(tf.SDK_LIBRARY + "-python/v0.1"))
    data = DAMAGED[compression]
    fields = struct.pack("<QQQI", 0, 0, 100, 0) + _string(compression) + struct.pack("<Q", len(data)) + data
    chunk = _record(0x06, fields)
    return MAGIC + header + chunk


@pytest.mark.parametrize("compression", sorted(DAMAGED))
def test_mcaps_readers_raise_the_decompressors_own_errors(tmp_path: Path, compression: str) -> None:
    """The premise: without the fix these errors reached the user as tracebacks."""
    from mcap.exceptions import McapError
    from mcap.stream_reader import StreamReader

    (tmp_path / "x.mcap").write_bytes(damaged_recording(compression))
    with open(tmp_path / "x.mcap", "rb") as f, pytest.raises(Exception) as raised:
        list(StreamReader(f).records)
    assert not isinstance(raised.value, McapError | ValueError | EOFError | struct.error)


@pytest.mark.parametrize("compression", sorted(DAMAGED))
def test_a_damaged_recording_is_not_the_tools_own(tmp_path: Path, compression: str) -> None:
    trace = tmp_path / "fall__base__fake.mcap"
    trace.write_bytes(damaged_recording(compression))
    assert not is_own(trace, trace)
    partial = tmp_path / ("fall__base__fake.mcap" + tf.PARTIAL_SUFFIX)
    partial.write_bytes(damaged_recording(compression))
    assert is_own(partial, trace), "a .partial with this tool's writer's header is what a killed run left"


@pytest.mark.parametrize("compression", sorted(DAMAGED))
def test_a_rerun_over_a_damaged_recording_refuses_it(tmp_path: Path, compression: str) -> None:
    (tmp_path / "fall.yaml").write_text(SOURCE)
    out = tmp_path / "out"
    out.mkdir()
    recording = damaged_recording(compression)
    (out / "fall__base__fake.mcap").write_bytes(recording)
    done = subprocess.run([sys.executable, "-m", "runner", "run", "fall.yaml", "--backend", "fake", "--out", "out"],
                          capture_output=True, text=True, cwd=tmp_path, timeout=120)  # fmt: skip
    assert done.returncode == 2 and "Traceback" not in done.stderr, done.stderr
    assert "out/fall__base__fake.mcap was not written by scenario" in done.stderr
    assert (out / "fall__base__fake.mcap").read_bytes() == recording


@pytest.mark.parametrize("compression", sorted(DAMAGED))
def test_publishing_a_damaged_trace_writes_its_bytes(tmp_path: Path, compression: str) -> None:
    """A trace made elsewhere (a Ray worker) is published whatever it holds: its whole records first."""
    data = damaged_recording(compression)
    publish_trace(tmp_path / "x.mcap", data)
    assert (tmp_path / "x.mcap").read_bytes() == data


@pytest.mark.parametrize("compression", sorted(DAMAGED))
def test_a_damaged_chunk_ends_the_scene_read(tmp_path: Path, compression: str) -> None:
    (tmp_path / "x.mcap").write_bytes(damaged_recording(compression))
    assert read_scene_updates(tmp_path / "x.mcap") == []
