"""Contact points as arrows (``trace: {contact_points: true}``): /contact_points in the MCAP (read back with the
mcap reader and Foxglove's own SceneUpdate class) and ``/world/contact_points`` Arrows3D in the ``.rrd``
(rerun-sdk's RrdReader), for the lab's box resting on the ground on every engine; a scenario that does not ask
has no such channel."""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from foxglove_schemas_protobuf.SceneUpdate_pb2 import SceneUpdate
from mcap.reader import make_reader

from backends.registry import is_installed, list_backends
from backends.testing.tolerances import deviation, tol
from reports import trace_format as tf
from reports.rerun_contacts import ENTITY, read_arrows
from reports.trace_reader import read_trace
from runner.trace.contact_arrows import ARROW_LENGTH, KEY_SCALE
from tests.paths import ROOT

SCENARIO = ROOT / "tests" / "trace" / "data" / "contact_points.yaml"
ENGINES = [e.name for e in list_backends() if is_installed(e.name) and not e.opt_in]
RERUN = importlib.util.find_spec("rerun") is not None
HALF = 0.15
#: a corner's x and y, and a point's height: within the resting depth of the box (tests/backends/tolerances.py,
#: "resting_height": 2 mm)
CORNER = 2e-3


def _run(path: Path, backend: str, out: Path, *extra: str) -> Path:
    done = subprocess.run([sys.executable, "-m", "runner", "run", str(path), "--backend", backend, "--out", str(out),
                           "--quiet", *extra], cwd=ROOT, capture_output=True, text=True, timeout=300,
                          env={**os.environ, "RERUN_ANALYTICS": "0"})  # fmt: skip
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    (trace,) = out.glob("*.mcap")
    return trace


@pytest.mark.parametrize("backend", ENGINES)
def test_resting_box_arrows_in_mcap_and_rrd(backend: str, tmp_path: Path, request: pytest.FixtureRequest) -> None:
    reason = deviation("test_resting_box_arrows_in_mcap_and_rrd", "", backend)  # the 4 corners: drake's differ
    if reason is not None:
        request.applymarker(pytest.mark.xfail(strict=True, reason=f"{backend}: {reason}"))
    extra = ("--rerun",) if RERUN else ()
    path = _run(SCENARIO, backend, tmp_path, *extra, *(("--trace-process",) if backend == "ode" else ()))
    trace = read_trace(path)
    assert trace.channels[tf.TOPIC_CONTACT_POINTS].schema == "foxglove.SceneUpdate"
    scale = float(trace.scenario[KEY_SCALE])
    weight = 13.5 * 9.81  # 0.3^3 m^3 at 500 kg/m^3, the only moving body: its weight is ARROW_LENGTH long
    assert scale == pytest.approx(ARROW_LENGTH / weight, rel=1e-12)
    with open(path, "rb") as f:
        messages = list(make_reader(f).iter_messages(topics=[tf.TOPIC_CONTACT_POINTS], log_time_order=True))
    with open(path, "rb") as f:
        pair_steps = sum(1 for _ in make_reader(f).iter_messages(topics=[tf.TOPIC_CONTACTS]))
    assert len(messages) == pair_steps == 101  # every recorded step: t = 0, 0.01, ..., 1 (at rest, as the
    # backends' resting force test: tests/backends/test_backend_contract.py)
    first, last = (SceneUpdate.FromString(m[2].data) for m in (messages[0], messages[-1]))
    assert [len(e.arrows) for e in first.entities] == [0]  # t = 0: no step taken, no contact yet
    (entity,) = last.entities
    assert entity.frame_id == tf.WORLD_FRAME and {k.key: k.value for k in entity.metadata}[KEY_SCALE] == repr(scale)
    assert len(entity.arrows) == 4
    corners = sorted((round(np.sign(a.pose.position.x)), round(np.sign(a.pose.position.y))) for a in entity.arrows)
    assert corners == [(-1, -1), (-1, 1), (1, -1), (1, 1)]
    arrows = read_arrows(path)
    # no arrow at t = 0; then at most the 4 corners (a point whose force is 0 has no arrow: dart's first step)
    assert arrows is not None and arrows.counts[0] == 0 and arrows.counts[-1] == 4 and max(arrows.counts) == 4
    origins, vectors = arrows.origins[-4:], arrows.vectors[-4:]
    assert np.abs(origins[:, :2]) == pytest.approx(np.full((4, 2), HALF), abs=CORNER)
    assert origins[:, 2] == pytest.approx(np.zeros(4), abs=CORNER)
    # up (the force on the box, body b), unit direction within float64 rounding of the quaternion (1e-12)
    assert vectors[:, :2] == pytest.approx(np.zeros((4, 2)), abs=1e-12)
    # the lengths sum to the weight times the scale, as the forces sum to m g (tolerance "contact_force")
    assert vectors[:, 2].sum() == pytest.approx(ARROW_LENGTH, rel=tol("contact_force", backend))
    if RERUN:
        _check_rrd(path.with_suffix(".rrd"), vectors, arrows.counts.tolist())


