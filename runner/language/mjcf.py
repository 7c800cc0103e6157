"""Read an MJCF file into a :class:`~runner.language.robot_desc.ModelDesc`, through MuJoCo's own compiler.

Why MuJoCo's compiler: `<include>`, default classes, `<asset>` meshes, `<compiler>` (angle, eulerseq,
meshdir, inertiafromgeom, balanceinertia...), `fromto` and frame composition are MuJoCo's semantics; only
MuJoCo computes them exactly. So whatever MuJoCo accepts is read (a file MuJoCo refuses is refused with its
message and line), and the compiled model is mapped into the engine-neutral description:

- every body a link (the world body is the static link `worldbody`), its mass, centre of mass and inertia
  as MuJoCo computed them; every geom that can collide (contype or conaffinity non-zero, and the file's
  `<flag contact>` not disabled) a shape: primitives as they are, an ellipsoid and a mesh as a convex hull
  (docs/robots.md, MJCF);
- every joint (hinge, slide, ball, free); a body without a joint is welded to its parent;
- body pairs MuJoCo never lets touch (contype/conaffinity of all their geoms, `<exclude>`) are excluded;
- actuators are listed (the robot's controllable joints);
- every hinge's and slide's damping, friction loss, armature and stiffness (:class:`JointDynamics`);
- several joints in one body, in order (every engine: a chain of light bodies where MuJoCo is not the engine,
  backends/_kit/chains.py);
- tendons and equalities (runner.language.mjcf_needs): a tendon without a force of its own is inert (a note);
  an equality that couples two hinges or slides linearly is a mimic (``JointDesc.mimic``, `joint:mimic`);
- `<option density viscosity wind>`: MuJoCo's inertia-box fluid model (:attr:`ModelDesc.fluid`), run by the
  runner's forces where MuJoCo is not the engine (runner.sim.fluid);
- what only an engine that reads the file itself can run (a tendon that acts, any other `<equality>`, a ball
  joint's dynamics, explicit contact pairs, a massless moving body, per-geom ellipsoid fluid forces) is recorded in
  :attr:`ModelDesc.needs` as capabilities, with what needs it at its line: MuJoCo, which builds the robot from
  the file (backends/mujoco), runs it; another engine refuses it before the run. Armature and stiffness are
  named there too (`joint:armature`, `joint:stiffness`), so that an engine without them refuses at their line.

Named sites become frames on their bodies (``ModelDesc.frames``: readable, never simulated); cameras, lights,
`<custom>`, `<sensor>`, `<visual>`, `<statistic>` do not change the dynamics of a step
and are not read; `<keyframe>`s are read as start states a scenario may pick (`initial: {keyframe: NAME}`).
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np

from backends.types import PlacedShape
from runner.language.mjcf_checks import check_compiled, check_meshes
from runner.language.mjcf_collision import contacts_disabled, excluded_pairs, flag_notes, geom_shape
from runner.language.mjcf_legacy import Upgraded, upgrade
from runner.language.mjcf_needs import first_line, read_needs
from runner.language.mjcf_parts import (
    JOINT_KINDS,
    body_and_joint_names,
    joint_dynamics,
    named_lines,
    read_actuators,
    read_keyframes,
    read_sites,
)
from runner.language.model_numbers import check_mjcf_numbers
from runner.language.robot_desc import JointDesc, LinkDesc, ModelDesc, ModelFileError, quat4, vec
from runner.language.urdf_xml import parse_xml
from runner.language.visuals import mjcf_visuals, within_budget


def _mujoco(file: Path) -> Any:
    try:
        import mujoco
    except ImportError:
        raise ModelFileError(
            file,
            0,
            "reading MJCF needs MuJoCo's compiler: pip install 'physics-scenarios[mujoco]' (URDF models load "
            "without it)",
        ) from None
    return mujoco


def compile_file(file: Path, legacy: Upgraded | None = None) -> Any:
    """MuJoCo's compiled model of ``file``, or of its upgrade from MJCF's legacy dialect (ModelFileError with
    MuJoCo's message and line when it refuses)."""
    mujoco = _mujoco(file)
    try:
        if legacy is None:
            return mujoco.MjModel.from_xml_path(str(file))
        includes = {name: Path(path).read_bytes() for name, path in legacy.includes}
        spec = mujoco.MjSpec.from_string(legacy.text, include=includes or None)
        spec.modelfiledir = str(file.parent)  # meshes and textures relative to the file, as from the file
        return spec.compile()
    except ValueError as exc:
        found = re.search(r"line (\d+)", str(exc))
        where = re.search(r"[Ff]ile[: ]+'?([^'\n]+\.xml)", str(exc))
        owner = Path(where.group(1)) if where and Path(where.group(1)).is_file() else file
        line = int(found.group(1)) if found else 0
        raise ModelFileError(owner, line, f"MuJoCo refused the model: {exc}") from None


def load_mjcf(file: Path) -> ModelDesc:
    tree = parse_xml(file)
    check_mjcf_numbers(tree, file)
    check_meshes(tree, file)
    mujoco = _mujoco(file)
    legacy = upgrade(file)
    model = compile_file(file, legacy)
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    lines = named_lines(tree)
    bodies, joint_names = body_and_joint_names(model, file, lines)
    check_compiled(model, file, bodies, lines)
    touchless = contacts_disabled(model, mujoco)
    links = []
    for b in range(model.nbody):
        rot = np.zeros(9)
        mujoco.mju_quat2Mat(rot, model.body_iquat[b])
        r = rot.reshape(3, 3)
        tensor = r @ np.diag(model.body_inertia[b]) @ r.T
        shapes = []
        for g in range(model.body_geomadr[b], model.body_geomadr[b] + model.body_geomnum[b]):
            if touchless or not (model.geom_contype[g] or model.geom_conaffinity[g]):
                continue  # a visual geom (or contacts off in the file): it never touches anything
            shape = geom_shape(model, g, mujoco)
            if shape is None:
                continue
            rgba = model.geom_rgba[g]
            color = (float(rgba[0]), float(rgba[1]), float(rgba[2]), float(rgba[3]))
            shapes.append(PlacedShape(shape, vec(model.geom_pos[g]), quat4(model.geom_quat[g]), color))
        mass = 0.0 if b == 0 else float(model.body_mass[b])
        links.append(
            LinkDesc(
                bodies[b],
                mass,
                vec(model.body_ipos[b]),
                (vec(tensor[0]), vec(tensor[1]), vec(tensor[2])),
                vec(data.xpos[b]),
                quat4(data.xquat[b]),
                tuple(shapes),
                None,
                lines.get(("body", bodies[b]), 0),
                mjcf_visuals(model, b, mujoco, geom_shape),
            )
        )
    joints = []
    start: list[tuple[str, float]] = []
    notes: list[str] = list(legacy.notes) if legacy is not None else []
    found = read_needs(model, mujoco, tree, bodies, joint_names, lines)
    notes.extend(flag_notes(model, mujoco, first_line(tree, "flag")))
    for b in range(1, model.nbody):
        parent = bodies[int(model.body_parentid[b])]
        line = lines.get(("body", bodies[b]), 0)
        if int(model.body_jntnum[b]) == 0:  # welded to its parent
            joints.append(JointDesc(f"{bodies[b]}_weld", "fixed", parent, bodies[b], (1.0, 0.0, 0.0),
                                    vec(data.xpos[b]), None, None, line))  # fmt: skip
        first = int(model.body_jntadr[b])
        for j in range(first, first + int(model.body_jntnum[b])):
            kind = JOINT_KINDS[int(model.jnt_type[j])]
            limited = bool(model.jnt_limited[j]) and kind in ("hinge", "slider")
            zero = float(model.qpos0[int(model.jnt_qposadr[j])]) if limited else 0.0  # `ref`: the file's pose
            lo, hi = (None, None) if not limited else (float(model.jnt_range[j][0]) - zero,
                                                       float(model.jnt_range[j][1]) - zero)  # fmt: skip
            if lo is not None and hi is not None and not lo <= 0.0 <= hi:  # ant's ankles: range="30 100"
                begin = lo if lo > 0.0 else hi
                start.append((joint_names[j], begin))
                notes.append(f"joint `{joint_names[j]}`: its zero (the file's pose) is outside its range [{lo:g}, "
                             f"{hi:g}]; it starts at {begin:g}, the nearest end (MuJoCo would start it outside "
                             f"and the limit would throw it)")  # fmt: skip
            anchor = vec(data.xanchor[j]) if kind != "free" else vec(data.xpos[b])
            joints.append(JointDesc(joint_names[j], kind, parent, bodies[b], vec(data.xaxis[j]), anchor, lo, hi,
                                    lines.get(("joint", joint_names[j]), line), joint_dynamics(model, j),
                                    found.mimics.get(joint_names[j])))  # fmt: skip
    return ModelDesc(
        str(file),
        "worldbody",
        tuple(within_budget(links)),
        tuple(joints),
        notes=tuple(notes + found.notes),
        needs=tuple(found.needs),
        actuators=tuple(read_actuators(model, joint_names, lines, mujoco)),
        excluded=tuple(excluded_pairs(model, bodies, mujoco)),
        timestep=float(model.opt.timestep),
        gravity=vec(model.opt.gravity),
        keyframes=tuple(read_keyframes(model, joint_names, tree)),
        frames=tuple(read_sites(model, bodies, set(joint_names))),
        start=tuple(start),
        upgraded=(legacy.text, legacy.includes) if legacy is not None else None,
        fluid=found.fluid,
    )
