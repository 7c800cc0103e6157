"""The MCAP trace: writer (runner/trace/writer.py), reader and inspect (reports/), read back with `mcap` itself."""

from __future__ import annotations

import json
import math
import signal
import subprocess
import sys
import textwrap
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from mcap.reader import make_reader

from backends import types as bt
from backends.errors import EngineFailure
from reports import trace_format as tf
from reports.inspect import summary_text
from reports.trace_reader import TraceReadError, read_trace
from runner.errors import TraceError
from runner.trace import foxglove as fx
from runner.trace.writer import SolidVisual, TraceMeta, TraceWriter

REPO = Path(__file__).resolve().parents[2]
G = 9.81
DT = 0.04
Z0 = 2.0
RES = tf.VALUE_RESOLUTION
YAML = b"scenario: unit\nworld: {dt: 0.04}\n"
WAV = b"RIFF\x24\x00\x00\x00WAVEfmt " + bytes(range(40))


def make_meta() -> TraceMeta:
    bodies = (
        bt.BodySpec("floor", bt.Motion.STATIC, bt.Shape(bt.ShapeKind.PLANE), 0.0, (0, 0, 0), (0, 0, 0), (1, 0, 0, 0)),
        bt.BodySpec("box", bt.Motion.DYNAMIC, bt.Shape(bt.ShapeKind.BOX, (0.3, 0.2, 0.1)), 13.5, (1, 1, 1), (1, 0, Z0),
                    (1, 0, 0, 0), color=(0.9, 0.2, 0.1, 1.0)),
        bt.BodySpec("door", bt.Motion.DYNAMIC, bt.Shape(bt.ShapeKind.BOX, (2, 2, 0.1)), 400.0, (1, 1, 1), (1, 0, 0),
                    (1, 0, 0, 0)),
    )  # fmt: skip
    joints = (bt.JointSpec("slider", bt.JointKind.SLIDER, "door", None, motor=bt.Motor(0.3, 100.0)),)
    return TraceMeta(
        scenario="unit", variant="fall", backend="fake", backend_version="1.2.3",
        engine_settings={"solver_iterations": 50, "erp": 0.2}, dt=DT, substeps=2, duration=4.0,
        tool_version="0.1.0", scenario_sha256="ab" * 32, scenario_path="unit.yaml", schema_version=1,
        bodies=bodies, joints=joints, state_names=("door_open", "count"),
    )  # fmt: skip


def states_at(t: float) -> bt.BodyStates:
    """Floor at rest, the box in free fall from Z0, the door sliding at 0.3 m/s."""
    pos = np.array([[0, 0, 0], [1, 0, Z0 - 0.5 * G * t * t], [1 + 0.3 * t, 0, 0]], dtype=float)
    half = 0.5 * 0.7 * t  # box spinning about z at 0.7 rad/s
    quat = np.array([[1, 0, 0, 0], [math.cos(half), 0, 0, math.sin(half)], [1, 0, 0, 0]], dtype=float)
    vel = np.array([[0, 0, 0], [0, 0, -G * t], [0.3, 0, 0]], dtype=float)
    angvel = np.array([[0, 0, 0], [0, 0, 0.7], [0, 0, 0]], dtype=float)
    return bt.BodyStates(pos, quat, vel, angvel)


def joints_at(t: float) -> bt.JointStates:
    return bt.JointStates(np.array([0.3 * t]), np.array([0.3]), np.array([-12.5]))


def write_trace(path: Path, steps: int = 50, finish: bool = True, writer: Any = TraceWriter, **kw: Any) -> Any:
    w = writer(path, make_meta(), **kw)
    w.attach("unit.yaml", YAML, "application/yaml")
    w.attach("sounds/thud.wav", WAV, "audio/wav")
    w.scene(0.0, [
        SolidVisual("ball", "box", "sphere", center=(0, 0, 0.1), radius=0.45),
        SolidVisual("lid", "door", "polygon", vertices=((-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0))),
    ])  # fmt: skip
    for k in range(steps):
        t = k * DT
        contacts = [bt.Contact(0, 2, 4, 0.001, 3924.0)] + ([bt.Contact(1, 2, 1, 0.002, float("nan"))] if k == 7 else [])
        w.step(t, states_at(t), joints_at(t), contacts, {"door_open": k >= 10, "count": float(k)})
        if k == 10:
            w.event(t, "box-into-door", "collision", {"into": "lid"})
            w.sound(t, "thud", "start", 0.0, 0.8)
            w.log(t, "warning", "door opened", "handler")
        if k == 20:
            w.scene(t, scales={"box": 2.0})
            w.sound(t, "thud", "stop")
    if finish:
        t_end = (steps - 1) * DT
        lands = {"name": "lands", "passed": True, "measured": 0.05, "expected": "< 0.1"}
        w.verdicts(t_end, [lands, {"name": "never-bounces", "passed": False, "measured": math.inf, "expected": 0}])
        w.finish(tf.STATUS_FAILED, {"passed": 1, "failed": 1})
    return w


