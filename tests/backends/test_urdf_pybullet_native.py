"""A URDF run on PyBullet reproduces pybullet's own `loadURDF` with documented settings (issue 28, item 3).

The reference loads the same file with `p.loadURDF(file, pos, orn, useFixedBase=1,
flags=URDF_USE_INERTIA_FROM_FILE)` and then sets what `loadURDF` adds on its own and the scenario language
does not have (docs/robots.md, "PyBullet's loadURDF"): the velocity motor it puts on every joint off
(`setJointMotorControl2(VELOCITY_CONTROL, force=0)`), the multibody's linear and angular damping 0 (it
sets 0.04), and the joints' `<dynamics damping>` 0 (the backend alone, without the runner's damping). Gravity
-9.81 and the step 1/240 s are set on both. The robot is welded to the world tilted (hpr 20, 30, 10
degrees) so gravity swings every joint. After every step each joint's position must agree to 1e-9 rad
(m): the same engine integrates the same tree with the same inertias, so they agree to rounding (the
link frames are built differently: `createMultiBody` from the description against Bullet's URDF importer,
which changes the last bits); a wrong inertia, a motor left on, damping or a misplaced axis shows at 1e-4 or
more within the swing. The models: ones whose links do not touch each other while they swing (the
runner keeps self-collision on, `loadURDF` off by default). The swing stops at 0.8 s: at 0.9 s kuka's folded
links touch each other, and from there the runner's contacts (the scenario's surface, ODE-style) are not
`loadURDF`'s defaults. Measured: given `URDF_USE_SELF_COLLISION`, each link's friction and restitution as
the adapter sets them and the adapter's engine parameters (solver iterations, restitution threshold,
contact breaking threshold), the reference follows kuka to 1.8e-13 rad over 1.2 s, the self-contact included
(docs/robots.md).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from backends.registry import create_backend
from runner.compile.program import build_program
from runner.language.hpr import hpr_to_quat
from runner.language.load import load_scenario

p = pytest.importorskip("pybullet", reason="pybullet is a base dependency")

TOL = 1e-9  # rad (m for a slider): rounding only (module docstring)
#: 0.8 s: before kuka's links touch each other (step 216, module docstring)
DT, DURATION, HPR = 1.0 / 240.0, 0.8, (20.0, 30.0, 10.0)
MODELS = (
    "cartpole.urdf",
    "pendulum5.urdf",
    "kuka_iiwa/model.urdf",
    "kuka_iiwa/model_free_base.urdf",
    "quadruped/quadruped.urdf",
)


def _reference(file: Path, c: int) -> tuple[int, dict[str, int]]:
    q = hpr_to_quat(HPR)
    uid = p.loadURDF(str(file), [0, 0, 1], [q[1], q[2], q[3], q[0]], useFixedBase=1,
                     flags=p.URDF_USE_INERTIA_FROM_FILE, physicsClientId=c)  # fmt: skip
    p.changeDynamics(uid, -1, linearDamping=0, angularDamping=0, physicsClientId=c)
    joints = {}
    for j in range(p.getNumJoints(uid, physicsClientId=c)):
        info = p.getJointInfo(uid, j, physicsClientId=c)
        if info[2] in (p.JOINT_REVOLUTE, p.JOINT_PRISMATIC):
            joints[f"r.{info[1].decode()}"] = j
            p.setJointMotorControl2(uid, j, p.VELOCITY_CONTROL, force=0, physicsClientId=c)
            p.changeDynamics(uid, j, jointDamping=0, physicsClientId=c)
    return uid, joints


@pytest.mark.parametrize("model", MODELS)
def test_urdf_on_pybullet_reproduces_load_urdf(tmp_path: Path, model: str) -> None:
    import pybullet_data

    path = tmp_path / "s.yaml"
    path.write_text(
        f"schema_version: 1\nscenario: native\nworld: {{dt: {DT!r}, duration: {DURATION}}}\n"
        "bodies:\n  marker: {box: [0.05, 0.05, 0.05], motion: static, pos: [100, 100, 0]}\n"
        f"robots:\n  r: {{urdf: '@pybullet_data/{model}', fixed: true, pos: [0, 0, 1], hpr: {list(HPR)}}}\n"
    )
    world = build_program(load_scenario(path)).world
    c = p.connect(p.DIRECT)
    try:
        p.setGravity(0, 0, -9.81, physicsClientId=c)
        p.setTimeStep(DT, physicsClientId=c)
        uid, joints = _reference(Path(pybullet_data.getDataPath()) / model, c)
        compared = [(k, joints[s.name]) for k, s in enumerate(world.joints) if s.name in joints]
        assert len(compared) == len(joints) > 0
        moved = 0.0
        with create_backend("pybullet", world) as sim:
            for step in range(round(DURATION / DT)):
                sim.step()
                p.stepSimulation(physicsClientId=c)
                ours = sim.joint_states().position
                for k, j in compared:
                    theirs = p.getJointState(uid, j, physicsClientId=c)[0]
                    assert abs(ours[k] - theirs) <= TOL, f"{model}: {world.joints[k].name} at step {step + 1}"
                    moved = max(moved, abs(theirs))
        assert moved > 1e-3  # the joints swung, a million times the tolerance (not two models at rest)
    finally:
        p.disconnect(physicsClientId=c)
