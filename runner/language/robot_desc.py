"""What a URDF or MJCF file says, engine-neutral, and where its files are (roots, `package://`).

A :class:`ModelDesc` holds every link in the model's own frame at its zero configuration (forward
kinematics already applied), its inertial frame, its collision shapes, and every joint with its axis and
anchor in the model frame. :mod:`runner.compile.robots` places it in the world. Problems found while
reading a model are :class:`ModelFileError`s naming the *model file* and line.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from backends.types import NO_DYNAMICS, Fluid, JointDynamics, PlacedShape, Quat, Rgba, Vec3

#: `@pybullet_data/...`: the models shipped inside the pybullet wheel (pybullet_data.getDataPath()).
PYBULLET_DATA = "@pybullet_data"


class ModelFileError(Exception):
    """A problem in a model file (or a file it names): the file, the line and column (1-based; 0: unknown)
    and what is wrong. Without a column, it is that of ``near`` (the offending text, e.g. an attribute's
    value) on the line, else of the line's first non-blank character (where its element starts)."""

    def __init__(self, file: Path | str, line: int, message: str, near: str = "", column: int = 0) -> None:
        super().__init__(message)
        self.file = str(file)
        self.line = line
        self.message = message
        self.column = column or line_column(self.file, line, near)


def line_column(file: str, line: int, near: str = "") -> int:
    """The 1-based column of ``near`` on ``line`` of ``file`` (else of its first non-blank character; 0 when
    the line is unknown or unreadable). Read only when an error is raised."""
    if line <= 0:
        return 0
    try:
        lines = Path(file).read_bytes().decode("utf-8", "replace").splitlines()
    except OSError:
        return 0
    if line > len(lines):
        return 0
    text = lines[line - 1]
    found = text.find(near) if near else -1
    if found < 0:
        found = len(text) - len(text.lstrip())
    return found + 1


@dataclass(frozen=True)
class FrameDesc:
    """A named frame fixed on a link (an MJCF site; a URDF link without mass on a fixed joint, merged into its
    parent): readable as `<robot>.<name>.pos|quat|vel|angvel` (docs/language.md, "Sensors")."""

    name: str
    link: str  # the link that carries it
    pos: Vec3  # in the link frame
    quat: Quat


@dataclass(frozen=True)
class LinkDesc:
    """A model file's link, engine-neutral: mass properties, frame at the zero configuration, shapes."""

    name: str
    mass: float  # kg; 0: the model says none (only a fixed root may have none)
    com: Vec3  # in the link frame
    inertia: tuple[Vec3, Vec3, Vec3]  # full tensor about the COM, link frame
    pos: Vec3  # link frame in the model frame, at the zero configuration
    quat: Quat
    shapes: tuple[PlacedShape, ...]  # collision shapes in the link frame
    color: Rgba | None  # the first visual's colour, if the model gives one
    line: int
    #: what the model draws (URDF <visual>, MJCF's visible geoms) in the link frame; engines never see it
    visuals: tuple[PlacedShape, ...] = ()


@dataclass(frozen=True)
class MimicDesc:
    """URDF `<mimic>` or an MJCF equality coupling two joints (runner.language.mjcf_needs): the joint's position
    is ``multiplier`` x ``leader``'s + ``offset``, both read as the description reads them (from each joint's zero
    in the description: the file's, or its start clamp; MJCF: qpos0)."""

    leader: str
    multiplier: float
    offset: float


@dataclass(frozen=True)
class JointDesc:
    """A model file's joint, engine-neutral, in the model frame at the zero configuration."""

    name: str
    kind: str  # hinge | slider | fixed | ball | free (MJCF: a free body)
    parent: str
    child: str
    axis: Vec3  # unit, model frame, at the zero configuration
    anchor: Vec3  # model frame: the child's frame origin
    lo: float | None  # from the zero configuration
    hi: float | None
    line: int
    #: damping, friction loss, armature, stiffness, effort and velocity limits (URDF `<dynamics>`/`<limit>`,
    #: MJCF's compiled joint), in the joint's coordinate as ``lo``/``hi``
    dynamics: JointDynamics = NO_DYNAMICS
    mimic: MimicDesc | None = None  # URDF <mimic>, MJCF equality: held at a multiple of another's position


@dataclass(frozen=True)
class ModelNeed:
    """Something in a model file only an engine that builds the robot from the file itself runs (MuJoCo for
    MJCF): the capability it needs (``backends.types.Capability`` value), what it is, and its line."""

    capability: str
    what: str
    line: int


@dataclass(frozen=True)
class ActuatorDesc:
    """An actuator the model declares (MJCF `<actuator>`): the robot's controllable joints."""

    name: str
    kind: str  # motor | position | velocity | general
    joint: str | None  # the joint it drives (None: a tendon, site or body transmission)
    line: int
    #: MuJoCo's force law, as compiled: force = gain ctrl + bias[0] + bias[1] length + bias[2] velocity with
    #: length = gear q and velocity = gear qdot, clamped to ``forcerange``; the joint gets gear x force
    gear: float = 1.0
    gain: float = 1.0
    bias: tuple[float, float, float] = (0.0, 0.0, 0.0)
    ctrlrange: tuple[float, float] | None = None  # None: ctrl not limited
    forcerange: tuple[float, float] | None = None  # None: force not limited
    #: why the runner's law cannot reproduce it off MuJoCo (a site or body transmission, activation
    #: dynamics, a non-fixed gain or non-affine bias); None: it can
    unmapped: str | None = None


