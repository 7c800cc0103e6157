"""The named parts of a compiled MJCF model: bodies' and joints' names (with the lines they are written at),
joint dynamics, actuators, keyframes and sites."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from backends.types import NO_DYNAMICS, JointDynamics
from runner.language.model_names import check_names
from runner.language.robot_desc import ActuatorDesc, FrameDesc, KeyframeDesc, quat4, vec

JOINT_KINDS = {0: "free", 1: "ball", 2: "slider", 3: "hinge"}  # mjtJoint
_ACTUATOR_KINDS = {  # (gaintype, biastype, dyntype) -> the MJCF shortcut it was written as
    (0, 0, 0): "motor",
    (0, 1, 0): "position",
}


def named_lines(tree: Any) -> dict[tuple[str, str], int]:
    """(tag, name) -> line, for every named element of the main file."""
    return {(e.tag, e.get("name")): e.sourceline or 0 for e in tree.getroot().iter() if isinstance(e.tag, str)
            and e.get("name")}  # fmt: skip


def body_and_joint_names(model: Any, file: Path, lines: dict[tuple[str, str], int]) -> tuple[list[str], list[str]]:
    """Every body's and joint's name in the description: the file's, else `body_<i>`, `<body>_joint` (the
    k-th unnamed joint of a body with several: `<body>_joint<k>`), `<body>_free`."""
    bodies = ["worldbody"] + [model.body(i).name or f"body_{i}" for i in range(1, model.nbody)]
    joints = []
    for j in range(model.njnt):
        body = int(model.jnt_bodyid[j])
        name = model.joint(j).name
        if not name:
            count, k = int(model.body_jntnum[body]), j - int(model.body_jntadr[body])
            suffix = "free" if int(model.jnt_type[j]) == 0 else ("joint" if count == 1 else f"joint{k}")
            name = f"{bodies[body]}_{suffix}"
        joints.append(name)
    for kind, names in (("body", bodies), ("joint", joints)):
        check_names(file, kind, [(n, lines.get((kind, n), 0)) for n in names])
    return bodies, joints


def joint_dynamics(model: Any, j: int) -> JointDynamics:
    """A hinge's or slide's damping, friction loss, armature and spring as MuJoCo compiled them (defaults
    applied); the spring's rest position from the zero configuration (``qpos_spring - qpos0``)."""
    if int(model.jnt_type[j]) not in (2, 3):
        return NO_DYNAMICS
    dof, q = int(model.jnt_dofadr[j]), int(model.jnt_qposadr[j])
    return JointDynamics(
        damping=float(model.dof_damping[dof]),
        frictionloss=float(model.dof_frictionloss[dof]),
        armature=float(model.dof_armature[dof]),
        stiffness=float(model.jnt_stiffness[j]),
        springref=float(model.qpos_spring[q] - model.qpos0[q]),
    )


def read_actuators(model: Any, joints: list[str], lines: dict[tuple[str, str], int], mujoco: Any) -> list[ActuatorDesc]:
    out = []
    for a in range(model.nu):
        name = model.actuator(a).name or f"actuator_{a}"
        key = (int(model.actuator_gaintype[a]), int(model.actuator_biastype[a]), int(model.actuator_dyntype[a]))
        kind = _ACTUATOR_KINDS.get(key, "general")
        if kind == "position" and model.actuator_biasprm[a][1] == 0:
            kind = "velocity"  # bias (0, 0, -kv)
        on_joint = int(model.actuator_trntype[a]) in (mujoco.mjtTrn.mjTRN_JOINT, mujoco.mjtTrn.mjTRN_JOINTINPARENT)
        joint = joints[int(model.actuator_trnid[a][0])] if on_joint else None
        if joint is not None and int(model.jnt_type[int(model.actuator_trnid[a][0])]) not in (2, 3):
            joint = None  # a ball or free joint's actuator: several coordinates, MuJoCo's alone
        line = next((v for (tag, n), v in lines.items() if n == name and tag != "joint" and tag != "body"), 0)
        trn = mujoco.mjtTrn(int(model.actuator_trntype[a])).name.removeprefix("mjTRN_").lower()
        unmapped = None
        if joint is None:
            unmapped = f"a {trn} transmission"
        elif key[2] != 0:
            unmapped = "activation dynamics (`dyntype`)"
        elif key[0] != 0 or key[1] not in (0, 1):
            unmapped = "a gain or bias that is not fixed or affine"
        limited = bool(model.actuator_ctrllimited[a]), bool(model.actuator_forcelimited[a])
        out.append(
            ActuatorDesc(
                name, kind, joint, line,
                gear=float(model.actuator_gear[a][0]),
                gain=float(model.actuator_gainprm[a][0]),
                bias=(float(model.actuator_biasprm[a][0]), float(model.actuator_biasprm[a][1]),
                      float(model.actuator_biasprm[a][2])),
                ctrlrange=(float(model.actuator_ctrlrange[a][0]), float(model.actuator_ctrlrange[a][1]))
                if limited[0] else None,
                forcerange=(float(model.actuator_forcerange[a][0]), float(model.actuator_forcerange[a][1]))
                if limited[1] else None,
                unmapped=unmapped,
            )
        )  # fmt: skip
    return out


def read_keyframes(model: Any, joints: list[str], tree: Any) -> list[KeyframeDesc]:
    """The file's keys: hinge and slide values from the zero configuration (qpos0), and the other joints
    they move."""
    keys = list(tree.getroot().iter("key"))
    out = []
    for k in range(model.nkey):
        name = model.key(k).name or f"key_{k}"
        values, others = [], []
        for j in range(model.njnt):
            q, d = int(model.jnt_qposadr[j]), int(model.jnt_dofadr[j])
            kind = JOINT_KINDS[int(model.jnt_type[j])]
            if kind in ("hinge", "slider"):
                values.append((joints[j], float(model.key_qpos[k][q] - model.qpos0[q]), float(model.key_qvel[k][d])))
                continue
            nq, nv = (7, 6) if kind == "free" else (4, 3)
            moved = np.any(model.key_qpos[k][q : q + nq] != model.qpos0[q : q + nq])
            if moved or np.any(model.key_qvel[k][d : d + nv]):
                others.append(joints[j])
        line = (keys[k].sourceline or 0) if k < len(keys) else 0
        out.append(KeyframeDesc(name, line, tuple(values), tuple(others)))
    return out


def read_sites(model: Any, bodies: list[str], joints: set[str]) -> list[FrameDesc]:
    """Every named site as a frame on its body (as MuJoCo compiled its pose in the body frame); a site named as
    a body or joint is left out (the body or joint keeps the name)."""
    taken = set(bodies) | joints
    out = []
    for i in range(model.nsite):
        name = model.site(i).name
        if name and name not in taken:
            out.append(
                FrameDesc(name, bodies[int(model.site_bodyid[i])], vec(model.site_pos[i]), quat4(model.site_quat[i]))
            )
    return out
