"""Kinetic energy, momentum, angular momentum and body-frame angular velocity (runner.sim.body_quantities),
judged against an independent computation: scipy's Rotation (scalar-last quaternions) turns the centre of
mass and the inertia tensor into the world frame, and each quantity is written from its definition
(1/2 m v_c.v_c + 1/2 w.(I_world w); m v_c; I_world w; I_world w + p_c x m v_c; R^T w). Both are float64
sums of a few dozen terms of size <= 50: they agree to 1e-12 relative (1e-12 absolute near zero).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from backends.types import BodySpec, BodyStates, CompiledWorld, Motion, Shape, ShapeKind
from runner.language.load import load_scenario
from runner.sim.resolver import Snapshot, StateResolver


def body(name: str, com: tuple[float, float, float], inertia_quat: tuple[float, float, float, float]) -> BodySpec:
    return BodySpec(name=name, motion=Motion.DYNAMIC, shape=Shape(ShapeKind.BOX, (0.1, 0.2, 0.3)), mass=2.5,
                    inertia=(0.04, 0.03, 0.02), pos=(0.0, 0.0, 0.0), quat=(1.0, 0.0, 0.0, 0.0), com=com,
                    inertia_quat=inertia_quat)  # fmt: skip


def truth(spec: BodySpec, row: np.ndarray) -> dict[str, np.ndarray]:
    pos, quat, v, w = row[0:3], row[3:7], row[7:10], row[10:13]
    rot = Rotation.from_quat([quat[1], quat[2], quat[3], quat[0]]).as_matrix()
    axes = Rotation.from_quat([*spec.inertia_quat[1:], spec.inertia_quat[0]]).as_matrix()
    tensor_world = rot @ axes @ np.diag(spec.inertia) @ axes.T @ rot.T
    arm = rot @ np.asarray(spec.com)
    v_com = v + np.cross(w, arm)
    return {
        "kinetic_energy": np.array(0.5 * spec.mass * v_com @ v_com + 0.5 * w @ tensor_world @ w),
        "momentum": spec.mass * v_com,
        "angmom": tensor_world @ w,
        "angmom_origin": tensor_world @ w + np.cross(pos + arm, spec.mass * v_com),
        "angvel_body": rot.T @ w,
    }


def test_each_quantity_of_a_body_with_a_com_offset_and_turned_axes_and_of_a_group() -> None:
    q = np.array([0.9, 0.1, -0.3, 0.2])
    specs = (body("plain", (0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0)),
             body("link", (0.05, -0.02, 0.1), tuple((q / np.linalg.norm(q)).tolist())))  # type: ignore[arg-type]  # fmt: skip
    world = CompiledWorld("t", (0.0, 0.0, -9.81), 0.01, 1, 1.0, specs)
    rng = np.random.default_rng(5)
    quats = rng.normal(size=(2, 4))
    rows = np.hstack([rng.normal(size=(2, 3)), quats / np.linalg.norm(quats, axis=1)[:, None], rng.normal(size=(2, 6))])
    snap = Snapshot()
    snap.bodies = BodyStates.from_rows(rows)
    resolver = StateResolver(world, {"both": ["plain", "link"]}, {}, {}, snap, {}, eps=2.0**-52)
    for i, spec in enumerate(specs):
        want = truth(spec, rows[i])
        assert resolver.value(f"{spec.name}.kinetic_energy") == pytest.approx(float(want["kinetic_energy"]), rel=1e-12)
        for name in ("momentum", "angmom", "angmom_origin", "angvel_body"):
            for k, c in enumerate("xyz"):
                assert resolver.value(f"{spec.name}.{name}.{c}") == pytest.approx(want[name][k], rel=1e-12, abs=1e-12)
    group = [truth(s, rows[i])["momentum"][2] for i, s in enumerate(specs)]
    assert resolver.value("both.momentum.z") == pytest.approx(group, rel=1e-12)
    # the kinetic energy is the mechanical energy less the gravitational part, -m g.p_c
    g_part = [-s.mass * (rows[i, 0:3] + Rotation.from_quat([*rows[i, 4:7], rows[i, 3]]).as_matrix() @ s.com)[2] * -9.81
              for i, s in enumerate(specs)]  # fmt: skip
    assert np.allclose(
        np.array(resolver.value("both.energy")) - g_part, resolver.value("both.kinetic_energy"), rtol=1e-12
    )


def test_the_new_names_are_readable(tmp_path: Path) -> None:
    path = tmp_path / "q.yaml"
    names = ["box.kinetic_energy", "box.momentum.z", "box.angmom.x", "box.angmom_origin.y", "box.angvel_body.z"]
    text = "".join(f"  - {{name: a{i}, at: end, value: {n}, near: 0, tol: 1e9}}\n" for i, n in enumerate(names))
    head = "schema_version: 1\nscenario: q\nworld: {gravity: [0, 0, -9.81], dt: 0.01, duration: 0.1}\n"
    path.write_text(head + "bodies:\n  box: {box: [0.1, 0.2, 0.3], mass: 1, pos: [0, 0, 1]}\nassertions:\n" + text)
    load_scenario(path)
