"""An MJCF robot handed to MuJoCo as MuJoCo reads it: ``MjSpec.from_file``, then the scenario's parts.

The user's file is the spec the world is compiled from, so everything MuJoCo reads in it comes along
(`<include>`, defaults, assets, `<compiler>`, `<option>`, tendons, equality constraints, actuators,
contact pairs and excludes, joint damping and armature). The scenario's own bodies, joints, motors and
exclusions are built in a spec of their own (radians, explicit inertials, whatever the file's `<compiler>`
says) and attached to the file's world, after the file's bodies: the file's bodies, joints and dofs keep
MuJoCo's order and addresses. A robot placed away from the origin (`pos`/`hpr`) has its world's children in
a frame at that pose. ``CompiledWorld.model_options`` keeps the file's `<option>` and its geoms' contact
parameters (MuJoCo's own mj_step); otherwise the backend's options and the scenario's surfaces apply.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import mujoco

from ..errors import UnsupportedFeature
from ..types import CompiledWorld, JointSpec, ModelFile


@dataclass
class NativeModel:
    """The file's spec and the names of its parts (CompiledWorld name -> MuJoCo name)."""

    file: ModelFile
    spec: Any
    bodies: dict[str, str]  # the file's bodies but its world body
    joints: dict[str, str]
    geoms: dict[str, list[str]] = field(default_factory=dict)  # body -> its geoms' MuJoCo names
    world_link: str = ""  # the CompiledWorld body standing for the file's world body
    total_mass: float = 0.0  # the file's `<compiler settotalmass>` (0: none), applied to its bodies only

    def owns_body(self, name: str) -> bool:
        return name in self.bodies


def load(world: CompiledWorld) -> NativeModel | None:
    """The world's MJCF robot as MuJoCo reads its file (None when it has none)."""
    files = [m for m in world.models if m.format == "mjcf"]
    if not files:
        return None
    if len(files) > 1:
        names = ", ".join(f.robot for f in files)
        raise UnsupportedFeature(f"mujoco: one MJCF robot per scenario is supported; found {names}")
    file = files[0]
    try:
        spec = _spec(file)
    except ValueError as exc:  # read by the same compiler when the scenario loaded: a changed file
        raise UnsupportedFeature(f"mujoco: MuJoCo refused {file.path}: {exc}") from None
    strip = len(file.robot) + 1
    named = [b.name for b in spec.bodies[1:] if b.name] + [j.name for j in spec.joints if j.name]
    listed = [n[strip:] for n in (*file.bodies[1:], *file.joints)]
    if len(spec.bodies) != len(file.bodies) or len(spec.joints) != len(file.joints) or not set(named) <= set(listed):
        raise UnsupportedFeature(f"mujoco: {file.path} changed since the scenario was loaded")
    bodies: dict[str, str] = {}
    for i, body in enumerate(spec.bodies):  # MjSpec lists them in MuJoCo's compiled order (as the description)
        if i == 0:
            continue  # the world body
        if not body.name:
            body.name = file.bodies[i][strip:]  # the description's name, `body_<i>`
        bodies[file.bodies[i]] = body.name
    joints: dict[str, str] = {}
    for k, joint in enumerate(spec.joints):
        if not joint.name:
            joint.name = file.joints[k][strip:]
        joints[file.joints[k]] = joint.name
    native = NativeModel(file, spec, bodies, joints, world_link=file.bodies[0])
    if spec.compiler.settotalmass > 0:  # the compiler would scale the scenario's bodies too: done after it
        native.total_mass, spec.compiler.settotalmass = float(spec.compiler.settotalmass), -1.0
    for i, body in enumerate(spec.bodies):
        geom_names: list[str] = []
        for k, geom in enumerate(body.geoms):
            if not geom.name:
                geom.name = f"{file.bodies[i]}:geom{k}"
            geom_names.append(geom.name)
        native.geoms[file.bodies[i]] = geom_names
    _place(spec, file)
    return native


