"""What the MuJoCo adapter reads from MjData after an engine step, as functions of the model and data: the
touching body pairs, the contact points and the watched joints' reactions (and, before anything is built,
which reactions MuJoCo can give). The adapter (``_backend``) calls them; MJWarp's reads its device copy.
"""

from __future__ import annotations

import mujoco
import numpy as np

from .._kit import contact_point, group_by_pair, sorted_points
from ..errors import UnsupportedFeature
from ..types import CompiledWorld, Contact, ContactPoint
from ._model import Layout

#: per watched joint: the MuJoCo body it hangs, +1/-1 (that body is the joint's first/other), the first body's id
ReactionRows = tuple[np.ndarray, np.ndarray, np.ndarray]


def touching(d: mujoco.MjData, owner: np.ndarray, bodies: int) -> list[Contact]:
    """Body pairs touching (distance <= 0) in the last engine step (MjData keeps them until the next); ``owner``:
    MuJoCo geom -> world body, of ``bodies`` bodies."""
    n = d.ncon
    if n == 0:
        return []
    c = d.contact
    dist, geom, rows = c.dist[:n], c.geom[:n], c.efc_address[:n]
    keep = dist <= 0.0
    if not keep.all():
        dist, geom, rows = dist[keep], geom[keep], rows[keep]
    # elliptic cone: a contact's first row is its normal; a contact at distance 0 is "in the gap":
    # touching, with no row (address -1, 0 N; efc_force[-1] is only read, then dropped, when nefc > 0)
    force = np.where(rows >= 0, d.efc_force[rows], 0.0) if d.nefc else np.zeros(rows.size)
    return group_by_pair(bodies, owner[geom[:, 0]], owner[geom[:, 1]], -dist, force)


def contact_points(m: mujoco.MjModel, d: mujoco.MjData, owner: np.ndarray, stepped: bool) -> list[ContactPoint]:
    """MjData's contacts of the last engine step (distance <= 0), read as columns: ``pos`` (midway between
    the surfaces), ``frame[:3]`` (the normal, from geom1 to geom2) and the normal force: on the elliptic
    cone the contact's first constraint row (as :func:`touching`), on a model's pyramidal cone
    ``mj_contactForce`` (its rows are the pyramid's edges). None before the first step (``stepped``)."""
    n = d.ncon if stepped else 0
    if n == 0:
        return []
    c = d.contact
    keep = np.flatnonzero(c.dist[:n] <= 0.0)
    rows = c.efc_address[keep]
    if m.opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC:
        force = np.where(rows >= 0, d.efc_force[rows] if d.nefc else 0.0, 0.0)
    else:
        force, wrench = np.zeros(len(keep)), np.zeros(6)
        for i, k in enumerate(keep.tolist()):
            if rows[i] >= 0:
                mujoco.mj_contactForce(m, d, k, wrench)
                force[i] = wrench[0]
    geom = c.geom[keep]
    columns = zip(owner[geom[:, 0]].tolist(), owner[geom[:, 1]].tolist(), c.pos[keep].tolist(),
                  c.frame[keep, :3].tolist(), (-c.dist[keep]).tolist(), force.tolist(), strict=True)  # fmt: skip
    return sorted_points([contact_point(*column) for column in columns])


def reaction_rows(world: CompiledWorld, m: mujoco.MjModel, lay: Layout) -> ReactionRows:
    """For each joint of ``world.reaction_joints``: the MuJoCo body it hangs (its child in the tree), +1 when
    that is the joint's first body and -1 when it is the other, and the first body's MuJoCo id."""
    index = {j.name: k for k, j in enumerate(world.joints)}
    hung = {edge.joint: name for name, edge in lay.edges.items() if edge.joint is not None}
    child, sign, first = [], [], []
    for name in world.reaction_joints:
        k = index[name]
        spec = world.joints[k]
        body = int(lay.body_id[world.body_index(spec.body)])
        if k in hung:
            below = int(lay.body_id[world.body_index(hung[k])])
        elif lay.joint_id[k] >= 0:  # a joint of a model built from its file
            below = int(m.jnt_bodyid[lay.joint_id[k]])
        else:
            below = -1
        other = int(lay.body_id[world.body_index(spec.other)]) if spec.other is not None else 0
        if below < 0 or below not in (body, other) or body == other or m.body_jntnum[below] > 1:
            raise UnsupportedFeature(
                f"mujoco: the reaction of joint `{name}` (its body is moved by several joints in one MuJoCo body, "
                f"or merged with the other: MuJoCo gives a body's wrench from its parent, not one joint's)"
            )
        child.append(below)
        sign.append(1.0 if below == body else -1.0)
        first.append(body)
    return np.array(child, dtype=np.intp), np.array(sign), np.array(first, dtype=np.intp)


def check_reactions(world: CompiledWorld) -> None:
    """Refuse, before anything is built, reading the reaction of a joint that shares its body with another joint
    of a model file (MJCF's several joints in one body, ``CompiledWorld.joint_chains``): MuJoCo's ``cfrc_int``
    is one wrench per body."""
    chained = {j: chain for chain in world.joint_chains for j in chain}
    by_name = {j.name: j for j in world.joints}
    for name in world.reaction_joints:
        if name in chained:
            body = by_name[name].body
            raise UnsupportedFeature(
                f"mujoco: the reaction of joint `{name}`: its body `{body}` is moved by several joints of the model "
                f"file, and MuJoCo gives one wrench per body (cfrc_int), not one per joint"
            )


def reactions_now(m: mujoco.MjModel, d: mujoco.MjData, rows: ReactionRows) -> np.ndarray:
    """The watched joints' wrenches on their first bodies in the engine step just taken, flattened (``rows``:
    :func:`reaction_rows`).

    ``mj_rnePostConstraint`` gives ``cfrc_int``: the wrench (torque, force) a body's parent applies to it
    through its joint, at the subtree centre of mass of its tree's root, world axes, from the step's
    accelerations and the kinematics the step was computed with (still in MjData after it). Moved to the
    world origin, turned to the first body (the opposite wrench where the tree hangs the joint from the
    other end) and moved to that body's centre of mass."""
    mujoco.mj_rnePostConstraint(m, d)
    child, sign, first = rows
    wrench = d.cfrc_int[child]
    force = sign[:, None] * wrench[:, 3:]
    origin = sign[:, None] * (wrench[:, :3] + np.cross(d.subtree_com[m.body_rootid[child]], wrench[:, 3:]))
    torque = origin - np.cross(d.xipos[first], force)
    return np.hstack((force, torque)).ravel()
