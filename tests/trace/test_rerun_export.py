"""Rerun, natively: `scenario run --rerun` writes a `.rrd` beside each trace with the rerun-sdk, read back here
with rerun-sdk's own reader (``rerun.chunk.RrdReader``).

For every example scenario (scenarios/*.yaml and scenarios/robots/*.yaml, every variant, on PyBullet):

* one 3D entity per body and robot link (``/world/<name>``): its pose at every recorded step, equal to the
  trace's, and its shape;
* one scalar series per quantity the assertions read (``/asserted/<unit>/<quantity>``), equal to the trace's
  values at every recorded step; the quantities are listed by hand for three scenarios (box_pile's five crates
  with the top one, the KUKA hand and joint, the cart-pole's joints) so the list itself is checked;
* the verdicts in the log, the blueprint, and the same content from the same trace twice.

rerun-sdk is the optional `viewers` extra: skipped without it, and SCENARIO_REQUIRE_RERUN=1 (set by .ci/run,
which installs the extra) turns the skip into a failure.
"""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from reports.rerun_export import asserted_series, recording_id
from reports.scene3d.model import scene_model
from reports.trace_reader import read_trace
from runner.compile.asserted import asserted_quantities
from runner.compile.program import build_program
from runner.language.load import load_files
from tests.paths import ROOT

REQUIRED = os.environ.get("SCENARIO_REQUIRE_RERUN") == "1"
INSTALLED = importlib.util.find_spec("rerun") is not None
pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(not INSTALLED and not REQUIRED, reason="rerun-sdk is not installed (pip install '.[viewers]')"),
]
ENV = {**os.environ, "RERUN_ANALYTICS": "0"}
FILES = sorted((ROOT / "scenarios").glob("*.yaml")) + sorted((ROOT / "scenarios" / "robots").glob("*.yaml"))
SHAPES = ("Boxes3D", "Ellipsoids3D", "Cylinders3D", "Capsules3D", "Mesh3D", "Asset3D", "LineStrips3D")
#: what the assertions read, written out from the scenario files (box_pile: count 5, every crate)
BY_HAND = {
    "box-pile__base": [f"crate_{k}.{q}" for q in ("speed", "pos.z", "pos.x", "pos.y") for k in range(5)],
    "kuka-arm__base": [
        "arm.lbr_iiwa_link_7.pos.z",
        "arm.lbr_iiwa_joint_2.position",
        "arm.lbr_iiwa_link_7.pos.x",
        "arm.lbr_iiwa_link_7.pos.y",
    ],  # fmt: skip
    "cartpole-pendulum__base": ["cartpole.slider_to_cart.position", "cartpole.cart_to_pole.position"],
}


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    if not INSTALLED:
        pytest.fail("SCENARIO_REQUIRE_RERUN=1 but rerun-sdk is not installed (pip install '.[viewers]')")
    out = tmp_path_factory.mktemp("rrd")
    done = subprocess.run(
        [sys.executable, "-m", "runner", "run", *map(str, FILES), "--all-variants", "--backend", "pybullet",
         "--out", str(out), "-j", "2", "--quiet", "--rerun"],
        cwd=ROOT, capture_output=True, text=True, timeout=900, env=ENV,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-3000:]
    return out


def _entities(rrd: Path) -> dict[str, dict[str, Any]]:
    """Entity path -> {component column: values in time order, "sim_time": the times (s)} of the recording."""
    from rerun.chunk import RrdReader

    rows: dict[str, dict[str, list[Any]]] = {}
    for chunk in RrdReader(rrd).stream().to_chunks():
        batch = chunk.to_record_batch()
        entity = rows.setdefault(chunk.entity_path, {})
        times = [t.value / 1e9 for t in batch.column("sim_time")] if "sim_time" in batch.schema.names else []
        for name in batch.schema.names:
            if ":" in name:
                values = batch.column(name).to_pylist()
                entity.setdefault(name, []).extend(zip(times or [None] * len(values), values, strict=True))
    out: dict[str, dict[str, Any]] = {}
    for path, columns in rows.items():
        out[path] = {}
        for name, pairs in columns.items():
            pairs.sort(key=lambda p: -1.0 if p[0] is None else p[0])
            out[path][name] = [v for _, v in pairs]
            out[path][f"{name}@t"] = [t for t, _ in pairs]
    return out


def _cases() -> list[tuple[str, Any]]:
    cases = load_files(FILES, None, True)
    return [(f"{c.model.scenario}__{c.variant}", c) for c in cases]


