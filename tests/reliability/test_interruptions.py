"""Interruptions of a running `scenario run`: SIGINT and SIGTERM finish the trace (status interrupted,
exit 130/143); SIGKILL leaves a `.partial` that `scenario inspect --recover` reads up to its last chunk.

The run: a 0.1 m sphere drifting at 1 m/s without gravity for 50,000 simulated seconds (5e6 steps of
0.01 s), so that it is always mid-run when the signal comes; its trace is checked step by step
(x = t on the float64 engines). The engine runs in a worker process of the command (runner.exec): a
signal to the command is passed on to it, SIGKILL of the command reaches it through the kernel, and
the worker itself may be killed. Then FUZZ_FAULTS runs (conftest.py) are signalled at random moments
(SIGINT, SIGTERM, SIGKILL to the command, SIGKILL to the worker, two SIGINTs), on every real engine,
and every outcome must leave a readable, self-consistent trace (read both by the project's stream
reader and by mcap's own indexed reader) and no traceback.
"""

from __future__ import annotations

import contextlib
import os
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

from reports import trace_format as tf
from reports.trace_reader import Trace, read_trace
from tests.engines import INSTALLED

from .conftest import FUZZ_FAULTS, count
from .processes import wait_released, worker_of

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
REAL = list(INSTALLED)


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
            except StopIteration:  # the footer and the closing magic: a whole file (not renamed yet)
                return stream.pos
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