def _spec(file: ModelFile) -> Any:
    """The file's spec; for a file in MJCF's legacy dialect, the runner's upgrade of it (``ModelFile.xml``),
    its meshes and includes found as from the file."""
    if not file.xml:
        return mujoco.MjSpec.from_file(file.path)
    includes = {name: Path(path).read_bytes() for name, path in file.includes}
    spec = mujoco.MjSpec.from_string(file.xml, include=includes or None)
    spec.modelfiledir = str(Path(file.path).parent)
    return spec


def _place(spec: Any, file: ModelFile) -> None:
    """The file's world children in a frame at the robot's pose (nothing when it is the identity)."""
    if file.pos == (0.0, 0.0, 0.0) and file.quat == (1.0, 0.0, 0.0, 0.0):
        return
    world = spec.worldbody
    frame = world.add_frame(pos=list(file.pos), quat=list(file.quat))
    for element in [*world.bodies, *world.geoms, *world.sites, *world.cameras, *world.lights, *world.frames]:
        if element is not frame:
            element.set_frame(frame)


def attach(native: NativeModel, parts: Any) -> Any:
    """The scenario's spec attached to the file's world (names kept as they are), the file's spec returned."""
    native.spec.attach(parts, frame=native.spec.worldbody.add_frame(), prefix="")
    return native.spec


@contextmanager
def unprefixed() -> Iterator[None]:
    """Compiling with the scenario's spec attached without a prefix: MuJoCo warns (a Python warning and its
    console log) that such a model may not be saved to XML, which is never done here; only that is hidden."""
    config = mujoco.MjLogConfig.get() if hasattr(mujoco, "MjLogConfig") else None
    console = config.logto_console if config is not None else False
    if config is not None:
        config.logto_console = False
        config.set()
    try:
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", message="Attaching a spec with an empty prefix")
            yield
    finally:
        if config is not None:
            config.logto_console = console
            config.set()


def set_geom_surfaces(native: NativeModel, params: Any, solimp: list[float]) -> None:
    """The scenario's surface on every geom of the file (its contype/conaffinity kept)."""
    for geom in native.spec.geoms:
        geom.condim, geom.friction = params.condim, list(params.friction)
        geom.solref, geom.solimp = list(params.solref), solimp
        geom.priority = 0


def drop_contact_flag(native: NativeModel) -> None:
    """The file's `<flag contact="disable"/>` (or `constraint="disable"`) under the scenario's options: its own
    geoms touch nothing (contype = conaffinity = 0, as the description has no shape for them on every engine);
    the flag itself is cleared with the file's other flags (:func:`clear_flags`), so that the scenario's bodies
    still touch one another (MuJoCo's flag holds for the whole world: a box beside dm_control's reacher fell
    through the ground, 1.17 m below it after 0.5 s)."""
    off = int(mujoco.mjtDisableBit.mjDSBL_CONTACT) | int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    if not int(native.spec.option.disableflags) & off:
        return
    for geom in native.spec.geoms:
        geom.contype, geom.conaffinity = 0, 0


def clear_flags(spec: Any) -> None:
    """Under the scenario's options, the file's `<flag>` settings are not the world's: MuJoCo's flags hold for
    every body of the model (the scenario's too), and the other engines have none of them (dm_control's finger
    disables gravity: it fell on PyBullet and floated on MuJoCo). The backend's own flags are set after this;
    what of a file's flags is the model's (contacts off) is read into the description (runner.language.mjcf)."""
    spec.option.disableflags = 0
    spec.option.enableflags = 0


def scale_total_mass(model: mujoco.MjModel, native: NativeModel) -> None:
    """`settotalmass` as MuJoCo's compiler applies it (mj_setTotalmass, then mj_setConst), on the file's
    bodies only."""
    if native.total_mass <= 0:
        return
    ids = [model.body(name).id for name in native.bodies.values()]
    scale = native.total_mass / float(sum(model.body_mass[i] for i in ids))
    model.body_mass[ids] *= scale
    model.body_inertia[ids] *= scale
    mujoco.mj_setConst(model, mujoco.MjData(model))