@dataclass(frozen=True)
class KeyframeDesc:
    """An MJCF `<key>`: its hinges' and slides' positions (from the zero configuration) and rates."""

    name: str
    line: int
    values: tuple[tuple[str, float, float], ...]  # (joint, position, rate)
    others: tuple[str, ...] = ()  # free or ball joints it moves away from their zero or at rest, not taken


@dataclass(frozen=True)
class ModelDesc:
    """A URDF or MJCF model as read: its links and joints, and what the loader decided for the user."""

    file: str  # as resolved (absolute)
    root: str  # the root link
    links: tuple[LinkDesc, ...]
    joints: tuple[JointDesc, ...]
    #: what the loader decided that the file left open (a joint started inside its limits, ...), for the user
    notes: tuple[str, ...] = ()
    #: what only an engine reading the file itself runs (MJCF; runner.language.mjcf)
    needs: tuple[ModelNeed, ...] = ()
    actuators: tuple[ActuatorDesc, ...] = ()
    #: link pairs the model never lets touch (MJCF contype/conaffinity and `<exclude>`)
    excluded: tuple[tuple[str, str], ...] = ()
    #: the model's own step and gravity (MJCF `<option>`), for `world.options: model`
    timestep: float | None = None
    gravity: Vec3 | None = None
    #: named frames on links (MJCF sites, merged URDF links), never a link's or joint's name
    frames: tuple[FrameDesc, ...] = ()
    #: MJCF `<keyframe>`s, in the file's order
    keyframes: tuple[KeyframeDesc, ...] = ()
    #: (joint, position from the zero) where the model starts a joint whose zero is outside its range (MJCF:
    #: the nearest end, noted; a keyframe or the scenario's `initial` overrides it)
    start: tuple[tuple[str, float], ...] = ()
    #: MJCF in the legacy dialect: the text MuJoCo 4 reads and the files its `<include>`s name (as written,
    #: absolute path), runner.language.mjcf_legacy; None: the file as it is
    upgraded: tuple[str, tuple[tuple[str, str], ...]] | None = None
    #: MJCF `<option density viscosity wind>` when MuJoCo's inertia-box fluid model acts (runner.language.mjcf_needs)
    fluid: Fluid | None = None

    def keyframe(self, name: str) -> KeyframeDesc | None:
        return next((key for key in self.keyframes if key.name == name), None)

    def link(self, name: str) -> LinkDesc:
        return next(link for link in self.links if link.name == name)


def data_root(text: str) -> tuple[Path, str] | None:
    """`@pybullet_data/rest` -> (the folder, rest); None for a path that does not start with a root."""
    if text == PYBULLET_DATA or text.startswith(PYBULLET_DATA + "/"):
        from importlib.util import find_spec

        spec = find_spec("pybullet_data")  # the data package's folder, found without importing anything
        if spec is None or not spec.submodule_search_locations:  # pybullet is a base dependency
            raise ModelFileError(text, 0, f"`{PYBULLET_DATA}` needs the pybullet package (pip install pybullet)")
        return Path(list(spec.submodule_search_locations)[0]), text[len(PYBULLET_DATA) :].lstrip("/")
    return None


def resolved(path: Path, model_file: Path | str, line: int, near: str) -> Path:
    """``path`` with its symlinks followed; a symlink loop (or a path the system cannot follow) is a
    ModelFileError at ``line`` of ``model_file`` (0: the scenario's line), not a crash (it was exit 70)."""
    try:
        return path.resolve()
    except (OSError, RuntimeError) as exc:  # Python 3.11 raises RuntimeError("Symlink loop from ...")
        why = "is a symlink loop" if "loop" in str(exc).lower() else f"cannot be followed ({exc})"
        raise ModelFileError(model_file, line, f"`{near}` {why}", near=near) from None


def resolve_file(text: str, base_dir: Path) -> Path:
    """A model path as the scenario writes it: relative to the scenario's folder, or under a root."""
    rooted = data_root(text)
    if rooted is not None:
        return resolved(rooted[0] / rooted[1], text, 0, text)
    return resolved(base_dir / text, text, 0, text)


#: how many folders above the model's own a `package://` name is looked for in (ROS's `<pkg>/urdf/x.urdf` is 1)
PACKAGE_SEARCH_UP = 4


def package_bases(package: str, model_file: Path) -> list[Path]:
    """Where `package://NAME/...` may live when the robot names no `package_root`, in order: the model's
    folder and the folders above it (``PACKAGE_SEARCH_UP``), then each ROS_PACKAGE_PATH entry. Each
    place holds the package as `NAME/`, or is the package itself (its folder is called NAME)."""
    import os

    places = [model_file.parent.resolve(), *list(model_file.parent.resolve().parents)[:PACKAGE_SEARCH_UP]]
    places += [Path(p).resolve() for p in os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep) if p]
    bases: list[Path] = []
    for place in places:
        for base in ([place] if place.name == package else []) + [place / package]:
            if base not in bases:
                bases.append(base)
    return bases