def _check_rrd(rrd: Path, vectors: np.ndarray, arrows_per_step: list[int]) -> None:
    from rerun.chunk import RrdReader

    rows: list[list[list[float]]] = []
    for chunk in RrdReader(rrd).stream().to_chunks():
        batch = chunk.to_record_batch()
        if "Arrows3D:vectors" in batch.schema.names:
            rows += [v or [] for v in batch.column("Arrows3D:vectors").to_pylist()]
    assert [len(r) for r in rows] == arrows_per_step, ENTITY
    # rerun stores float32 vectors: within 2^-24 relative of the trace's
    assert np.array(rows[-1]) == pytest.approx(vectors, rel=2**-23, abs=1e-9)


def test_no_channel_unless_asked(tmp_path: Path) -> None:
    plain = tmp_path / "plain.yaml"
    plain.write_text(SCENARIO.read_text().replace("trace: {contact_points: true}\n", ""))
    trace = read_trace(_run(plain, "pybullet", tmp_path / "out"))
    assert tf.TOPIC_CONTACT_POINTS not in trace.channels and KEY_SCALE not in trace.scenario


def test_own_scale(tmp_path: Path) -> None:
    scaled = tmp_path / "scaled.yaml"
    own = "{contact_points: true, contact_arrow_scale: 0.001}"
    scaled.write_text(SCENARIO.read_text().replace("{contact_points: true}", own))
    path = _run(scaled, "mujoco", tmp_path / "out")
    arrows = read_arrows(path)
    assert float(read_trace(path).scenario[KEY_SCALE]) == 0.001
    assert arrows is not None
    assert arrows.vectors[-4:, 2].sum() == pytest.approx(0.001 * 13.5 * 9.81, rel=tol("contact_force", "mujoco"))


def test_the_reports_pictures_draw_the_arrows(tmp_path: Path) -> None:
    """The report's scene (reports.scene3d) reads /contact_points: at the end the 4 arrows, as long as the trace
    draws them, and Panda3D's software renderer shows their colour where its lens puts their middles."""
    pytest.importorskip("panda3d.core", reason="engine not installed: panda3d (the ode extra)")
    from reports.scene3d import frame_camera, scene_model
    from reports.scene3d.offscreen import OffscreenRenderer
    from reports.scene3d.panda import PandaScene
    from runner.trace.contact_arrows import ARROW_RGBA, ENTITY_ID
    from tests.view.pictures import found_near

    path = _run(SCENARIO, "pybullet", tmp_path)
    model = scene_model(read_trace(path))
    arrows = model.entities_at(model.end_time)[ENTITY_ID].primitives
    drawn = read_arrows(path)
    assert drawn is not None and len(arrows) == 4
    assert sorted(a.size[0] for a in arrows) == pytest.approx(sorted(np.linalg.norm(drawn.vectors[-4:], axis=1)))
    renderer = OffscreenRenderer(400, 300)
    scene = PandaScene(model)
    camera = frame_camera([model])
    scene.show(model.end_time)
    image = np.asarray(renderer.render(scene, camera))
    middles = (drawn.origins[-4:] + 0.5 * drawn.vectors[-4:]).tolist()
    seen = [found_near(image, px, ARROW_RGBA[:3]) for px in renderer.project(scene, camera, middles)]
    assert sum(seen) >= 2, seen  # each arrow runs up a vertical edge of the box: the far ones may be hidden by it
    renderer.close()
