"""Traces read back with the `mcap` library: Foxglove schemas, simulated time, attachments, determinism."""

from __future__ import annotations

from pathlib import Path

from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory

from reports.trace_reader import read_trace
from runner.language.load import load_scenario
from runner.sim.run import run_loaded
from tests.paths import ROOT


def test_foxglove_channels_sim_time_and_attachments(tmp_path: Path) -> None:
    result = run_loaded(
        load_scenario(ROOT / "scenarios" / "factory_intervals.yaml", "door-closed"), "pybullet", tmp_path
    )
    with open(result.trace, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        schemas = {summary.schemas[c.schema_id].name for c in summary.channels.values()}
        assert {"foxglove.FrameTransforms", "foxglove.SceneUpdate", "foxglove.Log"} <= schemas
        times = [message.log_time for _, _, message in reader.iter_messages()]
        assert min(times) == 0 and max(times) == round(8.0 * 1e9)  # simulated, nanoseconds, 0 .. duration
        attachments = {a.name: a for a in reader.iter_attachments()}
        assert (
            attachments["factory_intervals.yaml"].data == (ROOT / "scenarios" / "factory_intervals.yaml").read_bytes()
        )
        assert "sounds/thud.wav" in attachments and "sounds/close.wav" in attachments
        metadata = {m.name: m.metadata for m in reader.iter_metadata()}
        assert metadata["scenario"]["backend"] == "pybullet"
        assert metadata["scenario"]["variant"] == "door-closed"
    with open(result.trace, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        logs = [(m.log_time, d) for _, _, m, d in reader.iter_decoded_messages(topics=["/log"])]
    assert any("box-into-door" in entry.message for _, entry in logs)
    assert all(entry.message.isprintable() and "\\u" not in entry.message for _, entry in logs)  # plain UTF-8


def test_same_run_twice_gives_identical_bytes(tmp_path: Path) -> None:
    for name in ("a", "b"):
        run_loaded(
            load_scenario(ROOT / "scenarios" / "factory_physics.yaml", "door-opens-with-the-box-on-it"),
            "pybullet",
            tmp_path / name,
        )
    first = next((tmp_path / "a").glob("*.mcap")).read_bytes()
    second = next((tmp_path / "b").glob("*.mcap")).read_bytes()
    assert first == second


def test_each_verdict_is_logged_when_it_is_decided_and_the_summary_at_the_end(tmp_path: Path) -> None:
    result = run_loaded(
        load_scenario(ROOT / "scenarios" / "factory_physics.yaml", "door-moves-away-box-falls"), "pybullet", tmp_path
    )
    trace = read_trace(result.trace)
    end = trace.end_time
    logs = [(round(lg.t * 1e9), lg.message) for lg in trace.logs if lg.name == "verdict"]
    assert logs[-1] == (round(end * 1e9), f"{len(trace.verdicts)}/{len(trace.verdicts)} assertions passed")
    logged = {message.split(":")[0].removeprefix("PASS "): ns for ns, message in logs[:-1]}
    assert len(logged) == len(trace.verdicts)
    early = 0
    for v in trace.verdicts:
        kind, at = v.data["kind"], v.data["time"]
        if kind in ("value", "check", "always", "never", "eventually"):  # decided at the step of its own time
            expected = at
        elif kind in ("max", "min"):  # decided when its window closes: after its extremum
            assert logged[v.name] >= round(at * 1e9), v.name
            expected = logged[v.name] / 1e9
        else:  # events and sounds are judged at the end
            expected = end
        assert logged[v.name] == round(expected * 1e9), v.name
        early += logged[v.name] < round(end * 1e9)
    assert early >= 3  # kick-velocity-step-1 at 0.04 s, ... : not all at the end
