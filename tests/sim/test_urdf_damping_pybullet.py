"""URDF `<dynamics damping>` on PyBullet against pybullet's own `loadURDF`, which simulates it.

What pybullet does with a URDF joint's `<dynamics>` (measured with pybullet 3.2.7, and read in bullet3's
importer, which copies `damping` and `friction` onto the multibody link): the damping acts, as a joint
torque -c qdot from the rate at the start of each step (setting it to 0 with `changeDynamics(jointDamping=0)`
changes a swing of pybullet_data's `pendulum5.urdf` by radians within a second), while the `friction` is
stored and not simulated (a copy of that file with `friction="0"` moves identically, to the last bit). So
the runner gets the file's damping, and its friction is overridden to 0 (`dynamics: {friction: 0}`) to
compare with what pybullet simulates.

The model: one link (a rod of mass m, COM L below a revolute joint about y) welded to the world tilted by
30 degrees about the joint axis, so it swings from rest; damping c over a range. The runner's damping is the
joint's motor towards rest bounded by c |qdot| (docs/semantics.md, "Joint dynamics"): while the rate keeps
its sign over a step the bound is active, the motor applies exactly -c qdot_k, and both runs are the same
engine integrating the same forces: equal to rounding (1e-12) plus the trace's rounding of positions to
1e-9. In a step where the rate crosses zero the motor stops the joint instead of pushing it on: its
impulse differs from -c qdot_k h by at most 2 c |qdot_k| h, a rate difference of 2 c |qdot_k| h / I, and a
rate error of a damped pendulum moves its angle by at most that times the time left (|sin(w t)| / w <= t).
So after every step: |ours - theirs| <= 2e-9 + sum over crossings k before it of 2 c |qdot_k| h (t - t_k) / I.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from reports.trace_reader import read_trace
from runner.language.hpr import hpr_to_quat
from runner.language.load import load_scenario
from runner.sim.run import run_loaded

p = pytest.importorskip("pybullet", reason="pybullet is a base dependency")
pytestmark = pytest.mark.slow

DT, DURATION, HPR = 1.0 / 240.0, 2.0, (0.0, 0.0, 30.0)
MASS, LENGTH, ROD = 1.5, 0.4, 0.02  # kg; m from the joint to the COM; the rod's radius
INERTIA = MASS * LENGTH**2 + MASS * (3 * ROD**2 + (2 * LENGTH) ** 2) / 12  # about the joint axis (y)
URDF = """<?xml version="1.0"?>
<robot name="swing">
  <link name="base"><inertial><mass value="0"/>
    <inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial></link>
  <link name="rod">
    <inertial><origin xyz="0 0 -{L}"/><mass value="{m}"/>
      <inertia ixx="{i}" ixy="0" ixz="0" iyy="{i}" iyz="0" izz="{iz}"/></inertial>
  </link>
  <joint name="hinge" type="continuous">
    <parent link="base"/><child link="rod"/><axis xyz="0 1 0"/>
    <dynamics damping="{c}" friction="0.3"/>
  </joint>
</robot>
"""


def _urdf(tmp_path: Path, damping: float) -> Path:
    i, iz = MASS * (3 * ROD**2 + (2 * LENGTH) ** 2) / 12, MASS * ROD**2 / 2
    path = tmp_path / "swing.urdf"
    path.write_text(URDF.format(L=LENGTH, m=MASS, i=repr(i), iz=repr(iz), c=damping))
    return path


def _reference(file: Path, steps: int, damped: bool = True) -> np.ndarray:
    """The joint's position after every step of `loadURDF` with its own damping (its motor and the link
    damping off, as tests/backends/test_urdf_pybullet_native.py)."""
    c = p.connect(p.DIRECT)
    try:
        p.setGravity(0, 0, -9.81, physicsClientId=c)
        p.setTimeStep(DT, physicsClientId=c)
        q = hpr_to_quat(HPR)
        uid = p.loadURDF(str(file), [0, 0, 1], [q[1], q[2], q[3], q[0]], useFixedBase=1,
                         flags=p.URDF_USE_INERTIA_FROM_FILE, physicsClientId=c)  # fmt: skip
        p.changeDynamics(uid, -1, linearDamping=0, angularDamping=0, physicsClientId=c)
        p.changeDynamics(uid, 0, linearDamping=0, angularDamping=0, physicsClientId=c)
        p.setJointMotorControl2(uid, 0, p.VELOCITY_CONTROL, force=0, physicsClientId=c)
        if not damped:
            p.changeDynamics(uid, 0, jointDamping=0, physicsClientId=c)
        out = np.zeros(steps + 1)
        for k in range(1, steps + 1):
            p.stepSimulation(physicsClientId=c)
            out[k] = p.getJointState(uid, 0, physicsClientId=c)[0]
        return out
    finally:
        p.disconnect(physicsClientId=c)


@pytest.mark.parametrize("damping", [0.05, 0.3, 1.0])
def test_urdf_damping_matches_load_urdf(tmp_path: Path, damping: float) -> None:
    steps = round(DURATION / DT)
    file = _urdf(tmp_path, damping)
    theirs = _reference(file, steps)
    path = tmp_path / "s.yaml"
    path.write_text(
        f"schema_version: 1\nscenario: damping\nworld: {{dt: {DT!r}, duration: {DURATION}}}\n"
        "bodies:\n  marker: {box: [0.05, 0.05, 0.05], motion: static, pos: [100, 100, 0]}\n"
        f"robots:\n  r: {{urdf: swing.urdf, fixed: true, pos: [0, 0, 1], hpr: {list(HPR)},\n"
        "      joints: {hinge: {dynamics: {friction: 0}}}}\n"
    )
    result = run_loaded(load_scenario(path), "pybullet", tmp_path / "out")
    assert result.status == "passed", result.failure
    assert result.trace is not None
    trace = read_trace(result.trace)
    ours, rate = trace.joints["r.hinge"].position, trace.joints["r.hinge"].velocity
    times = np.arange(steps + 1) * DT
    bound = np.full(steps + 1, 2e-9)
    for k in range(steps):
        if rate[k] * rate[k + 1] < 0:  # the rate crossed zero in step k -> k + 1
            bound[k + 1 :] += 2 * damping * abs(rate[k]) * DT * (times[k + 1 :] - times[k]) / INERTIA
    assert np.count_nonzero(rate[:-1] * rate[1:] < 0) >= 2  # it swung back and forth
    assert np.all(np.abs(ours - theirs) <= bound), float(np.max(np.abs(ours - theirs) - bound))
    undamped = _reference(file, steps, damped=False)  # the comparison tells damping from none
    assert float(np.max(np.abs(undamped - theirs))) > 100 * float(bound[-1])
