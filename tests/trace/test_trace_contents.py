"""Traces read back with the `mcap` library: Foxglove schemas, simulated time, attachments, determinism."""

from __future__ import annotations

import json
from pathlib import Path

from mcap.reader import make_reader

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
        logs = [json.loads(m.data) for s, c, m in make_reader(f).iter_messages(topics=["/log"])]
    assert any("box-into-door" in entry["message"] for entry in logs)


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
