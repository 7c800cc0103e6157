"""The MCAP trace: writer (runner/trace/writer.py), reader and inspect (reports/), read back with `mcap` itself
and Foxglove's own protobuf decoder (mcap-protobuf-support), which builds the message classes from the
schema records in the file: an outside reader, not ours."""

from __future__ import annotations

import io
import json
import math
import signal
import subprocess
import sys
import textwrap
import wave
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from foxglove_schemas_protobuf.FrameTransforms_pb2 import FrameTransforms
from foxglove_schemas_protobuf.Log_pb2 import Log
from foxglove_schemas_protobuf.SceneUpdate_pb2 import SceneUpdate
from google.protobuf.descriptor_pb2 import FileDescriptorSet
from mcap.reader import make_reader
from mcap.writer import Writer
from mcap_protobuf.decoder import DecoderFactory

from backends import types as bt
from backends.errors import EngineFailure
from reports import trace_format as tf
from reports.inspect import summary_text
from reports.trace_reader import TraceReadError, read_trace
from runner.errors import TraceError
from runner.trace import foxglove as fx
from runner.trace import output
from runner.trace import scene as sc
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


def mcap_messages(path: Path) -> list[tuple[str, str, int, Any]]:
    """[(topic, schema name, log time, decoded protobuf message)] in file order: mcap's seeking reader and
    mcap-protobuf's decoder, with classes built from the file's own schema records."""
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        messages = reader.iter_decoded_messages(log_time_order=False)
        return [(c.topic, s.name if s is not None else "", m.log_time, d) for s, c, m, d in messages]


def as_ns(times: np.ndarray) -> list[int]:
    return [round(t * 1e9) for t in times.tolist()]


@pytest.fixture
def trace_file(tmp_path: Path) -> Path:
    path = tmp_path / "unit.mcap"
    write_trace(path)
    return path