def apply_limits(model: mujoco.MjModel, world: CompiledWorld, native: NativeModel) -> None:
    """A scenario's `limits`/`free` on a file's hinge or slide: its range set on the compiled model (the
    world's stops count from the joint's start, ``ModelFile.start``, itself from the file's zero, qpos0 (a
    joint's `ref`); MuJoCo's range is on qpos)."""
    start = {name: q for file in world.models for name, q, _ in file.start}
    for joint in world.joints:
        name = native.joints.get(joint.name)
        if name is None or joint.kind.value not in ("hinge", "slider"):
            continue
        j = model.joint(name).id
        limited = bool(model.jnt_limited[j])
        file = (float(model.jnt_range[j][0]), float(model.jnt_range[j][1])) if limited else (None, None)
        q0 = start.get(joint.name, 0.0) + float(model.qpos0[int(model.jnt_qposadr[j])])  # the file's zero: its `ref`
        stops = tuple(None if x is None else x + q0 for x in (joint.lo, joint.hi))
        if stops == file:  # (a start's round trip may move a stop by an ulp: then it is set, as good)
            continue
        model.jnt_limited[j] = joint.lo is not None or joint.hi is not None
        lo = -math.inf if stops[0] is None else stops[0]
        hi = math.inf if stops[1] is None else stops[1]
        model.jnt_range[j] = (lo, hi)


def set_start(model: mujoco.MjModel, data: mujoco.MjData, world: CompiledWorld, joint_id: Any) -> Any:
    """The files' joints at their start (``ModelFile.start``: qpos = qpos0 + q, qvel = rate); the start
    position of every world joint (0 but for those), which a reading subtracts (stops and readings count
    from the start, backends/types.py)."""
    import numpy as np

    index = {joint.name: k for k, joint in enumerate(world.joints)}
    starts = np.zeros(len(world.joints))
    for file in world.models:
        for name, q, rate in file.start:
            k = index[name]
            j = int(joint_id[k])
            data.qpos[model.jnt_qposadr[j]] = model.qpos0[model.jnt_qposadr[j]] + q
            data.qvel[model.jnt_dofadr[j]] = rate
            starts[k] = q
    return starts


def without_file(world: CompiledWorld, native: NativeModel) -> CompiledWorld:
    """The world less the file's bodies (its world link stays: the robot's placement, a static body) and
    joints; a scenario joint to a file's body is refused."""
    own = native.file.robot + "."  # the robot's joints (and welds) are `<robot>.<name>`
    for joint in world.joints:
        ends = {joint.body, joint.other} - {None}
        if not joint.name.startswith(own) and any(native.owns_body(str(e)) for e in ends):
            raise UnsupportedFeature(f"mujoco: joint `{joint.name}` joins a body of the MJCF robot "
                                     f"`{native.file.robot}`, which MuJoCo builds from its file")  # fmt: skip
    bodies = tuple(b for b in world.bodies if not native.owns_body(b.name))
    joints = tuple(j for j in world.joints if not j.name.startswith(own))
    return replace(world, bodies=bodies, joints=joints)


class Names:
    """MuJoCo's names of the world's bodies and joints: `body:<name>`, `joint:<name>`, or the file's."""

    def __init__(self, native: NativeModel | None) -> None:
        self.native = native

    def body(self, name: str) -> str:
        if self.native is not None and name in self.native.bodies:
            return self.native.bodies[name]
        return f"body:{name}"

    def joint(self, name: str) -> str:
        if self.native is not None and name in self.native.joints:
            return self.native.joints[name]
        return f"joint:{name}"

    def has_motor(self, joint: JointSpec) -> bool:
        """Every scenario hinge and slider has a motor (set at run time); a file's joint only when the scenario
        gives it one (a helper body per joint of a file would change its solver scaling)."""
        return self.native is None or joint.name not in self.native.joints or joint.motor is not None