def resolve_package(uri: str, package_root: Path | None, model_file: Path, line: int) -> Path:
    """`package://NAME/rest` -> `<package_root>/NAME/rest`, or without a package root the first of
    :func:`package_bases` holding `rest`; a plain path is relative to the model file. A result outside its
    root (the package, or the model's folder) is refused."""
    if uri.startswith("package://") and package_root is None:
        package, _, rest = uri[len("package://") :].partition("/")
        bases = package_bases(package, model_file)
        for base in bases:
            target = resolved(base / rest, model_file, line, uri)
            if not target.is_relative_to(base):
                raise ModelFileError(
                    model_file, line, f"the mesh `{uri}` resolves to {target}, outside its root {base}", near=uri
                )
            if target.is_file():
                return target
        raise ModelFileError(
            model_file,
            line,
            f"the mesh `{uri}` was not found in the package `{package}` (looked in {', '.join(map(str, bases[:3]))}"
            f"{', ...' if len(bases) > 3 else ''}); set the robot's `package_root` to the folder holding "
            f"`{package}/`, or ROS_PACKAGE_PATH",
            near=uri,
        )
    if uri.startswith("package://") and package_root is not None:
        root, target = package_root, resolved(package_root / uri[len("package://") :], model_file, line, uri)
    elif uri.startswith("file://"):
        root, target = model_file.parent.resolve(), resolved(Path(uri[len("file://") :]), model_file, line, uri)
    else:
        root, target = model_file.parent.resolve(), resolved(model_file.parent / uri, model_file, line, uri)
    if not target.is_relative_to(root.resolve()):
        raise ModelFileError(
            model_file, line, f"the mesh `{uri}` resolves to {target}, outside its root {root}", near=uri
        )
    if not target.is_file():
        hint = "; set the robot's `package_root`" if uri.startswith("package://") else ""
        raise ModelFileError(model_file, line, f"the mesh `{uri}` does not exist (looked for {target}){hint}", near=uri)
    return target


def quat_from_matrix(r: np.ndarray) -> Quat:
    """A unit quaternion (w, x, y, z, w >= 0) from a proper rotation matrix (Shepperd's method)."""
    m = r
    t = m[0, 0] + m[1, 1] + m[2, 2]
    if t > 0:
        s = math.sqrt(t + 1.0) * 2
        q = (0.25 * s, (m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s)
    elif m[0, 0] > m[1, 1] and m[0, 0] > m[2, 2]:
        s = math.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2]) * 2
        q = ((m[2, 1] - m[1, 2]) / s, 0.25 * s, (m[0, 1] + m[1, 0]) / s, (m[0, 2] + m[2, 0]) / s)
    elif m[1, 1] > m[2, 2]:
        s = math.sqrt(1.0 + m[1, 1] - m[0, 0] - m[2, 2]) * 2
        q = ((m[0, 2] - m[2, 0]) / s, (m[0, 1] + m[1, 0]) / s, 0.25 * s, (m[1, 2] + m[2, 1]) / s)
    else:
        s = math.sqrt(1.0 + m[2, 2] - m[0, 0] - m[1, 1]) * 2
        q = ((m[1, 0] - m[0, 1]) / s, (m[0, 2] + m[2, 0]) / s, (m[1, 2] + m[2, 1]) / s, 0.25 * s)
    n = math.sqrt(sum(c * c for c in q))
    sign = -1.0 if q[0] < 0 else 1.0
    return (sign * q[0] / n, sign * q[1] / n, sign * q[2] / n, sign * q[3] / n)


def principal_axes(tensor: np.ndarray) -> tuple[Vec3, Quat]:
    """Principal moments and the rotation from the given frame to the principal axes: a diagonal tensor keeps
    its axes and order (identity); otherwise the eigenvectors, ascending, made right-handed."""
    off = abs(tensor[0, 1]) + abs(tensor[0, 2]) + abs(tensor[1, 2])
    if off <= 1e-12 * max(float(np.abs(tensor).max()), 1e-300):
        return (float(tensor[0, 0]), float(tensor[1, 1]), float(tensor[2, 2])), (1.0, 0.0, 0.0, 0.0)
    moments, vectors = np.linalg.eigh((tensor + tensor.T) / 2.0)
    if np.linalg.det(vectors) < 0:
        vectors[:, 2] = -vectors[:, 2]
    m = tuple(float(max(v, 0.0)) for v in moments)
    return (m[0], m[1], m[2]), quat_from_matrix(vectors)


def vec(a: np.ndarray) -> Vec3:
    return (float(a[0]), float(a[1]), float(a[2]))


def quat4(a: np.ndarray) -> Quat:
    return (float(a[0]), float(a[1]), float(a[2]), float(a[3]))
