"""Load the models a scenario names (``robots:``) and check the names its overrides use.

Model files are read once per load; a problem in one is an issue naming the *model file* and line (exit 2).
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path as FsPath

from runner.errors import Issue, ScenarioValidationError
from runner.language.model import Scenario
from runner.language.model_robots import Robot
from runner.language.robot_desc import ModelDesc, ModelFileError, data_root, line_column, resolve_file
from runner.language.semantics import unknown
from runner.language.yaml_source import Positions

#: What a robot's link or joint may not be called: the fields read after it (`arm.pos.x` would be ambiguous).
FIELD_NAMES = frozenset({"pos", "vel", "angvel", "quat", "speed", "energy", "position", "velocity", "force"})


def package_root(robot: Robot, model_file: FsPath, base_dir: FsPath) -> FsPath | None:
    """The robot's `package_root`; None: `package://` names are looked for near the model file and on
    ROS_PACKAGE_PATH (runner.language.robot_desc.package_bases)."""
    del model_file  # the search starts from it (package_bases)
    if robot.package_root is not None:
        return resolve_file(robot.package_root, base_dir)
    return None


def load_model(robot: Robot, base_dir: FsPath) -> ModelDesc:
    """Read one robot's model file (raises ModelFileError)."""
    file = resolve_file(robot.file, base_dir)
    rooted = data_root(robot.file)
    root = rooted[0].resolve() if rooted is not None else base_dir.resolve()
    if not file.is_relative_to(root):
        raise ModelFileError(file, 0, f"the model file must be inside {root}; found {robot.file!r}")
    try:
        info = file.stat() if file.is_file() else None
    except OSError as exc:  # a name the system refuses (too long, ...): the scenario's line, not a crash
        raise ModelFileError(file, 0, f"no model file at {file} ({exc.strerror or exc})") from None
    if info is None:
        raise ModelFileError(file, 0, f"no model file at {file}")
    triangles = robot.static_meshes == "triangles"
    return _read(robot.format, file, package_root(robot, file, base_dir), robot.fixed, triangles, info.st_mtime_ns)


@lru_cache(maxsize=32)
def _read(kind: str, file: FsPath, packages: FsPath | None, fixed: bool, triangles: bool, mtime_ns: int) -> ModelDesc:
    """One model file's description, read once per content version (every variant of a scenario, and every
    scenario of a folder, shares it; the file's modification time keys an edited file anew)."""
    del mtime_ns  # part of the cache key only
    if kind == "urdf":
        from runner.language.urdf import load_urdf

        return load_urdf(file, packages, fixed, triangles)
    from runner.language.mjcf import load_mjcf

    return load_mjcf(file)


