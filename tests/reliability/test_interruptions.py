"""Interruptions of a running `scenario run`: SIGINT and SIGTERM finish the trace (status interrupted,
exit 130/143); SIGKILL leaves a `.partial` that `scenario inspect --recover` reads up to its last chunk.

The run: a 0.1 m sphere drifting at 1 m/s without gravity for 50,000 simulated seconds (5e6 steps of
0.01 s), so that it is always mid-run when the signal comes; its trace is checked step by step
(x = t on the float64 engines). Then FUZZ_FAULTS runs (conftest.py) are signalled at random
moments, on every real engine, and every outcome must leave a readable, self-consistent trace (read
both by the project's stream reader and by mcap's own indexed reader) and no traceback.
"""

from __future__ import annotations

import random
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap.stream_reader import StreamReader

from backends.registry import is_installed
from reports import trace_format as tf
from reports.trace_reader import Trace, read_trace

from .conftest import FUZZ_FAULTS, count

DT = 0.01
DRIFT = """\
schema_version: 1
scenario: drift
world: {{gravity: [0, 0, 0], dt: 0.01, duration: {duration}}}
bodies:
  ball: {{sphere: 0.1, density: 1000, pos: [0, 0, 1], vel: [1, 0, 0]}}
assertions:
  - {{name: runs-to-the-end, at: end, check: time > 0}}
"""
REAL = [b for b in ("pybullet", "mujoco", "dart", "ode") if is_installed(b)]


def _default_sigint() -> None:
    """In the child: SIGINT as a terminal delivers it, even when this test runs with SIGINT ignored (a
    background job), which the child would inherit and Python would then keep."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


_children: list[subprocess.Popen] = []


@pytest.fixture(autouse=True)
def _no_leftover_runs() -> Iterator[None]:
    """A failed test must not leave its (long) run behind."""
    yield
    while _children:
        child = _children.pop()
        if child.poll() is None:
            child.kill()
            child.wait(timeout=30)


def start(tmp_path: Path, backend: str = "pybullet", duration: float = 50_000) -> tuple[subprocess.Popen, Path]:
    source = tmp_path / "drift.yaml"
    source.write_text(DRIFT.format(duration=duration))
    out = tmp_path / "out"
    child = subprocess.Popen(
        [sys.executable, "-m", "runner", "run", str(source), "--backend", backend, "--out", str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=_default_sigint,  # safe here: pytest runs these tests in one thread
    )
    _children.append(child)
    return child, out / f"drift__base__{backend}.mcap"


def partial_of(path: Path) -> Path:
    return path.with_name(path.name + tf.PARTIAL_SUFFIX)


def wait_for_chunks(child: subprocess.Popen, path: Path, size: int, timeout: float = 60.0) -> None:
    """Until the run's .partial holds ``size`` bytes (several chunks): the run is then well under way."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        partial = partial_of(path)
        if partial.exists() and partial.stat().st_size >= size:
            return
        if child.poll() is not None:
            raise AssertionError(f"the run ended early: {child.returncode}\n{child.stderr.read()}")  # type: ignore[union-attr]
        time.sleep(0.02)
    raise AssertionError(f"no {size}-byte partial trace after {timeout} s")


def finish(child: subprocess.Popen) -> tuple[int, str]:
    _, err = child.communicate(timeout=60)
    return child.returncode, err


def assert_steps(trace: Trace, exact_physics: bool = True) -> None:
    """Consecutive steps from t = 0, nothing missing or repeated; x = t for the drifting ball."""
    ns = np.round(trace.times * 1e9).astype(np.int64)
    assert ns.size >= 2 and ns[0] == 0
    np.testing.assert_array_equal(np.diff(ns), round(DT * 1e9))
    if exact_physics:  # float64 engines: x_k = x_{k-1} + 1 m/s * dt, rounding only (1e-9 at x = 1000)
        np.testing.assert_allclose(trace.bodies["ball"].pos[:, 0], trace.times, rtol=0, atol=1e-6)


def assert_whole_steps(trace: Trace) -> None:
    """A finished trace ends with a whole step: every per-step channel has every step, and the recorded
    end time is the last step's (a signal landing inside the writer breaks this)."""
    steps = len(trace.times)
    counts = {t: trace.channels[t].count for t in (tf.TOPIC_TF, tf.TOPIC_BODIES, tf.TOPIC_CONTACTS)}
    assert set(counts.values()) == {steps}, counts
    assert int(trace.result[tf.KEY_STEPS]) == steps
    assert float(trace.result[tf.KEY_END_TIME]) == pytest.approx(trace.times[-1], abs=1e-12)


def mcap_index_agrees(path: Path, trace: Trace) -> None:
    """mcap's seeking reader (which uses the summary and chunk indexes Foxglove uses) sees the same."""
    with open(path, "rb") as f:
        indexed = sum(1 for _ in make_reader(f).iter_messages())
    assert indexed == sum(c.count for c in trace.channels.values())


