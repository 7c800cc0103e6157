"""The energy watchdog (runner.sim.energy): energy from nowhere stops a run with exit 3; what the scenario
drives (motors, forces, resets) and what physics removes (restitution < 1) never trips it.

The pure-Python backend has no contacts; ``BouncingBackend`` adds the simplest one, a floor at z = 0 that
turns a falling ball's vertical velocity v into -e v (an impulse, as ODE's dContactBounce). With e < 1 the
impact removes (1 - e^2) of the ball's kinetic energy; with e = 2 it is the engine fault the watchdog is
for: it triples the kinetic energy at impact, K -> 4 K.

The ball (1 kg) falls from 1 m at dt = 0.01 s: it reaches the floor with K = m g h = 9.81 J (semi-implicit
Euler loses 1/2 m g^2 dt^2 per step, 4.8e-3 J per step, ~0.2 J over the 45 steps: K ~ 9.6 J). At e = 2 the
rise is 3 K ~ 29 J against the bound 0.25 K_peak + floor, where K_peak = 4 K ~ 38 J and the floor is
m g^2 dt (25 dt) = 0.24 J: 29 J > 9.9 J, so the watchdog fires at the first impact, t ~ 0.45 s.
"""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from backends.fake import FakeBackend
from backends.registry import entry, is_installed
from backends.types import BodyStates, JointStates
from runner.compile.program import build_program
from runner.errors import EnergyGain
from runner.exec.exits import classify
from runner.language.load import load_scenario
from runner.sim import run as run_module
from runner.sim.energy import GAIN_FRACTION, WINDOW_STEPS, EnergyWatch
from runner.sim.run import run_loaded
from runner.sim.session import RunResult, Session
from tests.paths import ROOT

G, DT, H0 = 9.81, 0.01, 1.0


class BouncingBackend(FakeBackend):
    """The fake backend with a floor at z = 0 that reverses a falling body's vertical velocity times
    ``restitution`` (the body's centre is its lowest point: a point mass)."""

    restitution = 0.5

    def _step(self) -> None:
        super()._step()
        for d in np.flatnonzero(self.moves):
            if self.pos[d, 2] < 0.0 and self.vel[d, 2] < 0.0:
                self.vel[d, 2] *= -self.restitution


def bouncing(e: float) -> type[BouncingBackend]:
    return type("Bouncing", (BouncingBackend,), {"restitution": e})


def run(tmp_path: Path, text: str, backend: type[FakeBackend], monkeypatch: pytest.MonkeyPatch) -> RunResult:
    path = tmp_path / "t.yaml"
    path.write_text(text)
    monkeypatch.setattr(run_module, "get_backend", lambda name: backend)
    return run_loaded(load_scenario(path, None), "fake", None)


DROP = f"""\
schema_version: 1
scenario: drop
world: {{gravity: [0, 0, -{G}], dt: {DT}, duration: 3}}
bodies:
  ball: {{sphere: 0.05, mass: 1, pos: [0, 0, {H0}]}}
"""


