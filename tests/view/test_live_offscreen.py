"""`scenario view` without a display: ``--offscreen --script`` (software renderer, inputs from a file),
and the clear refusals (no display, no Panda3D, a variant that exists, a bad script): exit 2, one line,
no traceback, nothing written.

The scripted run plays space at 1.2 s and mouse1 at 2.4 s on the lab's physics scene, takes a picture
from the window at 2.0 s (the box on the door) and 2.6 s (up again) and closes at 3 s (the rest of the
run goes on headless); its trace
equals the recorded variant's headless trace step for step. A replayed trace plays and pauses by script.
About 15 s.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
from PIL import Image

from reports.trace_reader import read_trace
from runner.language.load import load_scenario
from tests.view.conftest import FACTORY, assert_same_run, copy_scenario, need_panda3d, quiet_env, scenario
from tests.view.pictures import BOX, DOOR, centroid

SCRIPT = """\
- {at: 1.2, event: space}
- {at: 1.2, event: space-up}
- {at: 1.2, event: f1}
- {at: 2.0, screenshot: %(dir)s/a.png}
- {at: 2.4, event: mouse1}
- {at: 2.6, screenshot: %(dir)s/b.png}
- {at: 3.0, close: true}
"""


def test_a_scripted_run_is_recorded_and_replays_headless(tmp_path: Path) -> None:
    need_panda3d()
    path = copy_scenario(FACTORY, tmp_path)
    script = tmp_path / "script.yaml"
    script.write_text(SCRIPT % {"dir": tmp_path})
    done = scenario("view", str(path), "--record", "played", "--offscreen", "--script", str(script),
                    "--out", str(tmp_path / "live"), env=quiet_env())  # fmt: skip
    assert done.returncode in (0, 1), done.stderr
    assert "Traceback" not in done.stderr
    assert "recorded variant `played`" in done.stdout
    inputs = [(i.at, i.event) for i in load_scenario(path, "played").model.inputs]
    assert inputs == [(1.2, "space"), (2.4, "mouse1")]  # space-up is no event of the scenario; f1 is the viewer's
    live = read_trace(tmp_path / "live" / "factory-physics__played__pybullet.mcap")
    assert live.times[-1] == 6.0  # closed at 3 s, the run went on to its end
    headless = scenario("run", str(path), "--variant", "played", "--out", str(tmp_path / "run"), "--quiet")
    assert headless.returncode == done.returncode
    assert_same_run(live, read_trace(tmp_path / "run" / "factory-physics__played__pybullet.mcap"))
    a, b = (np.asarray(Image.open(tmp_path / n).convert("RGB")) for n in ("a.png", "b.png"))
    assert a.shape == b.shape == (720, 960, 3)
    for image in (a, b):
        assert centroid(image, BOX)[2] > 50 and centroid(image, DOOR)[2] > 500
    assert centroid(b, BOX)[1] < centroid(a, BOX)[1] - 20  # reset at 2.4 s: up again at 2.6 s


def _refused(done, words: str) -> None:  # noqa: ANN001
    assert done.returncode == 2, (done.stdout, done.stderr)
    assert words in done.stderr and "Traceback" not in done.stderr


def test_without_a_display_it_says_so(tmp_path: Path) -> None:
    path = copy_scenario(FACTORY, tmp_path)
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    done = scenario("view", str(path), "--record", "played", "--out", str(tmp_path / "out"), env=quiet_env())
    _refused(done, "needs a display")
    assert "xvfb-run" in done.stderr
    assert hashlib.sha256(path.read_bytes()).hexdigest() == digest and not (tmp_path / "out").exists()


def test_bad_requests_are_refused_before_the_window_opens(tmp_path: Path) -> None:
    path = copy_scenario(FACTORY, tmp_path)
    _refused(scenario("view", str(path), "--record", "door-stays-closed", "--offscreen", env=quiet_env()),
             "variant `door-stays-closed` already exists")  # fmt: skip
    bad = tmp_path / "bad.yaml"
    bad.write_text("- {at: 1, kick: space}\n")
    _refused(scenario("view", str(path), "--offscreen", "--script", str(bad), env=quiet_env()), "unknown key `kick`")
    _refused(scenario("view", str(path), "--speed", "0", env=quiet_env()), "--speed")
    _refused(scenario("view", str(path), "--variant", "nope", "--offscreen", env=quiet_env()), "unknown variant")
    _refused(scenario("view", str(path), "--set", "params.nope=1", "--offscreen", env=quiet_env()), "params.nope")
    trace = tmp_path / "x.mcap"
    trace.write_bytes(b"not a trace")
    _refused(scenario("view", str(trace), "--offscreen", env=quiet_env()), "cannot read the trace")
    _refused(scenario("view", str(path), str(trace), env=quiet_env()), "not both")
    _refused(scenario("view", str(trace), "--set", "world.dt=0.01", env=quiet_env()), "--set apply to a scenario")


def test_without_panda3d_the_hint_names_the_extra(tmp_path: Path) -> None:
    """Panda3D hidden from the child (a module that fails to import), as on an install without the extra."""
    blocker = tmp_path / "block"
    (blocker / "panda3d").mkdir(parents=True)
    (blocker / "panda3d" / "__init__.py").write_text("raise ImportError('hidden by the test')\n")
    env = quiet_env(PYTHONPATH=str(blocker))
    done = scenario("view", str(FACTORY), "--offscreen", env=env)
    _refused(done, "pip install 'physics-scenarios[view]'")


def test_a_replay_plays_and_pauses_by_script(tmp_path: Path) -> None:
    """`scenario view TRACE --paused` with space at 0.5 s and 1.5 s of wall time: the replay played for 1 s
    (x1: one simulated second per second; it used to advance one frame and fall back paused). The bound
    above allows the second key's frame to be 0.25 s late on a loaded machine (docs/view.md)."""
    need_panda3d()
    variant = "door-opens-with-the-box-on-it"
    assert scenario("run", str(FACTORY), "--variant", variant, "--out", str(tmp_path), "--quiet").returncode == 0
    trace = tmp_path / f"factory-physics__{variant}__pybullet.mcap"
    script = tmp_path / "script.yaml"
    script.write_text("- {after: 0.5, event: space}\n- {after: 1.5, event: space}\n- {after: 2.0, close: true}\n")
    done = scenario("view", str(trace), "--paused", "--offscreen", "--script", str(script), env=quiet_env())
    assert done.returncode == 0, done.stderr
    t, _, mode = done.stdout.strip().splitlines()[-1].removeprefix("replay closed at t = ").partition(" s (")
    assert mode == "paused)" and 0.5 <= float(t) <= 1.25, done.stdout
    script.write_text("- {after: 1.0, close: true}\n")  # without --paused it plays by itself
    done = scenario("view", str(trace), "--offscreen", "--script", str(script), env=quiet_env())
    assert done.returncode == 0, done.stderr
    t, _, mode = done.stdout.strip().splitlines()[-1].removeprefix("replay closed at t = ").partition(" s (")
    assert mode == "playing)" and float(t) >= 0.5, done.stdout