def alive(pid: int) -> bool:
    """The process exists and is not a zombie waiting to be reaped."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except (FileNotFoundError, ProcessLookupError):
        return False


def assert_recovered_to_a_chunk(path: Path) -> Trace:
    partial = partial_of(path)
    assert partial.exists() and not path.exists()  # a half-written trace never has the final name
    trace = read_trace(path, recover=True)
    assert not trace.complete and trace.recovered and trace.status == tf.STATUS_INCOMPLETE
    # chunks close after the first step at or past each simulated second: the last one read is whole
    assert trace.times[-1] == pytest.approx(round(trace.times[-1])) and trace.times[-1] >= 1.0
    assert complete_record_end(partial) == partial.stat().st_size  # every byte on disk is recovered
    return trace


def test_sigkill_of_the_command_lets_its_worker_finish_the_trace(tmp_path: Path) -> None:
    """`scenario` killed outright: its worker is told by the kernel (PR_SET_PDEATHSIG) and finishes the
    trace at the next step, as for SIGTERM; nothing is lost."""
    child, path = start(tmp_path)
    wait_for_chunks(child, path, 60_000)
    worker = worker_of(child)
    child.send_signal(signal.SIGKILL)
    rc, _ = finish(child)
    assert rc == -signal.SIGKILL
    wait_released(path)
    deadline = time.monotonic() + 10
    while alive(worker) and time.monotonic() < deadline:  # then it ends: nobody is left to send it a job
        time.sleep(0.05)
    assert not alive(worker), "the orphaned worker outlived its trace"
    trace = read_trace(path)
    assert trace.complete and trace.status == tf.STATUS_INTERRUPTED and trace.times[-1] > 5.0
    assert_whole_steps(trace)
    assert_steps(trace)
    mcap_index_agrees(path, trace)


def test_a_killed_engine_process_is_a_crash_and_inspect_recovers_its_trace(tmp_path: Path) -> None:
    """The process running the engine killed (the OOM killer, a crash): exit 3 "crashed (signal 9)", the
    trace kept as .partial up to its last chunk, every byte on disk recovered."""
    child, path = start(tmp_path)
    wait_for_chunks(child, path, 60_000)
    os.kill(worker_of(child), signal.SIGKILL)
    rc, err = finish(child)
    assert rc == 3 and "crashed (signal 9)" in err and "Traceback" not in err, err
    trace = assert_recovered_to_a_chunk(path)
    assert_steps(trace)
    partial = partial_of(path)
    cli = [sys.executable, "-m", "runner", "inspect"]
    done = subprocess.run([*cli, str(partial), "--recover"], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    text = " ".join(done.stdout.split())
    assert "read up to its last complete chunk" in text and f"{len(trace.times)} (0 s to" in text
    refused = subprocess.run([*cli, str(partial)], capture_output=True, text=True, timeout=120)
    assert refused.returncode == 2 and "--recover" in refused.stderr and "Traceback" not in refused.stderr


def test_a_second_signal_ends_the_run_at_once_and_keeps_the_partial(tmp_path: Path) -> None:
    """Two SIGINTs in a row: the second kills the worker at once (as inside an engine call that never
    returns), the command exits 130 and the trace is kept up to its last chunk."""
    child, path = start(tmp_path)
    wait_for_chunks(child, path, 60_000)
    child.send_signal(signal.SIGINT)
    child.send_signal(signal.SIGINT)
    rc, err = finish(child)
    assert rc == 130 and "Traceback" not in err, err
    wait_released(path)
    if path.exists():  # the worker finished its step and the trace before the second signal reached it
        assert read_trace(path).status == tf.STATUS_INTERRUPTED
    else:
        assert_steps(assert_recovered_to_a_chunk(path))


KINDS = ["SIGINT", "SIGTERM", "SIGKILL", "SIGKILL to the engine's process", "SIGINT twice"]
EXPECTED = {"SIGINT": (130,), "SIGTERM": (143,), "SIGKILL": (-9,), "SIGKILL to the engine's process": (3,),
            "SIGINT twice": (130,)}  # fmt: skip


@pytest.mark.parametrize("case", range(FUZZ_FAULTS))
def test_a_signal_at_a_random_moment_never_corrupts_the_trace(tmp_path: Path, case: int) -> None:
    """A run of 0.1 s to a minute of wall time signalled at a random moment, possibly after it has finished:
    whatever the signal, the trace is whole (finished) or a .partial read to its last byte."""
    rng = random.Random(case)
    backend = rng.choice(REAL)
    kind = rng.choice(KINDS)
    child, path = start(tmp_path, backend, duration=rng.choice([50, 500, 5000]))
    wait_for_chunks(child, path, 1)
    worker = worker_of(child)
    time.sleep(rng.uniform(0.0, 2.0))
    if kind == "SIGKILL to the engine's process":
        with contextlib.suppress(ProcessLookupError):
            os.kill(worker, signal.SIGKILL)
    else:
        child.send_signal(getattr(signal, kind.split()[0]))
        if kind == "SIGINT twice":
            child.send_signal(signal.SIGINT)
    rc, err = finish(child)
    wait_released(path)
    sig = getattr(signal, kind.split()[0])
    # 0: the run was over; -sig: the signal came after `main()` had returned; the interrupted code: the
    # command was stopped, mid-run or while it wrapped up a run its worker had finished
    assert rc in (0, -sig, *EXPECTED[kind]), (rc, err)
    assert rc < 0 or "Traceback" not in err, err
    if path.exists():
        assert not partial_of(path).exists()
        trace = read_trace(path)
        assert trace.complete and trace.status in (tf.STATUS_PASSED, tf.STATUS_INTERRUPTED)
        late = trace.status == tf.STATUS_PASSED  # the worker had finished the run when the signal came
        assert late or rc in EXPECTED[kind], (rc, trace.status)
        assert_whole_steps(trace)
        mcap_index_agrees(path, trace)
        outcome = "after the run had finished" if late else f"{kind} mid-run"
    else:
        assert kind in ("SIGKILL to the engine's process", "SIGINT twice"), (kind, rc, err)
        trace = read_trace(path, recover=True)
        assert complete_record_end(partial_of(path)) == partial_of(path).stat().st_size
        outcome = f"{kind} mid-run (recovered)"
        if not len(trace.times):  # killed before its first chunk closed (one simulated second): header only
            assert trace.scenario["backend"] == backend and trace.attachments
            count("signals injected", f"{backend} {kind} before the first chunk (recovered: the header)")
            return
    assert_steps(trace, exact_physics=backend != "ode")
    count("signals injected", f"{backend} {outcome}")