def test_every_example_scenario_has_its_bodies_and_asserted_quantities_in_rerun(runs: Path) -> None:
    from rerun import escape_entity_path_part

    cases = _cases()
    assert len(cases) >= 13  # 4 + 4 + 1 + 4 robots: every variant of every example
    assert set(BY_HAND) <= {stem for stem, _ in cases}
    for stem, case in cases:
        trace_path = runs / f"{stem}__pybullet.mcap"
        rrd = runs / f"{stem}__pybullet.rrd"
        assert rrd.exists(), stem
        trace = read_trace(trace_path)
        entities = _entities(rrd)
        # one 3D entity per body and link, with its shape and its pose at every recorded step
        posed = sorted(p.removeprefix("/world/") for p, c in entities.items() if "Transform3D:translation" in c)
        assert posed == sorted(trace.bodies), stem
        drawn = {v.body for v in scene_model(trace).entities_at(0.0).values() if v.primitives and not v.solid}
        world = build_program(case).world  # every body with a visual or a collision shape: the cart-pole's rail
        assert drawn == {b.name for b in world.bodies if b.visuals or b.placed_shapes()}, stem  # has only a visual
        for name, body in trace.bodies.items():
            entity = entities[f"/world/{name}"]
            shaped = any(col.split(":")[0] in SHAPES for col in entity)
            assert shaped == (name in drawn), f"{stem}: {name}"
            np.testing.assert_array_equal(entity["Transform3D:translation@t"], trace.times, err_msg=stem)
            got = np.array([v[0] for v in entity["Transform3D:translation"]])
            np.testing.assert_array_equal(got, body.pos.astype(np.float32), err_msg=f"{stem}: {name}")
            quat = np.array([v[0] for v in entity["Transform3D:quaternion"]])
            np.testing.assert_array_equal(quat, body.quat[:, [1, 2, 3, 0]].astype(np.float32), err_msg=name)
        # one scalar series per asserted quantity, the trace's numbers at every recorded step
        wanted = asserted_quantities(build_program(case))
        if stem in BY_HAND:
            assert wanted == BY_HAND[stem], stem
        series, missing = asserted_series(trace)
        assert not missing and [s.name for s in series] == wanted, stem
        plotted = {p.rpartition("/")[2]: c for p, c in entities.items() if p.startswith("/asserted/")}
        assert sorted(plotted) == sorted(map(escape_entity_path_part, wanted)), stem  # `contact\(box\,\ door\)`
        for s in series:
            column = plotted[escape_entity_path_part(s.name)]
            values = np.array([v[0] for v in column["Scalars:scalars"]])
            np.testing.assert_array_equal(column["Scalars:scalars@t"], s.times, err_msg=f"{stem}: {s.name}")
            np.testing.assert_array_equal(values, s.values, err_msg=f"{stem}: {s.name}")
        # every verdict in the log, by name, with its outcome
        lines = [text[0] for text in entities["/log/verdict"]["TextLog:text"]]
        for v in trace.verdicts:
            assert any(f" {v.name}: " in line for line in lines), f"{stem}: {v.name}"


def test_box_piles_top_crate_height_is_plotted_in_metres(runs: Path) -> None:
    """The quantity Foxglove's plot used to drop (issue 30): the top crate's height, in the metres view."""
    entities = _entities(runs / "box-pile__base__pybullet.rrd")
    top = entities["/asserted/m/crate_4.pos.z"]["Scalars:scalars"]
    # dropped from 0.17 + 4 * 0.32 = 1.45 m; settles on four boxes: 0.15 + 4 * 0.3 = 1.35 m (within 1 cm, asserted)
    assert top[0][0] == pytest.approx(1.45, abs=1e-9)
    assert top[-1][0] == pytest.approx(1.35, abs=0.01)


def test_the_recording_has_the_blueprint_and_its_id_from_the_trace(runs: Path) -> None:
    from rerun.chunk import RrdReader

    trace = runs / "kuka-arm__base__pybullet.mcap"
    reader = RrdReader(runs / "kuka-arm__base__pybullet.rrd")
    assert [r.recording_id for r in reader.recordings()] == [recording_id(trace)]
    assert [r.application_id for r in reader.blueprints()] == ["physics-scenarios"]
    views = str([c.to_record_batch() for c in reader.stream(store=reader.blueprints()[0]).to_chunks()])
    for name in ("scene", "asserted (m)", "asserted (rad)", "joint and contact forces (N·m)", "log"):
        assert name in views, name


def test_the_same_trace_gives_the_same_recording(runs: Path, tmp_path: Path) -> None:
    """Same recording id and, entity by entity, the same components and values; only the ids the SDK mints
    (chunks, rows: TUIDs from the clock) differ, so the bytes do."""
    trace = runs / "factory-physics__door-stays-closed__pybullet.mcap"
    again = []
    for k in range(2):
        out = tmp_path / f"{k}.rrd"
        command = [sys.executable, "-m", "runner", "export", str(trace), "--to", "rerun", "--out", str(out)]
        done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=300, env=ENV)
        assert done.returncode == 0, done.stderr
        again.append(out)
    assert _entities(again[0]) == _entities(again[1]) == _entities(trace.with_suffix(".rrd"))


def test_export_refuses_what_it_cannot_do(runs: Path, tmp_path: Path) -> None:
    def export(*args: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run([sys.executable, "-m", "runner", "export", *args, "--to", "rerun"], cwd=ROOT,
                              capture_output=True, text=True, timeout=300, env=ENV)  # fmt: skip

    missing = export(str(tmp_path / "nothing.mcap"))
    assert missing.returncode == 2 and "does not exist" in missing.stderr and "Traceback" not in missing.stderr
    both = sorted(runs.glob("*.mcap"))[:2]
    two = export(*map(str, both), "--out", str(tmp_path / "one.rrd"))
    assert two.returncode == 2 and "--out FILE" in two.stderr
