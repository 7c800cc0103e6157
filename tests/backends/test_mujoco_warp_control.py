"""An MJCF file's actuators driven by ``set_control`` on mujoco_warp, alone and in a batch: the ctrl the runner
sets on the host reaches MJWarp's device data (backends/mujoco_warp/_backend.py, _batch.py).

The world: a 1 x 0.1 x 0.1 m rod of 1 kg on a hinge about z, no gravity, no contact (the ground is far below),
so the only generalized force is the actuator's: I = (1 + 0.01)/12 kg m^2. Reference: the same world on the
``mujoco`` backend (the same MjModel, float64, the same implicitfast step; without a contact MuJoCo's step is
``mj_step``).

Tolerance (float32, derived): a step computes the actuator force (ctrl stored in float32, gain x ctrl + bias:
at most 3 products and 2 sums for a position servo, kp ctrl - kp q - kv qdot), the mass matrix's one entry from
the body's inertia and centre (stored in float32, a few products and sums), the acceleration (one division;
implicitfast's velocity derivative: one more product, sum and division), then v += h a and q += h v (two
products, two sums): under K = 16 roundings, each at most 2^-24 relative to a value no larger than the run's
largest |q|, |v h| or |ctrl| (all <= Q = max(1, max |q|), h |v| << 1 here). The motor's recurrence adds the
step's errors (it integrates, it does not amplify them) and the servo's contracts them (its step matrix's
eigenvalues are inside the unit circle: h kp/I = 0.024, h kv/I = 0.24), so after n steps
|q_warp - q_mujoco| <= n K 2^-24 Q (mujoco's own float64 rounding is 2^-29 times smaller), plus, for q, the
sum of the velocity errors times h, which the same bound at n h <= 1 s covers twice: 2 n K 2^-24 Q.
Before the fix the rod did not move at all on mujoco_warp (ctrl never reached the device): an error of Q.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("mujoco_warp")

from backends.registry import create_backend, get_backend  # noqa: E402
from backends.types import CompiledWorld  # noqa: E402
from runner.compile.program import build_program  # noqa: E402
from runner.language.load import load_scenario  # noqa: E402

OPERATIONS = 16  # float32 roundings per step (module docstring)
EPS32 = 2.0**-24
STEPS = 60  # 0.6 s at dt 0.01

MJCF = """\
<mujoco>
  <worldbody>
    <body name="rod" pos="0 0 1">
      <joint name="hinge" type="hinge" axis="0 0 1"/>
      <geom type="box" size="0.5 0.05 0.05" mass="1"/>
    </body>
  </worldbody>
  <actuator>
    <motor name="spin" joint="hinge" gear="2" ctrlrange="-2 2"/>
    <position name="servo" joint="hinge" kp="20" kv="2"/>
  </actuator>
</mujoco>
"""
SCENARIO = """\
schema_version: 1
scenario: rod
world: {gravity: [0, 0, 0], dt: 0.01, duration: 1.0}
bodies:
  ground: {plane: {}, motion: static, pos: [0, 0, -5]}
robots:
  r: {mjcf: rod.xml}
"""
SPIN, SERVO = 0, 1  # the file's actuator order


@pytest.fixture(scope="module")
def rod(tmp_path_factory: pytest.TempPathFactory) -> CompiledWorld:
    folder: Path = tmp_path_factory.mktemp("rod")
    (folder / "rod.xml").write_text(MJCF)
    (folder / "rod.yaml").write_text(SCENARIO)
    return build_program(load_scenario(folder / "rod.yaml", None)).world


#: (step, actuator, ctrl) set before that step, held until changed: the motor, then the servo taking over
SCRIPT = [(0, SPIN, 0.4), (20, SPIN, 0.0), (20, SERVO, -0.3), (40, SERVO, 0.5)]


def _script(scale: float) -> list[tuple[int, int, float]]:
    return [(k, a, scale * c) for k, a, c in SCRIPT]


def _angles(engine: str, world: CompiledWorld, script: list[tuple[int, int, float]]) -> np.ndarray:
    """The hinge angle after each step, ``script`` driving the actuators."""
    out = []
    with create_backend(engine, world) as sim:
        joint = next(k for k, j in enumerate(sim.world.joints) if j.name == "r.hinge")
        for k in range(STEPS):
            for step, actuator, ctrl in script:
                if step == k:
                    sim.set_control(actuator, ctrl)
            sim.step()
            out.append(sim.joint_states().position[joint])
    return np.array(out)


def _bound(angles: np.ndarray) -> float:
    q = max(1.0, float(np.abs(angles).max()))
    return 2.0 * STEPS * OPERATIONS * EPS32 * q


def test_control_moves_the_rod_as_on_mujoco(rod: CompiledWorld) -> None:
    reference = _angles("mujoco", rod, SCRIPT)
    # it moved: the motor against the servo at ctrl 0 (static deflection gear ctrl/kp = 0.04 rad), then servoed
    assert reference[19] > 0.02 and reference[39] < -0.1 and reference[-1] > 0.3
    warp = _angles("mujoco_warp", rod, SCRIPT)
    assert np.abs(warp - reference).max() <= _bound(reference)


def test_each_world_of_a_batch_follows_its_own_control(rod: CompiledWorld) -> None:
    """Three worlds, each scripted with its own ctrl values (and world 1 never told anything at step 40); each
    ends as mujoco_warp ends that world alone (bit for bit: test_mujoco_warp_batch.py's reason) and as mujoco
    does (the bound above)."""
    scripts = [_script(1.0), [c for c in _script(-1.5) if c[0] != 40], _script(0.5)]
    cls = get_backend("mujoco_warp").world_batch()
    assert cls is not None
    got: list[list[float]] = [[], [], []]
    with cls([rod, rod, rod]) as batch:
        views = batch.views
        joint = next(k for k, j in enumerate(rod.joints) if j.name == "r.hinge")
        for k in range(STEPS):
            for view, script in zip(views, scripts, strict=True):
                for step, actuator, ctrl in script:
                    if step == k:
                        view.set_control(actuator, ctrl)
            assert batch.step_all([True] * 3) == {}
            for i, view in enumerate(views):
                view.step()
                got[i].append(view.joint_states().position[joint])
    for i, script in enumerate(scripts):
        alone = _angles("mujoco_warp", rod, script)
        assert np.array_equal(np.array(got[i]), alone), f"world {i}"
        reference = _angles("mujoco", rod, script)
        assert np.abs(alone - reference).max() <= _bound(reference), f"world {i}"
