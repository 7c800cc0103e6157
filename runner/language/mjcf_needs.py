"""What an MJCF file holds beyond links and joints: tendons and equality constraints read for every engine, and
what only an engine reading the file itself runs (:attr:`ModelDesc.needs`).

**Tendons.** A tendon acts on the dynamics only through its own passive force (stiffness, damping, friction
loss, armature) and its length limit; otherwise it is a length MuJoCo computes for what uses it (an actuator's
transmission, an equality). So a tendon without any of those is *inert*: accepted on every engine, named in a
note (``ModelDesc.notes``) with what uses it. A tendon that acts is ``constraint:tendon``, named with what it
does at its line. An actuator on a tendon stays MuJoCo's (``ActuatorDesc.unmapped``: ``actuator:native`` when
the scenario drives it).

**Equalities.** MuJoCo's definitions (mj_instantiateEquality), with x = q - qpos0 each joint's position from the
zero configuration (the description's coordinates: runner.language.mjcf) and a tendon's length counted from its
length at qpos0 (``tendon_length0``), a fixed tendon's being sum(coef_i q_i):

* joint: x1 = polycoef[0] + polycoef[1] x2 (+ higher powers);
* tendon, one tendon: L1 - L1_0 = polycoef[0] (the other coefficients unused);
* tendon, two tendons: L1 - L1_0 = polycoef[0] + polycoef[1] (L2 - L2_0) (+ higher powers).

One that reduces to a linear relation between exactly two hinges or slides becomes a mimic
(:class:`MimicDesc`: follower = multiplier x leader + offset, in these coordinates), run by the engines that
declare ``joint:mimic`` (a ``joint:mimic`` need at the equality's line, so that the others' refusal names it):

* a joint equality of degree 1: joint1 follows joint2, multiplier polycoef[1], offset polycoef[0];
* one fixed tendon of two joints, a x_a + b x_b = polycoef[0] (dm_control's manipulator: -0.5 thumb + 0.5
  finger = 0): the tendon's second joint follows its first, multiplier -a / b, offset polycoef[0] / b;
* two fixed tendons of one joint each, c1 x1 = polycoef[0] + polycoef[1] c2 x2: x1 follows x2, multiplier
  polycoef[1] c2 / c1, offset polycoef[0] / c1.

An equality inactive at the start (``active="false"``) is inert: nothing in a scenario activates it. Every other
(connect, weld, flex, a joint held in place, a coupling of three or more joints, a spatial tendon's length, a
polynomial of higher degree) is ``constraint:equality``, named with why at its line. MuJoCo's equalities are
soft (solref, solimp); the engines' mimics hold as their own gear or coupler constraints (docs/robots.md).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from backends.types import Fluid
from runner.language.robot_desc import MimicDesc, ModelNeed

_SCALAR = (2, 3)  # mjJNT_SLIDE, mjJNT_HINGE
_WRAP_JOINT = 1  # mjWRAP_JOINT: a fixed tendon's every wrap
_EQUALITY_KINDS = {0: "a connect constraint", 1: "a weld constraint", 4: "a flex constraint"}  # mjtEq but 2, 3


@dataclass
class ModelConstraints:
    """What :func:`read_needs` found: the needs, the mimics (follower joint -> its mimic) and the notes."""

    mimics: dict[str, MimicDesc] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    fluid: Fluid | None = None  # the medium of MuJoCo's inertia-box fluid model (None: no fluid forces)
    _first: dict[str, tuple[str, int, int]] = field(default_factory=dict)  # capability -> (what, line, count)

    def need(self, capability: str, what: str, line: int) -> None:
        first = self._first.get(capability)
        self._first[capability] = (what, line, 1) if first is None else (first[0], first[1], first[2] + 1)

    @property
    def needs(self) -> list[ModelNeed]:
        """Each capability once, with its first instance and how many more there are."""
        return [ModelNeed(capability, what if count == 1 else f"{what} (and {count - 1} more)", line)
                for capability, (what, line, count) in self._first.items()]  # fmt: skip


def section_lines(tree: Any, section: str, count: int, names: list[str]) -> list[int]:
    """The line of each of the ``count`` compiled elements of the file's top-level ``section`` (`<tendon>`,
    `<equality>`): the k-th child element when the main file holds exactly ``count`` (MuJoCo's order is the
    file's), else by name, else the section's line (0: none in the main file)."""
    sections = [e for e in tree.getroot() if e.tag == section]
    children = [c for s in sections for c in s if isinstance(c.tag, str)]
    first = (sections[0].sourceline or 0) if sections else 0
    if len(children) == count:
        return [c.sourceline or first for c in children]
    by_name = {c.get("name"): c.sourceline or first for c in children if c.get("name")}
    return [by_name.get(name, first) if name else first for name in names]


def _fixed_joints(model: Any, t: int) -> dict[int, float] | None:
    """A fixed tendon's joints and coefficients (a joint named twice summed, zeros dropped); None: spatial."""
    adr, num = int(model.tendon_adr[t]), int(model.tendon_num[t])
    out: dict[int, float] = {}
    for w in range(adr, adr + num):
        if int(model.wrap_type[w]) != _WRAP_JOINT:
            return None
        joint = int(model.wrap_objid[w])
        out[joint] = out.get(joint, 0.0) + float(model.wrap_prm[w])
    return {j: c for j, c in out.items() if c != 0.0}


def _acts(model: Any, t: int) -> list[str]:
    """What a tendon exerts on the dynamics itself (empty: it is inert)."""
    armature = getattr(model, "tendon_armature", None)  # MuJoCo 3.2 and later
    forces = {
        "stiffness": model.tendon_stiffness[t],
        "damping": model.tendon_damping[t],
        "friction loss": model.tendon_frictionloss[t],
        "armature": 0.0 if armature is None else armature[t],
    }
    found = [what for what, value in forces.items() if value != 0.0]  # fmt: skip
    if model.tendon_limited[t]:
        lo, hi = (float(v) for v in model.tendon_range[t])
        found.append(f"length limit [{lo:g}, {hi:g}]")
    return found


def _users(model: Any, mujoco: Any) -> dict[int, list[str]]:
    """Tendon -> what uses it: actuators (transmissions) and equalities."""
    out: dict[int, list[str]] = {}
    for a in range(model.nu):
        if int(model.actuator_trntype[a]) == int(mujoco.mjtTrn.mjTRN_TENDON):
            name = model.actuator(a).name or f"actuator_{a}"
            out.setdefault(int(model.actuator_trnid[a][0]), []).append(f"actuator `{name}`'s transmission")
    for e in range(model.neq):
        if int(model.eq_type[e]) == int(mujoco.mjtEq.mjEQ_TENDON):
            name = model.eq(e).name or f"equality_{e}"
            for t in (int(model.eq_obj1id[e]), int(model.eq_obj2id[e])):
                if t >= 0:
                    out.setdefault(t, []).append(f"equality `{name}`")
    return out


def _tendons(model: Any, mujoco: Any, tree: Any, names: list[str], found: ModelConstraints) -> None:
    lines = section_lines(tree, "tendon", model.ntendon, [model.tendon(t).name for t in range(model.ntendon)])
    users = _users(model, mujoco)
    inert = []
    for t, name in enumerate(names):
        acts = _acts(model, t)
        if acts:
            found.need("constraint:tendon", f"tendon `{name}`'s {', '.join(acts)}", lines[t])
        else:
            inert.append(f"`{name}` ({', '.join(users.get(t, ['unused']))})")
    if inert:
        found.notes.append("tendons without a force of their own (no stiffness, damping, friction loss, armature or "
                           f"length limit), inert on every engine: {', '.join(inert)}")  # fmt: skip


#: a coupling of two joints: (follower, leader, multiplier, offset), joints by index
Coupling = tuple[int, int, float, float]


def _tendon_pair(model: Any, e: int, joints: list[str], tendons: list[str]) -> Coupling | str:
    """A tendon equality's coupling (module docstring), or why it is none."""
    data = [float(v) for v in model.eq_data[e][:5]]
    t1, t2 = int(model.eq_obj1id[e]), int(model.eq_obj2id[e])
    first = _fixed_joints(model, t1)
    second = _fixed_joints(model, t2) if t2 >= 0 else {}
    if first is None or second is None:
        spatial = tendons[t1] if first is None else tendons[t2]
        return f"holds spatial tendon `{spatial}`'s length, which no coupling of two joints expresses"
    if t2 < 0:
        if len(first) != 2:
            named = ", ".join(f"`{joints[j]}`" for j in first)
            what = "a joint held in place" if len(first) < 2 else f"a coupling of {len(first)} joints ({named})"
            return f"holds tendon `{tendons[t1]}` at a length: {what}, where a mimic couples two"
        (lead, a), (follow, b) = first.items()
        return follow, lead, -a / b, data[0] / b
    both = f"tendons `{tendons[t1]}` and `{tendons[t2]}`"
    if len(first) != 1 or len(second) != 1:
        return f"relates {both} of {len(first)} and {len(second)} joints, where a mimic couples one joint to one"
    if any(data[2:]):
        return f"relates {both} by a polynomial of degree above 1 ({_poly(data)})"
    (j1, c1), (j2, c2) = next(iter(first.items())), next(iter(second.items()))
    if j1 == j2 or data[1] == 0.0:
        return f"holds joint `{joints[j1]}` in place through {both}"
    return j1, j2, data[1] * c2 / c1, data[0] / c1


def _poly(data: list[float]) -> str:
    return "polycoef " + " ".join(f"{v:g}" for v in data)


def _joint_pair(model: Any, e: int, joints: list[str]) -> Coupling | str:
    """A joint equality's coupling (module docstring), or why it is none."""
    data = [float(v) for v in model.eq_data[e][:5]]
    j1, j2 = int(model.eq_obj1id[e]), int(model.eq_obj2id[e])
    if j2 < 0 or data[1] == 0.0:
        return f"holds joint `{joints[j1]}` in place"
    if any(data[2:]):
        return f"relates joints `{joints[j1]}` and `{joints[j2]}` by a polynomial of degree above 1 ({_poly(data)})"
    return j1, j2, data[1], data[0]


def _not_mimic(model: Any, joints: list[str], pair: Coupling, mimics: dict[str, MimicDesc]) -> str | None:
    """Why a coupling cannot be a mimic (None: it can): both joints hinges or slides, the follower held by no
    earlier equality, no loop of followers."""
    follow, lead = joints[pair[0]], joints[pair[1]]
    if any(int(model.jnt_type[j]) not in _SCALAR for j in pair[:2]):
        return f"couples joints `{follow}` and `{lead}`, which are not both hinges or slides"
    if follow in mimics:
        return f"holds joint `{follow}`, which an earlier equality holds already"
    at, seen = lead, 0
    while at in mimics and at != follow and seen <= len(mimics):
        at, seen = mimics[at].leader, seen + 1
    return f"closes a loop of coupled joints at `{follow}`" if at == follow else None


def _equalities(model: Any, mujoco: Any, tree: Any, joints: list[str], tendons: list[str],
                found: ModelConstraints) -> None:  # fmt: skip
    names = [model.eq(e).name or f"equality_{e}" for e in range(model.neq)]
    lines = section_lines(tree, "equality", model.neq, [model.eq(e).name for e in range(model.neq)])
    inactive = []
    for e, name in enumerate(names):
        kind = int(model.eq_type[e])
        if not model.eq_active0[e]:
            inactive.append(f"`{name}`")
            continue
        pair: Coupling | str
        if kind == int(mujoco.mjtEq.mjEQ_JOINT):
            pair = _joint_pair(model, e, joints)
        elif kind == int(mujoco.mjtEq.mjEQ_TENDON):
            pair = _tendon_pair(model, e, joints, tendons)
        else:
            pair = _EQUALITY_KINDS.get(kind, f"an equality of type {kind}")
        if not isinstance(pair, str):
            pair = _not_mimic(model, joints, pair, found.mimics) or pair
        if isinstance(pair, str):
            found.need("constraint:equality", f"equality `{name}`: {pair}", lines[e])
            continue
        follow, lead, multiplier, offset = joints[pair[0]], joints[pair[1]], pair[2], pair[3]
        found.mimics[follow] = MimicDesc(lead, multiplier, offset)
        found.need("joint:mimic", f"equality `{name}`: joint `{follow}` follows `{lead}`", lines[e])
        shift = f" {'-' if offset < 0 else '+'} {abs(offset):.6g}" if offset else ""
        found.notes.append(f"equality `{name}`: joint `{follow}` = {multiplier:.6g} x `{lead}`{shift} from the zero "
                           "configuration, a mimic joint (joint:mimic); MuJoCo holds it softly, by the equality's "
                           "solref and solimp")  # fmt: skip
    if inactive:
        found.notes.append(f"equalities inactive at the start (`active=\"false\"`), which no scenario activates, not "
                           f"simulated: {', '.join(inactive)}")  # fmt: skip


def first_line(tree: Any, tag: str) -> int:
    found = next(iter(tree.getroot().iter(tag)), None)
    return (found.sourceline or 0) if found is not None else 0


def _has_dynamics(model: Any, j: int) -> bool:
    dofs = slice(int(model.jnt_dofadr[j]), int(model.jnt_dofadr[j]) + (6 if int(model.jnt_type[j]) == 0 else 3))
    return bool(np.any(model.dof_damping[dofs] != 0) or np.any(model.dof_frictionloss[dofs] != 0)
                or np.any(model.dof_armature[dofs] != 0) or model.jnt_stiffness[j] != 0)  # fmt: skip


def read_needs(model: Any, mujoco: Any, tree: Any, bodies: list[str], joints: list[str],
               lines: dict[tuple[str, str], int]) -> ModelConstraints:  # fmt: skip
    """The file's needs (each capability once, with its first instance: runner.language.mjcf), mimics and
    notes."""
    found = ModelConstraints()
    for b in range(1, model.nbody):  # several joints in one body are every engine's (CompiledWorld.joint_chains)
        if model.body_mass[b] <= 0 and int(model.body_jntnum[b]) > 0:
            found.need("body:massless", f"body `{bodies[b]}` moves but has no mass", lines.get(("body", bodies[b]), 0))
    for j in range(model.njnt):  # damping and friction loss of hinges and slides are every engine's (the runner's)
        dof, name = int(model.jnt_dofadr[j]), joints[j]
        line = lines.get(("joint", name), first_line(tree, "joint"))
        if int(model.jnt_type[j]) in (0, 1) and _has_dynamics(model, j):
            found.need("joint:ball-dynamics", f"joint `{name}`'s damping, friction loss, armature or stiffness", line)
        elif model.dof_armature[dof] > 0:
            found.need("joint:armature", f"joint `{name}`'s armature", line)
        if int(model.jnt_type[j]) in _SCALAR and model.jnt_stiffness[j] > 0:
            found.need("joint:stiffness", f"joint `{name}`'s stiffness", line)
    if any(model.jnt_limited[j] and int(model.jnt_type[j]) == 1 for j in range(model.njnt)):
        found.need("joint:ball-range", "a ball joint's range", first_line(tree, "joint"))
    tendons = [model.tendon(t).name or f"tendon_{t}" for t in range(model.ntendon)]
    _equalities(model, mujoco, tree, joints, tendons, found)
    _tendons(model, mujoco, tree, tendons, found)
    if model.npair:
        found.need("collision:explicit-pairs", "<contact><pair>", first_line(tree, "pair"))
    found.fluid = _fluid(model, mujoco, tree, bodies, lines, found)
    return found


def _fluid(model: Any, mujoco: Any, tree: Any, bodies: list[str], lines: dict[tuple[str, str], int],
           found: ModelConstraints) -> Fluid | None:  # fmt: skip
    """The file's medium when MuJoCo's fluid forces act (mj_fluid: density or viscosity above 0, and passive
    forces not all disabled; wind alone moves nothing); a geom's `fluidshape="ellipsoid"` (MuJoCo's per-geom
    model, which replaces the inertia box for its body) is `world:fluid-ellipsoid`, MuJoCo's alone."""
    off = int(mujoco.mjtDisableBit.mjDSBL_SPRING) | int(mujoco.mjtDisableBit.mjDSBL_DAMPER)
    if not (model.opt.density > 0 or model.opt.viscosity > 0) or int(model.opt.disableflags) & off == off:
        return None
    for g in range(model.ngeom):
        b = int(model.geom_bodyid[g])
        if model.geom_fluid[g][0] > 0 and model.body_mass[b] > 0:
            geom = model.geom(g).name or f"geom_{g}"
            line = lines.get(("geom", geom), first_line(tree, "geom"))
            found.need("world:fluid-ellipsoid", f"geom `{geom}` of body `{bodies[b]}`: fluidshape=\"ellipsoid\" "
                       "(MuJoCo's per-geom fluid model)", line)  # fmt: skip
    wind = model.opt.wind
    fluid = Fluid(float(model.opt.density), float(model.opt.viscosity), (float(wind[0]), float(wind[1]),
                                                                         float(wind[2])))  # fmt: skip
    found.notes.append(f"fluid (`<option>`, line {first_line(tree, 'option')}): density {fluid.density:g} kg/m^3, "
                       f"viscosity {fluid.viscosity:g} Pa s, wind {list(fluid.wind)} m/s, MuJoCo's inertia-box model "
                       "on every dynamic body, every engine (docs/semantics.md, \"Fluid forces\")")  # fmt: skip
    return fluid