def test_round_trip_with_the_mcap_reader(trace_file: Path) -> None:
    with open(trace_file, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        assert summary is not None and reader.get_header().library.startswith(tf.SDK_LIBRARY)
        schema_of = {ch.topic: summary.schemas[ch.schema_id] for ch in summary.channels.values()}
        for ch in summary.channels.values():
            assert (ch.message_encoding, schema_of[ch.topic].encoding) == ("protobuf", "protobuf")
        assert schema_of["/tf"].name == "foxglove.FrameTransforms"
        assert schema_of["/scene"].name == "foxglove.SceneUpdate"
        assert schema_of["/log"].name == "foxglove.Log"
        # the SDK's writer records a channel with its first message: the topics listed are those that carry any
        assert set(schema_of) == {topic for topic, *_ in mcap_messages(trace_file)}
        assert {c.compression for c in summary.chunk_indexes} == {"zstd"}
        meta = {m.name: m.metadata for m in reader.iter_metadata()}
        attachments = {a.name: (a.media_type, a.data, a.log_time) for a in reader.iter_attachments()}
    scenario = meta[tf.METADATA_SCENARIO]
    assert scenario[tf.KEY_NAME] == "unit" and scenario[tf.KEY_VARIANT] == "fall"
    assert scenario[tf.KEY_TRACE_FORMAT] == str(tf.TRACE_FORMAT_VERSION) == "2"
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
    box = msg.transforms[1]
    assert (box.timestamp.seconds, box.timestamp.nanos) == (ns // 10**9, ns % 10**9)
    assert (box.parent_frame_id, box.child_frame_id) == ("world", "box")
    assert box.translation.z == pytest.approx(Z0 - 0.5 * G * t * t, abs=RES)
    assert box.rotation.w == pytest.approx(math.cos(0.35 * t), abs=RES)
    assert box.rotation.z == pytest.approx(math.sin(0.35 * t), abs=RES)
    assert msg.transforms[2].translation.x == pytest.approx(1 + 0.3 * t, abs=RES)
    bodies = [m for topic, _, ns, m in messages if topic == "/bodies"]
    assert bodies[30].box.vel.z == pytest.approx(-G * t, abs=RES)
    assert bodies[30].box.angvel.z == 0.7 and bodies[30].door.vel.x == 0.3
    assert [f.name for f in type(bodies[30]).DESCRIPTOR.fields] == ["floor", "box", "door"]
    joints = [m for topic, _, _, m in messages if topic == "/joints"]
    slider = joints[30].slider
    assert (slider.position, slider.velocity, slider.motor_force) == (pytest.approx(0.3 * t, abs=RES), 0.3, -12.5)
    state = [m for topic, _, _, m in messages if topic == "/state"]
    assert (state[9].door_open, state[10].door_open, state[12].count) == (False, True, 12.0)
    logs = [(ns, m) for topic, _, ns, m in messages if topic == "/log"]
    event_ns = round(10 * DT * 1e9)
    event_logs = [(ns, m) for ns, m in logs if m.name == tf.LOGGER_EVENT]
    assert [m.level for _, m in event_logs] == [Log.INFO]
    assert event_logs[0][1].message == 'box-into-door (collision) {"into":"lid"}'
    assert (event_logs[0][0], event_logs[0][1].timestamp.nanos) == (event_ns, event_ns)
    verdict_logs = [m for _, m in logs if m.name == tf.LOGGER_VERDICT]
    assert [(m.level, m.message) for m in verdict_logs] == [(Log.ERROR, "1/2 assertions passed; failed: never-bounces")]
    assert [(m.time, m.name, m.source, [(d.key, d.value) for d in m.detail])
            for topic, _, _, m in messages if topic == "/events"] == [
        (10 * DT, "box-into-door", "collision", [("into", '"lid"')])
    ]  # fmt: skip
    sounds = [(m.name, m.action, m.volume) for topic, _, _, m in messages if topic == "/sounds"]
    assert sounds == [("thud", "start", pytest.approx(0.8)), ("thud", "stop", 1.0)]


def test_scene_entities_are_frame_locked_body_shapes_and_translucent_solids(trace_file: Path) -> None:
    messages = mcap_messages(trace_file)
    scenes = [(ns, m) for topic, _, ns, m in messages if topic == "/scene"]
    assert [ns for ns, _ in scenes] == [0, round(20 * DT * 1e9)]
    first = {e.id: e for e in scenes[0][1].entities}
    assert set(first) == {"body/floor", "body/box", "body/door", "solid/box/ball", "solid/door/lid", "joint/slider"}
    box = first["body/box"]
    assert (box.frame_id, box.frame_locked, box.lifetime.seconds, box.lifetime.nanos) == ("box", True, 0, 0)
    assert box.HasField("lifetime")
    cube = box.cubes[0]
    assert (cube.size.x, cube.size.y, cube.size.z) == (0.3, 0.2, 0.1)
    assert (cube.color.r, cube.color.g, cube.color.b, cube.color.a) == (0.9, 0.2, 0.1, 1.0)
    floor = first["body/floor"].cubes[0]
    assert floor.size.z == fx.PLANE_THICKNESS and floor.size.x >= 20
    assert floor.pose.position.z + floor.size.z / 2 == pytest.approx(0.0)  # top face = the plane
    (grid,) = first["body/floor"].lines  # 1 m apart over the plane's width, both ways, just above it
    assert len(grid.points) == 2 * 2 * (int(floor.size.x) + 1) and {p.z for p in grid.points} == {sc.GRID_LIFT}
    ball = first["solid/box/ball"].spheres[0]
    assert (ball.size.x, ball.size.y, ball.size.z) == (0.9, 0.9, 0.9) and ball.color.a < 1
    lid = first["solid/door/lid"]
    assert len(lid.triangles[0].points) == 2 * 2 * 3  # both faces of 2 triangles
    assert len(lid.lines[0].points) == 4
    rescaled = {e.id: e for e in scenes[1][1].entities}
    size = rescaled["body/box"].cubes[0].size
    assert (size.x, size.y, size.z) == (0.6, 0.4, 0.2)
    assert "joint/slider" not in rescaled  # the joints are drawn once, frame-locked to their body


def test_foxglove_channels_carry_foxglove_s_own_schemas(trace_file: Path) -> None:
    """/tf, /scene and /log carry the exact files of foxglove-schemas-protobuf (Foxglove and Rerun recognise
    them by name and read them by these descriptors)."""
    with open(trace_file, "rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None
    schemas = {ch.topic: summary.schemas[ch.schema_id] for ch in summary.channels.values()}
    for topic, cls in (("/tf", FrameTransforms), ("/scene", SceneUpdate), ("/log", Log)):
        files = {fd.name: fd for fd in FileDescriptorSet.FromString(schemas[topic].data).file}
        assert cls.DESCRIPTOR.file.name in files
        official = FileDescriptorSet()
        cls.DESCRIPTOR.file.CopyToProto(official.file.add())
        assert files[cls.DESCRIPTOR.file.name] == official.file[0]
    messages = mcap_messages(trace_file)  # every message decodes with its channel's schema
    assert {topic for topic, *_ in messages} == set(schemas) - {"/audio"}


def test_non_finite_values_are_written_as_they_are_and_read_back(tmp_path: Path) -> None:
    with TraceWriter(tmp_path / "nan.mcap", make_meta()) as w:
        s = states_at(0.0)
        s.pos[1, 2] = np.nan
        s.lin_vel[2, 0] = np.inf
        w.step(0.0, s, bt.JointStates(np.array([np.nan]), np.array([0.0]), np.array([2e9])), [], {"count": math.nan})
        path = w.finish(tf.STATUS_ENGINE_FAILURE, {"error": "NaN", "last": math.inf})
    messages = mcap_messages(path)
    pose = next(m for topic, _, _, m in messages if topic == "/tf").transforms[1].translation
    assert pose.x == 1.0 and math.isnan(pose.z)
    bodies = next(m for topic, _, _, m in messages if topic == "/bodies")
    assert bodies.door.vel.x == math.inf
    joints = next(m for topic, _, _, m in messages if topic == "/joints")
    assert math.isnan(joints.slider.position) and joints.slider.motor_force == 2e9  # exact
    trace = read_trace(path)
    assert math.isnan(trace.bodies["box"].pos[0, 2]) and trace.bodies["box"].pos[0, 0] == 1.0
    assert trace.summary == {"error": "NaN", "last": None}  # metadata stays JSON: null
    assert math.isnan(trace.series("state.count")[1][0])


def test_values_are_rounded_to_the_resolution_the_reader_gets_exactly(tmp_path: Path) -> None:
    """Doubles rounded to 1e-9 read back as the nearest double to the decimal n * 1e-9, as format 1 gave."""
    rng = np.random.default_rng(3)
    raw = rng.normal(scale=5.0, size=(3, 3))
    with TraceWriter(tmp_path / "q.mcap", make_meta()) as w:
        s = states_at(0.0)
        s.pos[:] = raw
        w.step(0.0, s, joints_at(0.0), [], {})
        path = w.finish(tf.STATUS_PASSED, {})
    trace = read_trace(path)
    got = np.array([trace.bodies[n].pos[0] for n in ("floor", "box", "door")])
    expected = np.array([[float(f"{round(v * 1e9)}e-9") for v in row] for row in raw])
    np.testing.assert_array_equal(got, expected)


def test_a_trace_of_the_previous_format_is_refused_with_its_version(tmp_path: Path) -> None:
    path = tmp_path / "old.mcap"
    with open(path, "wb") as f:
        w = Writer(f)
        w.start(profile="", library=tf.LIBRARY)
        sid = w.register_schema("foxglove.FrameTransforms", "jsonschema", b'{"type":"object"}')
        ch = w.register_channel("/tf", "json", sid)
        w.add_metadata(tf.METADATA_SCENARIO, {tf.KEY_NAME: "old", tf.KEY_TRACE_FORMAT: "1"})
        w.add_message(ch, 0, b'{"transforms":[]}', 0)
        w.finish()
    with pytest.raises(TraceReadError, match=r"is in trace format 1 \(JSON .*\); .* reads trace format 2 only"):
        read_trace(path)


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
        summary = make_reader(f).get_summary()
    assert summary is not None
    chunks = sorted(summary.chunk_indexes, key=lambda c: c.chunk_start_offset)
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
    assert trace.channels["/log"].schema == "foxglove.Log" and trace.channels["/log"].count == 5
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
    assert trace.verdicts[1].data["measured"] == "inf" and trace.verdicts[1].data["time"] is None
    assert [(lg.level, lg.name) for lg in trace.logs if lg.name == "handler"] == [("warning", "handler")]
    touching = dict(trace.contacts)
    assert len(touching) == 50 and touching[0.0] == [
        {"a": "floor", "b": "door", "points": 4, "depth": 0.001, "normal_force": 3924.0}
    ]
    pair = touching[7 * DT][1]
    assert math.isnan(pair.pop("normal_force"))
    assert pair == {"a": "box", "b": "door", "points": 1, "depth": 0.002}
    assert trace.attachment("unit.yaml") == YAML
    with pytest.raises(KeyError):
        trace.series("box.pos.w")


def test_inspect_summary_names_what_ran_and_how_it_ended(trace_file: Path) -> None:
    text = summary_text(read_trace(trace_file), width=120)
    for expected in ("unit", "fall", "fake 1.2.3", "failed", "50 (0 s to 1.96 s)", "foxglove.FrameTransforms",
                     "box-into-door", "lands", "never-bounces", "FAIL", "unit.yaml", "audio/wav"):  # fmt: skip
        assert expected in text, expected
    assert "unfinished" not in text


def _wav(samples: np.ndarray, rate: int) -> bytes:
    buffer = io.BytesIO()
    with wave.open(buffer, "wb") as w:
        w.setnchannels(1)
        w.setsampwidth(2)
        w.setframerate(rate)
        w.writeframes(samples.astype("<i2").tobytes())
    return buffer.getvalue()


def test_sounds_are_also_raw_audio_from_their_offset_at_their_volume(tmp_path: Path) -> None:
    rate = 8000
    samples = (np.arange(4000) % 200 * 100 - 10000).astype(np.int16)
    with TraceWriter(tmp_path / "audio.mcap", make_meta()) as w:
        w.attach("sounds/beep.wav", _wav(samples, rate), "audio/wav")
        w.attach("sounds/broken.wav", b"RIFF not a wav", "audio/wav")
        w.sound(0.5, "beep", "start", 0.25, 0.5)
        w.sound(0.6, "broken", "start")
        w.sound(0.7, "beep", "stop")
        path = w.finish(tf.STATUS_PASSED, {})
    audio = [(ns, m) for topic, _, ns, m in mcap_messages(path) if topic == "/audio"]
    assert len(audio) == 1
    ns, msg = audio[0]
    assert ns == 500_000_000 and (msg.timestamp.seconds, msg.timestamp.nanos) == (0, ns)
    assert (msg.format, msg.sample_rate, msg.number_of_channels) == ("pcm-s16", rate, 1)
    got = np.frombuffer(msg.data, dtype="<i2")
    np.testing.assert_array_equal(got, np.rint(samples[2000:] * 0.5).astype(np.int16))


def test_a_verdict_is_logged_when_it_is_decided(tmp_path: Path) -> None:
    with TraceWriter(tmp_path / "v.mcap", make_meta()) as w:
        w.verdict(0.4, {"name": "kick", "passed": True, "measured": "2.57056", "expected": "2.57056 ± 0.001"})
        w.verdict(1.2, {"name": "rest", "passed": False, "measured": "false", "expected": "always true",
                        "message": "false at t=1.2000"})  # fmt: skip
        w.verdicts(2.0, [{"name": "kick", "passed": True}, {"name": "rest", "passed": False}])
        path = w.finish(tf.STATUS_FAILED, {})
    logs = [(lg.t, lg.level, lg.message) for lg in read_trace(path).logs]
    assert logs == [
        (0.4, "info", "PASS kick: measured 2.57056 (expected 2.57056 ± 0.001)"),
        (1.2, "error", "FAIL rest: measured false (expected always true); false at t=1.2000"),
        (2.0, "error", "1/2 assertions passed; failed: rest"),
    ]


def _ours_and_an_sdk_recording(tmp_path: Path) -> tuple[Path, Path]:
    """The tool's trace, and a user's own recording with the same SDK (one JSON message, no scenario record)."""
    import foxglove  # the writer's library, as a user would call it

    ours = tmp_path / "ours.mcap"
    write_trace(ours)
    theirs = tmp_path / "theirs.mcap"
    context = foxglove.Context()
    with foxglove.open_mcap(theirs, context=context):
        foxglove.Channel("/x", message_encoding="json", context=context).log(b"{}", log_time=1)
    return ours, theirs


def test_own_traces_are_told_from_other_sdk_recordings(tmp_path: Path) -> None:
    """The SDK names itself in the header, so a trace is the tool's by the scenario record that follows it: a
    user's own recording with the same SDK (messages, no scenario record) is never taken for one."""
    ours, theirs = _ours_and_an_sdk_recording(tmp_path)
    with open(theirs, "rb") as f:
        assert make_reader(f).get_header().library.startswith(tf.SDK_LIBRARY)
    assert output.is_own(ours, ours)
    assert not output.is_own(theirs, theirs)
    partial = tmp_path / ("cut.mcap" + tf.PARTIAL_SUFFIX)
    partial.write_bytes(ours.read_bytes()[:40])  # killed inside the header: still the tool's to replace
    assert output.is_own(partial, tmp_path / "cut.mcap")


def test_the_quick_look_at_a_trace_agrees_with_mcaps_reader(tmp_path: Path) -> None:
    """runner.trace.output reads a trace's header and scenario record by hand (mcap's reader is not imported at
    start-up); where it answers, it must answer as mcap's StreamReader does: on every prefix of the tool's
    trace and of a user's SDK recording (as a final and as a partial file), and with each byte of the first
    two records changed in turn."""
    ours, theirs = _ours_and_an_sdk_recording(tmp_path)
    probe, answered = tmp_path / "probe.mcap", 0

    def reading(path: Path) -> object:
        """mcap's reader's answer, or the class of what it raised (a damaged chunk's zstd error, as before)."""
        try:
            return output._own_trace_read(path)
        except Exception as exc:  # noqa: BLE001 - the same failure on both paths is agreement too
            return type(exc)

    def check(data: bytes, partial: bool) -> None:
        nonlocal answered
        path = probe.with_name(probe.name + tf.PARTIAL_SUFFIX) if partial else probe
        path.write_bytes(data)
        quick = output._own_trace_quick(path)
        if quick is not None:
            answered += 1
            assert quick == reading(path), (len(data), partial, data[:96])
        else:
            try:
                whole: object = output._own_trace(path)
            except Exception as exc:  # noqa: BLE001
                whole = type(exc)
            assert whole == reading(path)
        path.unlink()

    for whole in (ours.read_bytes(), theirs.read_bytes()):
        head = 8 + 9 + int.from_bytes(whole[9:17], "little")  # magic, then the header record
        head += 9 + int.from_bytes(whole[head + 1 : head + 9], "little")  # then the record after it
        for n in range(head + 64):
            check(whole[:n], partial=n % 2 == 1)
        for i in range(head):
            check(whole[:i] + bytes([whole[i] ^ 0x5A]) + whole[i + 1 :], partial=False)
    assert answered > 0  # the quick look did decide some of them: the comparison is not empty


def test_state_messages_reused_only_for_the_same_value_objects() -> None:
    """/state's bytes are reused while the step's values are the very objects of the last message; any other
    value, even an equal one of another type (1 and 1.0 in a text variable), is encoded afresh."""
    from runner.trace.encoder import TraceEncoder

    enc = TraceEncoder(["box"], [])
    enc.state_channel({"open": False, "count": 0.0, "label": "a"})
    one, other = 1, 1.0
    steps: list[dict[str, Any]] = [
        {"open": False, "count": 2.5, "label": "a"},
        {"open": True, "count": 2.5, "label": "a"},
        {"open": True, "count": -0.0, "label": one},
        {"open": True, "count": 0.0, "label": other},
    ]
    fresh = TraceEncoder(["box"], [])
    fresh.state_channel(steps[0])
    for values in steps:
        first = enc.state_message(values)
        assert enc.state_message(dict(values)) is first  # the same objects: the same bytes, not encoded again
        assert first == fresh._state_bytes(values)
    assert len({enc.state_message(v) for v in steps}) == 4  # -0.0 and 0.0, 1 and 1.0 give different messages