def load_robots(model: Scenario, positions: Positions, base_dir: FsPath) -> dict[str, ModelDesc]:
    """Every robot's model, its override names checked; the issues of all robots raised together."""
    out: dict[str, ModelDesc] = {}
    issues: list[Issue] = []
    for name, robot in model.robots.items():
        where = ("robots", name, robot.format)
        try:
            desc = load_model(robot, base_dir)
        except ModelFileError as exc:
            if exc.line <= 0:  # no place in the model file (it is missing, unreadable): the scenario's line
                issues.append(positions.issue(where, exc.message))
            else:
                issues.append(Issue(exc.file, exc.line, exc.column, ".".join(str(p) for p in where), exc.message))
            continue
        out[name] = desc
        links = {link.name for link in desc.links}
        joints = {joint.name for joint in desc.joints}
        for kind, names in (("link", links), ("joint", joints)):
            clash = sorted(names & FIELD_NAMES)
            if clash:
                issues.append(
                    positions.issue(
                        where,
                        f"the model's {kind} `{clash[0]}` has the name of a field "
                        f"(`{name}.{clash[0]}` would be ambiguous); rename it in the model",
                    )
                )
        for jname, override in robot.joints.items():
            joint = next((j for j in desc.joints if j.name == jname), None)
            if joint is None:
                issues.append(positions.issue(("robots", name, "joints", jname), unknown("joint", jname, joints), True))
            elif joint.kind not in ("hinge", "slider") and (
                override.motor or override.servo or override.drive or override.limits or override.free
            ):
                message = (
                    f"joint `{jname}` is a {joint.kind} joint in the model; it takes no motor, servo, drive or limits"
                )
                issues.append(positions.issue(("robots", name, "joints", jname), message, True))
        actuators = [a.name for a in desc.actuators]
        for aname in robot.actuators:
            if aname not in actuators:
                what = "actuator (MJCF <actuator>)" if robot.format == "mjcf" else "actuator (a URDF has none)"
                issues.append(positions.issue(("robots", name, "actuators", aname), unknown(what, aname, actuators),
                                              True))  # fmt: skip
        for lname in robot.links:
            if lname not in links:
                issues.append(positions.issue(("robots", name, "links", lname), unknown("link", lname, links), True))
        for i, pair in enumerate(robot.exclude):
            for j, ref in enumerate(pair):
                if ref not in links:
                    issues.append(positions.issue(("robots", name, "exclude", i, j), unknown("link", ref, links)))
        root = desc.link(desc.root)
        if root.mass <= 0 and not robot.fixed and robot.format == "urdf":
            issues.append(
                Issue(
                    desc.file,
                    root.line,
                    line_column(desc.file, root.line),
                    f"robots.{name}.fixed",
                    f"root link `{root.name}` has no mass; a free model needs one (or `fixed: true`)",
                )
            )
        for link in desc.links:  # MJCF: MuJoCo's compiler judged the masses; a massless one is a need (mjcf.py)
            if link.name != desc.root and link.mass <= 0 and robot.format == "urdf":
                issues.append(
                    Issue(
                        desc.file,
                        link.line,
                        line_column(desc.file, link.line),
                        f"robots.{name}",
                        f"link `{link.name}` has no mass (no <inertial> or mass 0); a moving link needs one",
                    )
                )
    issues.extend(model_options_issues(model, positions, out))
    if issues:
        raise ScenarioValidationError(issues)
    return out


def model_options_issues(model: Scenario, positions: Positions, descs: dict[str, ModelDesc]) -> list[Issue]:
    """`world.options: model` needs one MJCF robot whose `<option>` timestep is the scenario's engine step
    (dt / substeps) and whose gravity is the scenario's: the scenario states them (its times are read with
    them), the check keeps the two from disagreeing."""
    if model.world.options != "model":
        return []
    where = ("world", "options")
    mjcf = [(name, descs[name]) for name, robot in model.robots.items() if robot.format == "mjcf" and name in descs]
    if len(mjcf) != 1 or len(model.robots) != 1:
        return [positions.issue(where, f"`options: model` takes the options of one MJCF robot; found "
                                f"{len(mjcf)} MJCF and {len(model.robots) - len(mjcf)} other robots")]  # fmt: skip
    _, desc = mjcf[0]
    issues = []
    if model.world.fluid is not None:
        issues.append(positions.issue(("world", "fluid"), "with `options: model` the fluid is the model's "
                                      "`<option density viscosity wind>`; leave `fluid` out"))  # fmt: skip
    step = model.world.dt / model.world.substeps
    if desc.timestep is not None and abs(step - desc.timestep) > 1e-12 * desc.timestep:
        issues.append(positions.issue(("world", "dt"), f"with `options: model` the engine step dt / substeps "
                                      f"({step:g} s) must be the model's timestep {desc.timestep:g} s"))  # fmt: skip
    if desc.gravity is not None and any(
        abs(a - b) > 1e-12 for a, b in zip(model.world.gravity, desc.gravity, strict=True)
    ):
        issues.append(positions.issue(("world", "gravity"), f"with `options: model` gravity must be the "
                                      f"model's {list(desc.gravity)}; found {list(model.world.gravity)}"))  # fmt: skip
    return issues
