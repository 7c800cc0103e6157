"""Damaged and crafted traces (issue 31): a damaged chunk is skipped and the rest recovered; anything that
is not a physics-scenarios trace is refused as such (exit 2 in the commands), never a crash; the work is
bounded before it is done (a chunk's uncompressed size, the names a trace lists).

Found by an outside probe: one flipped bit inside a zstd chunk made `inspect --recover` exit 70 instead of
recovering the chunks before it; deeply nested JSON, a superscript in `trace_format`, a bad summary or a
garbage schema made `inspect`, `report` and `view` exit 70; a 130 KB chunk declaring 2 GB was inflated
whole; a 3.2 MB trace naming 300,000 bodies took 13.5 GB in `inspect`."""

from __future__ import annotations

import struct
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from mcap.reader import make_reader
from mcap.writer import Writer

from reports import trace_format as tf
from reports.trace_checks import MAX_TRACE_NAMES
from reports.trace_reader import TraceReadError, read_trace
from reports.trace_records import MAX_CHUNK_BYTES
from tests.trace.test_trace import write_trace


def chunks_of(path: Path) -> list[Any]:
    with open(path, "rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None
    return sorted(summary.chunk_indexes, key=lambda c: c.chunk_start_offset)


def inspect(path: Path, *extra: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "runner", "inspect", str(path), *extra], capture_output=True,
                          text=True, timeout=120)  # fmt: skip


@pytest.fixture
def full(tmp_path: Path) -> Path:
    path = tmp_path / "full.mcap"
    write_trace(path, steps=100, flush_interval=0.2)
    return path


def damaged_copy(full: Path, change: str) -> tuple[Path, Any, list[Any]]:
    """The trace with its middle chunk damaged: a bit flipped in its compressed bytes, or its uncompressed
    size set to 2 GB."""
    chunks = chunks_of(full)
    middle = chunks[len(chunks) // 2]
    data = bytearray(full.read_bytes())
    start = middle.chunk_start_offset + 9  # the chunk's body, after its opcode and length
    if change == "bit":
        data[middle.chunk_start_offset + middle.chunk_length - 20] ^= 0x10  # inside the zstd frame
    else:
        struct.pack_into("<Q", data, start + 16, 2 * 1024**3)  # uncompressed_size
    path = full.with_name(f"{change}.mcap")
    path.write_bytes(bytes(data))
    return path, middle, chunks


@pytest.mark.parametrize("change", ["bit", "size"])
def test_a_damaged_chunk_is_skipped_and_the_rest_recovered(full: Path, change: str) -> None:
    path, middle, chunks = damaged_copy(full, change)
    with pytest.raises(TraceReadError, match=f"damaged at byte {middle.chunk_start_offset}"):
        read_trace(path)
    trace = read_trace(path, recover=True)
    whole = read_trace(full)
    lost = {t for t in whole.times if middle.message_start_time <= round(t * 1e9) <= middle.message_end_time}
    assert 0 < len(lost) < len(whole.times)
    assert trace.times.tolist() == [t for t in whole.times if t not in lost]  # before and after the damage
    assert trace.recovered and trace.complete and f"damaged at byte {middle.chunk_start_offset}" in trace.stop_reason
    assert trace.scenario == whole.scenario and trace.status == whole.status
    if change == "size":
        assert str(MAX_CHUNK_BYTES) in trace.stop_reason  # refused from its header, never inflated
    done = inspect(path, "--recover")
    assert done.returncode == 0 and "Traceback" not in done.stderr, done.stderr
    assert f"damaged at byte {middle.chunk_start_offset}" in done.stdout.replace("\n", " "), done.stdout
    done = inspect(path)
    assert done.returncode == 2 and f"damaged at byte {middle.chunk_start_offset}" in done.stderr, done.stderr


def crafted(path: Path, scenario: dict[str, str], result: dict[str, str] | None = None,
            schema: bytes | None = None) -> Path:  # fmt: skip
    """A small MCAP file holding the given metadata (and a message with a garbage schema)."""
    with open(path, "wb") as f:
        w = Writer(f)
        w.start(profile=tf.PROFILE)
        w.add_metadata(tf.METADATA_SCENARIO, scenario)
        if schema is not None:
            sid = w.register_schema("foxglove.FrameTransforms", "protobuf", schema)
            cid = w.register_channel("/tf", "protobuf", sid)
            w.add_message(cid, log_time=0, data=b"\x0a\x03abc", publish_time=0)
        if result is not None:
            w.add_metadata(tf.METADATA_RESULT, result)
        w.finish()
    return path


def good_scenario(full: Path) -> dict[str, str]:
    return dict(read_trace(full).scenario)


@pytest.mark.parametrize(
    "case",
    ["superscript", "nested-bodies", "nested-summary", "summary-list", "many-bodies", "garbage-schema", "text"],
)
def test_what_is_not_a_physics_scenarios_trace_is_refused_as_such(full: Path, tmp_path: Path, case: str) -> None:
    scenario = good_scenario(full)
    path = tmp_path / f"{case}.mcap"
    if case == "superscript":
        crafted(path, {**scenario, tf.KEY_TRACE_FORMAT: "\N{SUPERSCRIPT TWO}"})
        expected = "trace format"
    elif case == "nested-bodies":
        crafted(path, {**scenario, tf.KEY_BODIES: "[" * 100_000 + "]" * 100_000}, schema=b"")
        expected = "not a physics-scenarios trace: its scenario record's 'bodies' is not JSON"
    elif case == "nested-summary":
        crafted(path, scenario, {tf.KEY_STATUS: "passed", tf.KEY_SUMMARY: "[" * 100_000 + "]" * 100_000})
        expected = "not a physics-scenarios trace"
    elif case == "summary-list":
        crafted(path, scenario, {tf.KEY_STATUS: "passed", tf.KEY_SUMMARY: "[1, 2]"})
        expected = "not a physics-scenarios trace"
    elif case == "many-bodies":
        names = ",".join(f'"b{i}"' for i in range(MAX_TRACE_NAMES + 1))
        crafted(path, {**scenario, tf.KEY_BODIES: f"[{names}]"}, schema=b"")
        expected = "not a physics-scenarios trace"
    elif case == "garbage-schema":
        crafted(path, scenario, schema=b"\xff\x00garbage")
        expected = "not a physics-scenarios trace"
    else:
        path.write_text("schema_version: 1\n" * 100)
        expected = "not a physics-scenarios trace"
    for recover in (False, True):
        with pytest.raises(TraceReadError, match=expected):
            read_trace(path, recover=recover)
    done = inspect(path, "--recover")
    assert done.returncode == 2 and expected in done.stderr and "Traceback" not in done.stderr, done.stderr
