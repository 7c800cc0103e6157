"""The mass and inertia range one ODE island can resolve in single precision; wider ones are refused up front.

panda3d builds ODE with ``dSINGLE``: dWorldStep factorises each island's constraint matrix
A = J M^-1 J^T + CFM / h in float32, whose epsilon is 2^-23 (1.2e-7). A body's rows carry its inverse mass and
inverse inertia, so where one body of a jointed group weighs less than 2^-23 of another's (mass, or smallest
principal inertia against the group's largest), the heavy body's terms are below the rounding of the light
one's and the world's CFM (1e-5 / h = 5e-3 at h = 2 ms, against 1/I = 1.7e9 for dog's tail tip) no longer
regularises dependent rows: the LDLT meets an exact zero pivot and ODE's ``dIASSERT`` aborts the process.

Measured. dm_control's dog (issue 28's survey, h = 2 ms): its last tail vertebra Ca_21 has 6.0e-10 kg m^2 against
the group's largest principal inertia 0.026 kg m^2 (a ratio of 2.3e-8; mass 2.9e-4 kg, 1.1e-4 of the
heaviest). Landing, the tail's hinge stops and its floor contacts made the LCP singular: "assertion d[i] !=
dReal(0.0) failed in _dLDLTRemove" at step 161 of a 0.7 m drop. With the tail's stops removed, or its
contacts, it runs 1 s; with every principal inertia raised to at least 1e-6 kg m^2 it still aborts (step 254),
and a relative stop CFM ran at 1e-3 h / I but aborted at 1e-2 and 1e-5: no mapping change was found that holds,
so the range is refused. The rule is a bound on what float32 resolves, not a measured threshold.

Checked on the corpus (docs/robots.md, the survey): of pybullet_data's 91 loadable URDFs the smallest ratios
are 2.5e-6 (mass, racecar's camera_link) and 5.7e-6 (inertia, aliengo's imu_link); of the 45 MJCF files, four
fall below 2^-23: dog (2.3e-8 inertia), thrower (7.3e-8 mass, 7.2e-11 inertia: stopped by the energy
watchdog before), manipulator and stacker (their "pinch site" bodies, 2.1e-9: jointless, welded to the hand;
refused for `joint:mimic` before ODE had mimics, by this rule since. Lending the site the hand's inertia, and then
mass, keeping the pair's composite exact, let the rule pass, but ODE stayed at its zero pivot's edge there:
over six variants of the mimic solve each file ran in some and aborted in others (manipulator at 28 ms with a
coupling torque of 7e-8 N m; without the site it ran), so the rule stands).
The next are pusher (2.8e-7: runs) and humanoid_CMU (4.5e-6: runs).

Left out of the comparison: the light bodies that chain several joints of one body (backends/_kit/chains.py:
the mapping's own, at ``chain_light`` of their body, measured there), and bodies the joints hold still
(``_held``: they do not turn, and their inertia is raised where float32 needs it).
"""

from __future__ import annotations

from .._kit.components import components
from ..errors import UnsupportedFeature
from ..types import BodySpec, CompiledWorld, Motion
from ._held import FLOAT32_EPS, held_bodies


def jointed_groups(world: CompiledWorld, bodies: set[str]) -> dict[str, str]:
    """Each body's group: the bodies that joints between dynamic bodies connect (a chain's light bodies join
    their two neighbours); the representative of each."""
    dynamic = (b.name for b in world.bodies if b.motion is Motion.DYNAMIC)
    group = components(dynamic, ((j.body, j.other) for j in world.joints if j.other is not None))
    return {n: group[n] for n in bodies}


def check_ranges(world: CompiledWorld) -> None:
    """Refuse a jointed body whose mass or smallest principal inertia is below FLOAT32_EPS of its group's
    heaviest mass or largest principal inertia (module docstring)."""
    skip = world.chain_bodies | held_bodies(world)
    jointed = {j.body for j in world.joints} | {j.other for j in world.joints if j.other is not None}
    by_name = {b.name: b for b in world.bodies}
    checked = {n for n in jointed if n in by_name and by_name[n].motion is Motion.DYNAMIC and n not in skip}
    group = jointed_groups(world, checked)
    heaviest: dict[str, BodySpec] = {}
    widest: dict[str, BodySpec] = {}
    for name in sorted(checked):
        b, g = by_name[name], group[name]
        if g not in heaviest or b.mass > heaviest[g].mass:
            heaviest[g] = b
        if g not in widest or max(b.inertia) > max(widest[g].inertia):
            widest[g] = b
    ratios = []
    for name in sorted(checked):
        b, g = by_name[name], group[name]
        mass_ratio, inertia_ratio = b.mass / heaviest[g].mass, min(b.inertia) / max(widest[g].inertia)
        if min(mass_ratio, inertia_ratio) < FLOAT32_EPS:
            ratios.append((min(mass_ratio, inertia_ratio), mass_ratio, inertia_ratio, b, g))
    if not ratios:
        return
    _, mass_ratio, inertia_ratio, b, g = min(ratios, key=lambda r: r[0])
    others = f" (and {len(ratios) - 1} more)" if len(ratios) > 1 else ""
    raise UnsupportedFeature(
        f"Body `{b.name}`{others}: backend `ode`'s float32 solver cannot resolve its smallest principal inertia "
        f"{min(b.inertia):.3g} kg m^2 ({inertia_ratio:.2g} of `{widest[g].name}`'s "
        f"{max(widest[g].inertia):.3g}) or mass {b.mass:.3g} kg ({mass_ratio:.2g} of `{heaviest[g].name}`'s "
        f"{heaviest[g].mass:.3g}) in one jointed group: below 2^-23 = {FLOAT32_EPS:.2g}, it aborts on a zero pivot."
    )