def complete_record_end(path: Path) -> int:
    """Bytes of ``path`` that form complete MCAP records (counted by mcap's own stream reader)."""

    class Counting:
        def __init__(self, f) -> None:  # noqa: ANN001
            self.f, self.good, self.pos = f, 0, 0

        def read(self, n: int) -> bytes:
            data = self.f.read(n)
            self.pos += len(data)
            return data

    with open(path, "rb") as f:
        stream = Counting(f)
        records: Iterator = iter(StreamReader(stream, skip_magic=False, validate_crcs=True).records)
        while True:
            try:
                next(records)
            except Exception:  # noqa: BLE001 - the first incomplete record ends the readable part
                return stream.good
            stream.good = stream.pos


@pytest.mark.parametrize("sig,code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)], ids=["SIGINT", "SIGTERM"])
def test_sigint_and_sigterm_finish_the_trace_as_interrupted(tmp_path: Path, sig: int, code: int) -> None:
    child, path = start(tmp_path)
    wait_for_chunks(child, path, 60_000)
    child.send_signal(sig)
    rc, err = finish(child)
    assert rc == code, err
    assert "Traceback" not in err and "interrupted" in err
    assert path.exists() and not partial_of(path).exists()
    trace = read_trace(path)  # finished: no recover
    assert trace.complete and trace.status == tf.STATUS_INTERRUPTED
    assert_whole_steps(trace)
    assert trace.times[-1] > 5.0  # well into the run
    assert_steps(trace)
    mcap_index_agrees(path, trace)
    assert [a.name for a in trace.attachments] == ["drift.yaml"]


def test_sigkill_leaves_a_partial_that_inspect_recovers_up_to_its_last_chunk(tmp_path: Path) -> None:
    child, path = start(tmp_path)
    wait_for_chunks(child, path, 60_000)
    child.send_signal(signal.SIGKILL)
    rc, _ = finish(child)
    assert rc == -signal.SIGKILL
    partial = partial_of(path)
    assert partial.exists() and not path.exists()  # a half-written trace never has the final name
    trace = read_trace(path, recover=True)
    assert not trace.complete and trace.recovered and trace.status == tf.STATUS_INCOMPLETE
    assert_steps(trace)
    # chunks close after the first step at or past each simulated second: the last one read is whole
    assert trace.times[-1] == pytest.approx(round(trace.times[-1])) and trace.times[-1] >= 1.0
    assert complete_record_end(partial) == partial.stat().st_size  # every byte on disk is recovered
    cli = [sys.executable, "-m", "runner", "inspect"]
    done = subprocess.run([*cli, str(partial), "--recover"], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    text = " ".join(done.stdout.split())
    assert "read up to its last complete chunk" in text and f"{len(trace.times)} (0 s to" in text
    refused = subprocess.run([*cli, str(partial)], capture_output=True, text=True, timeout=120)
    assert refused.returncode == 2 and "--recover" in refused.stderr and "Traceback" not in refused.stderr


@pytest.mark.parametrize("case", range(FUZZ_FAULTS))
def test_a_signal_at_a_random_moment_never_corrupts_the_trace(tmp_path: Path, case: int) -> None:
    """A run of 0.1 s to a minute of wall time signalled at a random moment, possibly after it has finished."""
    rng = random.Random(case)
    backend = rng.choice(REAL)
    sig = rng.choice([signal.SIGINT, signal.SIGTERM, signal.SIGKILL])
    child, path = start(tmp_path, backend, duration=rng.choice([50, 500, 5000]))
    wait_for_chunks(child, path, 1)
    time.sleep(rng.uniform(0.0, 2.0))
    child.send_signal(sig)
    rc, err = finish(child)
    expected = {signal.SIGINT: 130, signal.SIGTERM: 143, signal.SIGKILL: -signal.SIGKILL}[sig]
    # -sig for SIGINT/SIGTERM: the signal came after `main()` had returned (the trace finished, exiting)
    assert rc in (0, expected, -sig), (rc, err)
    assert rc == -sig or "Traceback" not in err, err
    late = rc == 0 or (rc == -sig and sig != signal.SIGKILL) or (path.exists() and sig == signal.SIGKILL)
    outcome = "after the run had finished" if late else f"{signal.Signals(sig).name} mid-run"
    if path.exists():
        assert not partial_of(path).exists()
        trace = read_trace(path)
        assert trace.complete and trace.status in (tf.STATUS_PASSED, tf.STATUS_INTERRUPTED)
        assert (trace.status == tf.STATUS_PASSED) == late
        assert_whole_steps(trace)
        mcap_index_agrees(path, trace)
    else:
        assert rc == -signal.SIGKILL
        trace = read_trace(path, recover=True)
        assert complete_record_end(partial_of(path)) == partial_of(path).stat().st_size
        outcome += " (recovered)"
    assert_steps(trace, exact_physics=backend != "ode")
    count("signals injected", f"{backend} {outcome}")
