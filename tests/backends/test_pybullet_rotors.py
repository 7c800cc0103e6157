"""PyBullet's armature rotors: which worlds get Bullet's extra sweeps over the gears (backends/pybullet/_rotors.py).

The rule reads each geared joint's own inertia M_jj (what it moves, about its axis) from the world as built; it
must be the mass matrix's diagonal entry, so it is checked against MuJoCo's (``mj_fullM`` less ``dof_armature``,
at the same start: the description's clamped joints) on the real files. Bound: a body with n joints is a chain
through n - 1 light copies of it (backends/_kit/chains.py, ``LIGHT`` of its mass and inertia at its COM), which
the joints before them also move, so M_jj may exceed MuJoCo's by (n_max - 1) LIGHT relative; plus rounding,
1e-9 relative (both sum the same few products in double). pybullet_data's pusher and thrower (a/M_jj up to
9.9e7 and 2.3e9) get the sweeps; humanoid_CMU (up to 330) keeps Bullet's one.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("pybullet", reason="the pybullet extra")
mujoco = pytest.importorskip("mujoco", reason="MuJoCo's mass matrix is the reference")
import pybullet as p  # noqa: E402

from backends._kit.chains import LIGHT  # noqa: E402
from backends.pybullet import _rotors  # noqa: E402
from backends.registry import create_backend  # noqa: E402
from runner.compile.program import build_program  # noqa: E402
from runner.language.mjcf import load_mjcf  # noqa: E402
from runner.survey.cases import load_survey_scenario  # noqa: E402
from runner.survey.models import ROBOT, ModelFile  # noqa: E402

RELATIVE = 1e-9


def _files() -> dict[str, Path]:
    pybullet_data = pytest.importorskip("pybullet_data", reason="pybullet's bundled models")
    dm_control = pytest.importorskip("dm_control", reason="dm_control's suite is a test dependency (dm-control)")
    mjcf = Path(pybullet_data.getDataPath()) / "mjcf"
    return {"pusher": mjcf / "pusher.xml", "thrower": mjcf / "thrower.xml",
            "humanoid_CMU": Path(dm_control.__file__).parent / "suite" / "humanoid_CMU.xml"}  # fmt: skip


def _mujoco_own_inertia(file: Path) -> tuple[dict[str, float], int]:
    """Per geared joint, M_jj at the description's start; and the most joints in one body."""
    model = mujoco.MjModel.from_xml_path(str(file))
    data = mujoco.MjData(model)
    for joint, value in load_mjcf(file).start:  # counted from the file's zero, qpos0
        address = int(model.joint(joint).qposadr[0])
        data.qpos[address] = model.qpos0[address] + value
    mujoco.mj_forward(model, data)
    full = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, full)
    out = {}
    for j in range(model.njnt):
        dof = int(model.jnt_dofadr[j])
        if int(model.jnt_type[j]) in (2, 3) and model.dof_armature[dof] > 0:
            out[f"{ROBOT}.{model.joint(j).name}"] = float(full[dof, dof] - model.dof_armature[dof])
    return out, int(model.body_jntnum.max())


@pytest.mark.parametrize(("name", "swept"), [("pusher", True), ("thrower", True), ("humanoid_CMU", False)])
def test_light_gears_get_the_sweeps_and_own_inertia_is_the_mass_matrix_diagonal(name: str, swept: bool) -> None:
    file = _files()[name]
    world = build_program(load_survey_scenario(ModelFile(file, file.name, "mjcf"), 0.5)).world
    reference, most = _mujoco_own_inertia(file)
    bound = (most - 1) * LIGHT + RELATIVE
    with create_backend("pybullet", world) as backend:
        layout, client = backend._layout, backend._c  # type: ignore[attr-defined]  # the adapter's own
        index = {j.name: k for k, j in enumerate(backend.world.joints)}
        for joint, expected in reference.items():
            got = _rotors.own_inertia(backend.world, layout, p, client, index[joint])
            assert abs(got - expected) <= bound * expected, (joint, got, expected)
        sweeps = p.getPhysicsEngineParameters(physicsClientId=client)["numNonContactInnerIterations"]
    ratio = max(backend.world.joints[index[j]].dynamics.armature / m for j, m in reference.items())
    assert (ratio > _rotors.LIGHT_GEAR) is swept
    assert sweeps == (_rotors.ROTOR_SWEEPS if swept else 1)
