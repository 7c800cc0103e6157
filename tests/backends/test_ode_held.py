"""ODE: bodies that sliders and fixed joints hold to the world get their rotational inertia raised (float32).

backends/ode/_held.py: such a body never turns, so its inertia enters none of its motion; ODE's single-precision
rows do see it, and pybullet_data's pusher (a 4e-10 kg target on two sliders) aborted ODE at its first step.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("panda3d.ode")
pytest.importorskip("pybullet_data")

from backends._kit.chains import chained  # noqa: E402
from backends.ode import OdeBackend  # noqa: E402
from backends.ode._held import FLOAT32_EPS, HELD_RADIUS, held_bodies  # noqa: E402
from backends.testing import worlds as w  # noqa: E402
from backends.types import JointKind, JointSpec  # noqa: E402
from runner.compile.program import build_program  # noqa: E402
from runner.language.load import load_scenario  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]


def _pusher(tmp_path: Path) -> Path:
    path = tmp_path / "pusher.yaml"
    path.write_text(
        "schema_version: 1\nscenario: pusher\nworld: {gravity: [0, 0, -9.81], dt: 0.002, duration: 0.5}\n"
        "bodies:\n  ground: {plane: {}, motion: static}\n"
        "robots:\n  model: {mjcf: '@pybullet_data/mjcf/pusher.xml', pos: [0, 0, 0.01]}\n"
    )
    return path


def test_held_bodies_are_the_slider_chains_to_the_world(tmp_path: Path) -> None:
    world = build_program(load_scenario(_pusher(tmp_path))).world
    engine = OdeBackend.engine_world(world)
    held = held_bodies(engine)
    # object and target: slide x then slide y from the world (the light body between them is held too);
    # every arm link turns on a hinge
    assert held == {
        "model.object", "model.target", "model.object (after joint model.object_x)",
        "model.target (after joint model.target_x)",
    }  # fmt: skip
    for name in held:
        assert all(j.kind is JointKind.SLIDER for j in engine.joints if j.body == name)
    before = {b.name: b for b in chained(world, OdeBackend.chain_light).bodies}  # the world before the raise
    for body in engine.bodies:
        old = before[body.name]
        if body.name in held:  # each principal moment at least m (1 m)^2, the mass unchanged
            assert min(old.inertia) < FLOAT32_EPS * 0.36  # 2^-23 of the arm's largest principal inertia: raised
            assert body.mass == old.mass
            assert body.inertia == tuple(max(i, old.mass * HELD_RADIUS**2) for i in old.inertia)
            assert min(old.inertia) < 1e-9  # the file's: 6.4e-13 kg m^2 (target), 1.5e-11 (object)
        else:
            assert body == old


def test_pusher_runs_on_ode(tmp_path: Path) -> None:
    """Before the raise, ODE aborted the process (signal 6, "bNormalizationResult" in _dNormalize4) at step 1,
    hence a process of its own."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    done = subprocess.run(
        [sys.executable, "-m", "runner", "run", str(_pusher(tmp_path)), "-b", "ode", "--out", str(tmp_path / "o")],
        capture_output=True, text=True, env=env, cwd=ROOT, timeout=300, check=False,
    )  # fmt: skip
    assert done.returncode == 0, done.stdout + done.stderr
    assert "1/1 runs passed" in done.stdout


def test_held_is_joined_to_the_world_by_sliders_and_fixed_joints_only() -> None:
    """A slider on the world holds its body, a fixed joint on that body holds the next; a slider on a hinged
    body does not (it turns with the hinge), nor does a body no joint moves (free) or a hinged one."""
    size = (0.1, 0.1, 0.1)
    bodies = [w.ground("floor"), *(w.box(n, size, (0.0, 0.0, 1.0)) for n in ("rail", "welded", "arm", "cart", "free"))]
    joints = (
        JointSpec("j1", JointKind.SLIDER, "rail", None),
        JointSpec("j2", JointKind.FIXED, "welded", "rail"),
        JointSpec("j3", JointKind.HINGE, "arm", "floor"),
        JointSpec("j4", JointKind.SLIDER, "cart", "arm"),
    )
    world = w.world("held", bodies, joints=joints)
    assert held_bodies(world) == {"rail", "welded"}
    # their 1.67e-3 kg m^2 is not below 2^-23 of the largest (the same): not raised (only pusher's kind is)
    assert OdeBackend.engine_world(world) == world