def test_an_impact_that_adds_energy_stops_the_run(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    result = run(tmp_path, DROP, bouncing(2.0), monkeypatch)
    assert result.status == "engine-failure"
    assert result.failure is not None and result.failure.startswith("energy gain: body `ball` gained ")
    # semi-implicit Euler: z_n = H0 - g dt^2 n (n + 1) / 2 < 0 first at n = 45 (t = 0.45 s), the step whose
    # end the floor turns around
    n = next(n for n in range(1, 1000) if H0 - G * DT**2 * n * (n + 1) / 2 < 0)
    assert result.extra["time"] == pytest.approx(n * DT)
    assert f"at t = {result.extra['time']:.4f} s on fake" in result.failure
    gained = float(result.failure.split("gained ")[1].split(" J")[0])
    # the ball's energy rose by 3 K, K = m g H0 less the integrator's loss (< 0.5 J, module docstring)
    assert 3 * (G * H0 - 0.5) <= gained <= 3 * G * H0
    assert result.extra["last_good"]["vel"][2] < 0  # the state before the impact: still falling


@pytest.mark.parametrize("e", [0.0, 0.5, 0.9, 1.0])
def test_bouncing_with_restitution_up_to_one_never_trips(
    e: float, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    result = run(tmp_path, DROP, bouncing(e), monkeypatch)
    assert result.status == "passed", result.failure


def test_a_motor_lifting_a_body_does_work_that_is_booked(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A slider motor lifts 10 kg at 1 m/s for 2 s: +196 J of potential energy, far beyond the bound
    (0.25 * 5 J + 10 * 9.81^2 * 0.01 * 0.25 = 3.7 J), all of it booked as the motor's work."""
    text = f"""\
schema_version: 1
scenario: lift
world: {{gravity: [0, 0, -{G}], dt: {DT}, duration: 2}}
bodies:
  box: {{box: [0.2, 0.2, 0.2], mass: 10, pos: [0, 0, 1]}}
joints:
  lift: {{type: slider, bodies: [box, environment], axis: [0, 0, 1], motor: {{vel: 1, fmax: 1000}}}}
"""
    path = tmp_path / "t.yaml"
    path.write_text(text)
    program = build_program(load_scenario(path, None))
    session = Session(program, FakeBackend(program.world))
    assert session.run().status == "passed"
    gain = 10 * G * (session.snapshot.bodies.pos[0, 2] - 1.0) + 0.5 * 10 * 1.0**2
    assert gain > 190 and session.energy.work >= gain


@pytest.mark.parametrize(
    "action",
    [
        "{force: {body: ball, value: [0, 0, 2000]}}",  # one step: dv = 20 m/s, +200 J
        "{reset: {body: ball, vel: [0, 0, 20]}}",  # +200 J at once
    ],
)
def test_forces_and_resets_restart_the_check(action: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    text = DROP + f"on:\n  start: [{action}]\n"
    assert run(tmp_path, text, FakeBackend, monkeypatch).status == "passed"
    # the same energy coming from the engine trips the watchdog: the bouncing test above


def test_the_bound_is_the_documented_one(tmp_path: Path) -> None:
    path = tmp_path / "t.yaml"
    path.write_text(DROP)
    world = build_program(load_scenario(path, None)).world
    watch = EnergyWatch(world, "fake")
    assert watch.floor == pytest.approx(1.0 * G**2 * DT * WINDOW_STEPS * DT)
    a = math.pi / WINDOW_STEPS  # the fastest motion whose period is longer than the window: w h = 2 pi / 25
    assert 2 * a / (1 + a) < GAIN_FRACTION


def test_an_energy_gain_exits_3_on_every_path() -> None:
    exit_ = classify(EnergyGain("energy gain: body `ball` gained 29 J at t = 0.4600 s on fake"))
    assert exit_.code == 3 and exit_.message.startswith("energy gain: body `ball`")


def test_the_mujoco_pile_of_100_is_caught(tmp_path: Path) -> None:
    """issue 17: MuJoCo, one engine step per 10 ms, throws the top box of the issue's 100-box pile (1 cm per
    layer) up at 29.5 m/s at t = 1.2 s (a run of about 1 s). The backend now refuses such a column when it
    picks the step itself (docs/backends/mujoco.md, Stacking), so the pile sets the step by hand."""
    if not is_installed("mujoco"):
        pytest.skip(f"engine not installed: {entry('mujoco').hint}")
    pile = tmp_path / "pile.yaml"
    text = (ROOT / "scenarios/box_pile.yaml").read_text()
    pile.write_text(text.replace("\nparams:", "\nbackend_options: {mujoco: {engine_substeps: 1}}\nparams:", 1))
    proc = subprocess.run(
        [sys.executable, "-m", "runner", "run", str(pile), "--backend", "mujoco",
         "--set", "params.count=100", "--set", "params.shift=0.01", "--no-trace"],
        capture_output=True, text=True, cwd=ROOT, timeout=300,
    )  # fmt: skip
    assert proc.returncode == 3, proc.stdout + proc.stderr
    assert "energy gain: body `crate_99` gained " in proc.stdout + proc.stderr


ROTOR = f"""\
schema_version: 1
scenario: rotor
world: {{gravity: [0, 0, -{G}], dt: {DT}, duration: 1}}
bodies:
  wheel: {{box: [0.2, 0.2, 0.2], mass: 2, pos: [0, 0, 1]}}
joints:
  axle: {{type: hinge, bodies: [wheel, environment], axis: [0, 0, 1], dynamics: {{armature: {{a}}}}}}
"""


@pytest.mark.parametrize("armature", [0.01, 0.5, 20.0])
def test_a_rotor_s_energy_given_to_the_bodies_is_no_gain(armature: float, tmp_path: Path) -> None:
    """A joint's armature (a rotor's reflected inertia) holds kinetic energy 1/2 a qdot^2 of its own: when the
    rotor slows and the body speeds up by the same energy, nothing was gained. The wheel (I = m s^2/6 about z)
    is given the rotor's energy exactly: the check passes; the same body energy with no rotor energy before
    it is a gain beyond the bound (the body's whole kinetic energy above a reference with none)."""
    path = tmp_path / "rotor.yaml"
    path.write_text(ROTOR.replace("{a}", repr(armature)))
    world = build_program(load_scenario(path, None)).world
    inertia_z = 2 * 0.2**2 / 6
    rotor_rate = math.sqrt(2 * 5.0 / armature)  # 5 J in the rotor: well above the bound's floor (0.48 J here)
    body_rate = math.sqrt(armature / inertia_z) * rotor_rate  # 1/2 I w^2 = 1/2 a rotor_rate^2

    def states(w: float) -> BodyStates:
        return BodyStates(np.array([[0.0, 0.0, 1.0]]), np.array([[1.0, 0.0, 0.0, 0.0]]), np.zeros((1, 3)),
                          np.array([[0.0, 0.0, w]]))  # fmt: skip

    def joints(rate: float) -> JointStates:
        return JointStates(np.zeros(1), np.array([rate]), np.zeros(1))

    watch = EnergyWatch(world, "fake")
    watch.check(DT, states(0.0), joints(rotor_rate))
    watch.check(2 * DT, states(body_rate), joints(0.0))  # the rotor's energy moved into the wheel: no raise
    watch.flush()  # the block's steps are evaluated
    fresh = EnergyWatch(world, "fake")
    fresh.check(DT, states(0.0), joints(0.0))
    fresh.check(2 * DT, states(body_rate), joints(0.0))  # the same energy from nowhere
    with pytest.raises(EnergyGain):
        fresh.flush()


def test_a_gain_in_a_joints_rotor_names_the_joint(tmp_path: Path) -> None:
    """When the energy that rose is a rotor's (1/2 a qdot^2 of a joint with armature), the message names the
    joint, not the body that rose most (which rose less, or fell: DART's cheetah read "body `fthigh` gained
    -0.1603 J"). The wheel stays at rest; the rotor alone goes from rest to 5 J, above the 0.48 J floor."""
    path = tmp_path / "rotor.yaml"
    path.write_text(ROTOR.replace("{a}", "0.5"))
    world = build_program(load_scenario(path, None)).world
    rest = BodyStates(np.array([[0.0, 0.0, 1.0]]), np.array([[1.0, 0.0, 0.0, 0.0]]), np.zeros((1, 3)), np.zeros((1, 3)))
    watch = EnergyWatch(world, "fake")
    watch.check(DT, rest, JointStates(np.zeros(1), np.zeros(1), np.zeros(1)))
    watch.check(2 * DT, rest, JointStates(np.zeros(1), np.array([math.sqrt(2 * 5.0 / 0.5)]), np.zeros(1)))
    with pytest.raises(EnergyGain, match=r"^energy gain: the rotor and spring of joint `axle` gained 5 J"):
        watch.flush()