def mcap_messages(path: Path) -> list[tuple[str, str, int, dict[str, Any]]]:
    """[(topic, schema name, log time, message)] in file order, with mcap's seeking reader; no NaN allowed."""
    with open(path, "rb") as f:
        messages = make_reader(f).iter_messages(log_time_order=False)
        return [(c.topic, s.name, m.log_time, json.loads(m.data, parse_constant=_no_nan)) for s, c, m in messages]


def as_ns(times: np.ndarray) -> list[int]:
    return [round(t * 1e9) for t in times.tolist()]


def _no_nan(token: str) -> None:
    raise AssertionError(f"{token} is not JSON")


@pytest.fixture
def trace_file(tmp_path: Path) -> Path:
    path = tmp_path / "unit.mcap"
    write_trace(path)
    return path


def test_round_trip_with_the_mcap_reader(trace_file: Path) -> None:
    with open(trace_file, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        assert reader.get_header().library == tf.LIBRARY
        schema_of = {ch.topic: summary.schemas[ch.schema_id] for ch in summary.channels.values()}
        for ch in summary.channels.values():
            assert (ch.message_encoding, schema_of[ch.topic].encoding) == ("json", "jsonschema")
        assert schema_of["/tf"].name == "foxglove.FrameTransforms"
        assert schema_of["/scene"].name == "foxglove.SceneUpdate"
        assert schema_of["/log"].name == "foxglove.Log"
        assert {c.compression for c in summary.chunk_indexes} == {"lz4"}
        meta = {m.name: m.metadata for m in reader.iter_metadata()}
        attachments = {a.name: (a.media_type, a.data, a.log_time) for a in reader.iter_attachments()}
    scenario = meta[tf.METADATA_SCENARIO]
    assert scenario[tf.KEY_NAME] == "unit" and scenario[tf.KEY_VARIANT] == "fall"
    assert (scenario[tf.KEY_BACKEND], scenario[tf.KEY_BACKEND_VERSION]) == ("fake", "1.2.3")
    assert float(scenario[tf.KEY_DT]) == DT and scenario[tf.KEY_SCENARIO_SHA256] == "ab" * 32
    assert json.loads(scenario[tf.KEY_ENGINE_SETTINGS]) == {"erp": 0.2, "solver_iterations": 50}
    assert json.loads(scenario[tf.KEY_BODIES]) == ["floor", "box", "door"]
    assert json.loads(scenario[tf.KEY_BODY_SPECS])[1]["shape"]["size"] == [0.3, 0.2, 0.1]
    assert meta[tf.METADATA_RESULT][tf.KEY_STATUS] == tf.STATUS_FAILED
    assert meta[tf.METADATA_RESULT][tf.KEY_STEPS] == "50"
    assert attachments == {"unit.yaml": ("application/yaml", YAML, 0), "sounds/thud.wav": ("audio/wav", WAV, 0)}

    messages = mcap_messages(trace_file)
    tf_msgs = [(ns, m) for topic, _, ns, m in messages if topic == "/tf"]
    assert [ns for ns, _ in tf_msgs] == [round(k * DT * 1e9) for k in range(50)]  # simulated time in ns
    ns, msg = tf_msgs[30]
    t = 30 * DT
    box = msg["transforms"][1]
    assert box["timestamp"] == {"sec": ns // 10**9, "nsec": ns % 10**9}
    assert (box["parent_frame_id"], box["child_frame_id"]) == ("world", "box")
    assert box["translation"]["z"] == pytest.approx(Z0 - 0.5 * G * t * t, abs=RES)
    assert box["rotation"]["w"] == pytest.approx(math.cos(0.35 * t), abs=RES)
    assert box["rotation"]["z"] == pytest.approx(math.sin(0.35 * t), abs=RES)
    bodies = [m for topic, _, ns, m in messages if topic == "/bodies"]
    assert bodies[30]["box"]["vel"]["z"] == pytest.approx(-G * t, abs=RES)
    assert bodies[30]["door"]["pos"]["x"] == pytest.approx(1 + 0.3 * t, abs=RES)
    assert bodies[30]["box"]["quat"]["w"] == pytest.approx(math.cos(0.35 * t), abs=RES)
    joints = [m for topic, _, _, m in messages if topic == "/joints"]
    assert joints[30] == {
        "slider": {"position": pytest.approx(0.3 * t, abs=RES), "velocity": 0.3, "motor_force": -12.5}
    }
    logs = [(ns, m) for topic, _, ns, m in messages if topic == "/log"]
    event_ns = round(10 * DT * 1e9)
    event_logs = [m for ns, m in logs if m["name"] == tf.LOGGER_EVENT]
    assert [m["level"] for m in event_logs] == [2] and event_logs[0]["message"].startswith("box-into-door")
    assert event_logs[0]["timestamp"] == {"sec": 0, "nsec": event_ns}
    verdict_logs = [m for _, m in logs if m["name"] == tf.LOGGER_VERDICT]
    assert [(m["level"], m["message"].split()[0]) for m in verdict_logs] == [(2, "PASS"), (4, "FAIL")]
    assert [m for topic, _, _, m in messages if topic == "/events"] == [
        {"time": 10 * DT, "name": "box-into-door", "source": "collision", "detail": {"into": "lid"}}
    ]


def test_scene_entities_are_frame_locked_body_shapes_and_translucent_solids(trace_file: Path) -> None:
    messages = mcap_messages(trace_file)
    scenes = [(ns, m) for topic, _, ns, m in messages if topic == "/scene"]
    assert [ns for ns, _ in scenes] == [0, round(20 * DT * 1e9)]
    first = {e["id"]: e for e in scenes[0][1]["entities"]}
    assert set(first) == {"body/floor", "body/box", "body/door", "solid/box/ball", "solid/door/lid"}
    box = first["body/box"]
    assert (box["frame_id"], box["frame_locked"], box["lifetime"]) == ("box", True, {"sec": 0, "nsec": 0})
    assert box["cubes"][0]["size"] == {"x": 0.3, "y": 0.2, "z": 0.1}
    assert box["cubes"][0]["color"] == {"r": 0.9, "g": 0.2, "b": 0.1, "a": 1.0}
    floor = first["body/floor"]["cubes"][0]
    assert floor["size"]["z"] == fx.PLANE_THICKNESS and floor["size"]["x"] >= 20
    assert floor["pose"]["position"]["z"] + floor["size"]["z"] / 2 == pytest.approx(0.0)  # top face = the plane
    ball = first["solid/box/ball"]["spheres"][0]
    assert ball["size"] == {"x": 0.9, "y": 0.9, "z": 0.9} and ball["color"]["a"] < 1
    lid = first["solid/door/lid"]
    assert len(lid["triangles"][0]["points"]) == 2 * 2 * 3  # both faces of 2 triangles
    assert len(lid["lines"][0]["points"]) == 4
    rescaled = {e["id"]: e for e in scenes[1][1]["entities"]}
    assert rescaled["body/box"]["cubes"][0]["size"] == {"x": 0.6, "y": 0.4, "z": 0.2}


def _check(value: Any, schema: dict[str, Any], where: str) -> None:
    """Every field is declared in the schema (recursively); Foxglove objects carry all their fields."""
    if value is None:
        return
    if schema.get("type") == "object" and "properties" in schema:
        props = schema["properties"]
        assert isinstance(value, dict), where
        assert set(value) <= set(props), f"{where}: undeclared {set(value) - set(props)}"
        if schema["title"].startswith("foxglove.") or schema["title"] in ("time", "duration"):
            assert set(value) == set(props), f"{where}: missing {set(props) - set(value)}"
        for k, v in value.items():
            _check(v, props[k], f"{where}.{k}")
    elif schema.get("type") == "array":
        for i, v in enumerate(value):
            _check(v, schema.get("items", {}), f"{where}[{i}]")
    elif "oneOf" in schema:
        assert value in [c["const"] for c in schema["oneOf"]], where


def test_every_message_matches_its_channel_schema(trace_file: Path) -> None:
    with open(trace_file, "rb") as f:
        summary = make_reader(f).get_summary()
        schemas = {ch.topic: json.loads(summary.schemas[ch.schema_id].data) for ch in summary.channels.values()}
    messages = mcap_messages(trace_file)
    assert {topic for topic, *_ in messages} == set(schemas)
    for topic, name, _, msg in messages:
        assert schemas[topic]["title"] == name
        _check(msg, schemas[topic], topic)


def test_non_finite_values_are_written_as_null_and_read_back_as_nan(tmp_path: Path) -> None:
    with TraceWriter(tmp_path / "nan.mcap", make_meta()) as w:
        s = states_at(0.0)
        s.pos[1, 2] = np.nan
        s.lin_vel[2, 0] = np.inf
        w.step(0.0, s, bt.JointStates(np.array([np.nan]), np.array([0.0]), np.array([2e9])), [], {"count": math.nan})
        path = w.finish(tf.STATUS_ENGINE_FAILURE, {"error": "NaN", "last": math.inf})
    messages = mcap_messages(path)  # parse_constant refuses NaN and Infinity
    bodies = next(m for topic, _, _, m in messages if topic == "/bodies")
    assert bodies["box"]["pos"] == {"x": 1.0, "y": 0.0, "z": None} and bodies["door"]["vel"]["x"] is None
    joints = next(m for topic, _, _, m in messages if topic == "/joints")
    assert joints["slider"] == {"position": None, "velocity": 0.0, "motor_force": 2e9}  # exact, via repr
    trace = read_trace(path)
    assert math.isnan(trace.bodies["box"].pos[0, 2]) and trace.bodies["box"].pos[0, 0] == 1.0
    assert trace.summary == {"error": "NaN", "last": None}
    assert math.isnan(trace.series("state.count")[1][0])


def test_identical_calls_give_identical_bytes(tmp_path: Path) -> None:
    a, b, c = tmp_path / "a.mcap", tmp_path / "b.mcap", tmp_path / "c.mcap"
    write_trace(a)
    write_trace(b)
    write_trace(c, steps=49)
    assert a.read_bytes() == b.read_bytes()
    assert a.read_bytes() != c.read_bytes()


def test_written_to_partial_and_renamed_when_finished(tmp_path: Path) -> None:
    path = tmp_path / "out" / "run.mcap"
    w = write_trace(path, finish=False, flush_interval=0.2)
    partial = path.with_name("run.mcap.partial")
    assert partial.exists() and not path.exists()
    # chunks reach the file while running: closed after the steps at t = 0.2, 0.4, ..., 1.8 s
    assert as_ns(read_trace(path, recover=True).times) == [round(k * DT * 1e9) for k in range(46)]
    final = w.finish(tf.STATUS_PASSED, {})
    assert final == path and path.exists() and not partial.exists()
    assert w.finish(tf.STATUS_ERROR, {}) == path  # idempotent
    assert read_trace(path).status == tf.STATUS_PASSED
    with pytest.raises(TraceError):
        w.step(99.0, states_at(0.0), joints_at(0.0), [], {})


def test_force_false_refuses_to_overwrite(tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    write_trace(path, steps=3)
    before = path.read_bytes()
    with pytest.raises(TraceError, match="--force"):
        TraceWriter(path, make_meta(), force=False)
    assert path.read_bytes() == before and not path.with_name("run.mcap.partial").exists()
    path.with_name("other.mcap.partial").write_bytes(b"left by a killed run")
    with pytest.raises(TraceError, match="--recover"):
        TraceWriter(tmp_path / "other.mcap", make_meta(), force=False)
    write_trace(path, steps=5)  # force=True (the default) replaces it
    assert len(read_trace(path).times) == 5


@pytest.mark.parametrize(
    ("exc", "status"),
    [
        (RuntimeError("boom"), tf.STATUS_ERROR),
        (KeyboardInterrupt(), tf.STATUS_INTERRUPTED),
        (EngineFailure("box: NaN", body="box", time=0.44), tf.STATUS_ENGINE_FAILURE),
    ],
)
def test_abandoned_writer_leaves_a_finished_trace(tmp_path: Path, exc: BaseException, status: str) -> None:
    path = tmp_path / "abandoned.mcap"
    with pytest.raises(type(exc)), TraceWriter(path, make_meta()) as w:
        for k in range(12):
            w.step(k * DT, states_at(k * DT), joints_at(k * DT), [], {})
        raise exc
    assert not path.with_name("abandoned.mcap.partial").exists()
    trace = read_trace(path)  # not recover: the file is finished
    assert trace.complete and trace.status == status
    assert trace.summary["error"].startswith(type(exc).__name__)
    assert len(trace.times) == 12 and trace.times[-1] == pytest.approx(11 * DT)
    if isinstance(exc, EngineFailure):
        assert (trace.summary["body"], trace.summary["time"]) == ("box", 0.44)


def test_truncated_trace_is_recovered_up_to_its_last_complete_chunk(tmp_path: Path) -> None:
    path = tmp_path / "full.mcap"
    write_trace(path, steps=100, flush_interval=0.2)
    data = path.read_bytes()
    with open(path, "rb") as f:
        chunks = sorted(make_reader(f).get_summary().chunk_indexes, key=lambda c: c.chunk_start_offset)
    assert len(chunks) >= 15
    middle = chunks[len(chunks) // 2]
    cut = middle.chunk_start_offset + middle.chunk_length // 2  # the middle of the file, inside a chunk
    whole = [c for c in chunks if c.chunk_start_offset + c.chunk_length <= cut]
    assert len(whole) == len(chunks) // 2
    last_ns = whole[-1].message_end_time
    cut_path = tmp_path / "cut.mcap"
    cut_path.write_bytes(data[:cut])

    with pytest.raises(TraceReadError, match="recover"):
        read_trace(cut_path)
    trace = read_trace(cut_path, recover=True)
    full = read_trace(path)
    expected = [t for t in full.times if round(t * 1e9) <= last_ns]
    assert trace.recovered and not trace.complete and trace.status == tf.STATUS_INCOMPLETE
    assert trace.times.tolist() == expected and len(expected) < len(full.times)
    n = len(expected)
    np.testing.assert_array_equal(trace.bodies["box"].pos, full.bodies["box"].pos[:n])
    assert trace.scenario == full.scenario and [a.name for a in trace.attachments] == ["unit.yaml", "sounds/thud.wav"]
    assert [e.name for e in trace.events] == ["box-into-door"]
    assert "unfinished" in summary_text(trace)


def test_hard_kill_leaves_a_partial_trace_readable_up_to_the_last_flush(tmp_path: Path) -> None:
    path = tmp_path / "killed.mcap"
    script = textwrap.dedent(f"""
        import sys, time
        sys.path.insert(0, {str(REPO)!r})
        sys.path.insert(0, {str(Path(__file__).parent)!r})
        from test_trace import make_meta, states_at, joints_at
        from runner.trace.writer import TraceWriter
        w = TraceWriter({str(path)!r}, make_meta(), flush_interval=0.25)
        for k in range(31):  # t = 0 .. 1.2; chunks close after t = 0.28, 0.52, 0.76, 1.0
            w.step(k * 0.04, states_at(k * 0.04), joints_at(k * 0.04), [], {{}})
        print("ready", flush=True)
        time.sleep(60)
    """)
    child = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True, cwd=REPO)
    try:
        assert child.stdout is not None and child.stdout.readline().strip() == "ready"
    finally:
        child.send_signal(signal.SIGKILL)
        child.wait(timeout=30)
    assert child.returncode == -signal.SIGKILL
    assert not path.exists() and path.with_name("killed.mcap.partial").exists()
    trace = read_trace(path, recover=True)  # finds the .partial
    assert trace.path.name == "killed.mcap.partial" and trace.status == tf.STATUS_INCOMPLETE
    assert as_ns(trace.times) == [round(k * 0.04 * 1e9) for k in range(26)]
    assert trace.bodies["box"].pos[-1, 2] == pytest.approx(Z0 - 0.5 * G * 1.0, abs=RES)


@pytest.mark.parametrize("recover", [False, True])
def test_reader_refuses_what_is_not_a_trace(tmp_path: Path, trace_file: Path, recover: bool) -> None:
    cases = {
        "empty.mcap": b"",
        "text.mcap": b"scenario: not a trace\n" * 20,
        "head.mcap": trace_file.read_bytes()[:100],
    }
    for name, data in cases.items():
        (tmp_path / name).write_bytes(data)
        with pytest.raises(TraceReadError, match=name):
            read_trace(tmp_path / name, recover=recover)
    with pytest.raises(TraceReadError, match="does not exist"):
        read_trace(tmp_path / "missing.mcap", recover=recover)


def test_reader_arrays_series_and_records(trace_file: Path) -> None:
    trace = read_trace(trace_file)
    assert trace.complete and not trace.recovered and trace.status == tf.STATUS_FAILED
    assert (trace.start_time, trace.end_time) == (0.0, pytest.approx(49 * DT))
    assert trace.channels["/tf"].count == 50 and trace.channels["/scene"].count == 2
    assert trace.channels["/log"].schema == "foxglove.Log" and trace.channels["/log"].count == 6
    t, z = trace.series("box.pos.z")
    np.testing.assert_allclose(z, Z0 - 0.5 * G * t**2, atol=RES)
    _, w = trace.series("box.angvel.z")
    assert set(w.tolist()) == {0.7}
    _, pos = trace.series("slider.position")
    np.testing.assert_allclose(pos, 0.3 * trace.joint_times, atol=RES)
    _, door_open = trace.series("state.door_open")
    assert door_open.sum() == 40
    assert [(s.name, s.action, s.volume) for s in trace.sounds] == [("thud", "start", 0.8), ("thud", "stop", 1.0)]
    assert [(v.name, v.passed) for v in trace.verdicts] == [("lands", True), ("never-bounces", False)]
    assert trace.verdicts[1].data["measured"] is None  # inf -> null
    assert [(lg.level, lg.name) for lg in trace.logs if lg.name == "handler"] == [("warning", "handler")]
    touching = dict(trace.contacts)
    assert len(touching) == 50 and touching[7 * DT][1] == {
        "a": "box", "b": "door", "points": 1, "depth": 0.002, "normal_force": None,
    }  # fmt: skip
    assert trace.attachment("unit.yaml") == YAML
    with pytest.raises(KeyError):
        trace.series("box.pos.w")


def test_inspect_summary_names_what_ran_and_how_it_ended(trace_file: Path) -> None:
    text = summary_text(read_trace(trace_file), width=120)
    for expected in ("unit", "fall", "fake 1.2.3", "failed", "50 (0 s to 1.96 s)", "foxglove.FrameTransforms",
                     "box-into-door", "lands", "never-bounces", "FAIL", "unit.yaml", "audio/wav"):  # fmt: skip
        assert expected in text, expected
    assert "unfinished" not in text


def test_step_template_fast_and_fallback_paths_agree() -> None:
    tf_tpl, bodies_tpl, _ = fx.step_templates(["a", 'q"uote%'], [])
    rng = np.random.default_rng(7)
    values = rng.normal(scale=100.0, size=26)
    fast = json.loads(bodies_tpl.render(values))
    big = values.copy()
    big[0] = 3e9  # beyond the int64 fast path: repr for the whole message
    slow = json.loads(bodies_tpl.render(big))
    assert list(fast) == ["a", 'q"uote%'] and slow["a"]["pos"]["x"] == 3e9
    flat_fast = [fast[b][f][k] for b in fast for f in fast[b] for k in fast[b][f]]
    flat_slow = [slow[b][f][k] for b in slow for f in slow[b] for k in slow[b][f]]
    np.testing.assert_allclose(flat_fast, values, rtol=0, atol=RES / 2 + 1e-13)
    assert flat_slow[1:] == values[1:].tolist()  # the fallback is exact
    frames = json.loads(tf_tpl.render(values[:14], '{"sec":3,"nsec":5}'))["transforms"]
    assert [f["timestamp"] for f in frames] == [{"sec": 3, "nsec": 5}] * 2