#: kuka_iiwa/model.urdf's Blue and Orange materials; link 7 painted red by robots/kuka_arm.yaml
KUKA_COLOURS = {"blue": (0.5, 0.7, 1.0), "orange": (1.0, 0.423529411765, 0.0392156862745), "red": (0.9, 0.2, 0.2)}
PATCH = 25  # pixels: a colour counts as drawn when it covers at least a 5 x 5 patch


def test_a_robot_is_drawn_by_its_visual_meshes(tmp_path: Path) -> None:
    """`scenario view` of the KUKA arm shows the URDF's <visual> meshes in their materials' colours."""
    need_panda3d()
    script = tmp_path / "script.yaml"
    script.write_text(f"- {{at: 1.0, screenshot: {tmp_path}/arm.png}}\n- {{at: 1.1, close: true}}\n")
    arm = FACTORY.parent / "robots" / "kuka_arm.yaml"
    done = scenario("view", str(arm), "--offscreen", "--script", str(script), "--camera", "auto",
                    "--out", str(tmp_path / "live"), env=quiet_env())  # fmt: skip
    assert done.returncode == 0, done.stderr
    image = np.asarray(Image.open(tmp_path / "arm.png").convert("RGB"))
    for name, rgb in KUKA_COLOURS.items():
        assert centroid(image, rgb)[2] >= PATCH, name
