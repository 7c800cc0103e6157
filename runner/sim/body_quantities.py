"""Quantities that follow from a body's state and its mass properties, the same for every engine.

The states are those of the body frame (``backends/types.py``): ``p`` its origin, ``R`` its orientation, ``v``
the velocity of its origin, ``w`` its angular velocity (world frame). With ``c = R com`` the centre of mass
from the origin, ``v_c = v + w x c`` its velocity and ``I = R I_b R^T`` the inertia tensor about the centre
of mass in world axes (``I_b``: ``BodySpec.inertia_tensor()``):

* ``kinetic_energy`` (J): ``1/2 m |v_c|^2 + 1/2 w^T I w``;
* ``momentum`` (N s, world frame): ``m v_c``;
* ``angmom`` (N m s, world frame, about the body's **centre of mass**): ``I w``;
* ``angmom_origin`` (N m s, world frame, about the **world origin**): ``I w + (p + c) x m v_c``;
* ``angvel_body`` (rad/s, the body's own axes): ``R^T w``.

Each is a vector (or a scalar) per body; a group's getter gives the rows of its members.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from backends.geometry import quat_matrices
from backends.types import BodySpec, BodyStates

__all__ = ["BODY_VECTORS", "body_quantity"]

#: the vector quantities (x, y, z components) and the scalar one
BODY_VECTORS = ("momentum", "angmom", "angmom_origin", "angvel_body")
BODY_SCALAR = "kinetic_energy"


def body_quantity(
    name: str, specs: Sequence[BodySpec], rows: slice | np.ndarray, states: Callable[[], BodyStates]
) -> Callable[[], np.ndarray]:
    """A getter of ``name`` (one of :data:`BODY_VECTORS` or ``kinetic_energy``) for the bodies at ``rows`` of
    the states ``states()`` returns: an (N, 3) array, or (N,) for the kinetic energy."""
    mass = np.array([b.mass for b in specs], float)
    com = np.array([b.com for b in specs], float).reshape(-1, 3)
    tensor = np.array([b.inertia_tensor() for b in specs], float).reshape(-1, 3, 3)

    def parts() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(R, R com, v_c, w) of the bodies now."""
        s = states()
        rot = quat_matrices(s.quat[rows])
        arm = np.einsum("nij,nj->ni", rot, com)
        w = s.ang_vel[rows]
        return rot, arm, s.lin_vel[rows] + np.cross(w, arm), w

    def spin(rot: np.ndarray, w: np.ndarray) -> np.ndarray:
        """I w in world axes: R I_b R^T w."""
        wb = np.einsum("nji,nj->ni", rot, w)
        return np.einsum("nij,nj->ni", rot, np.einsum("nij,nj->ni", tensor, wb))

    def kinetic_energy() -> np.ndarray:
        rot, _, vc, w = parts()
        wb = np.einsum("nji,nj->ni", rot, w)
        return 0.5 * mass * np.add.reduce(vc * vc, axis=1) + 0.5 * np.einsum("ni,nij,nj->n", wb, tensor, wb)

    def momentum() -> np.ndarray:
        _, _, vc, _ = parts()
        return mass[:, None] * vc

    def angmom() -> np.ndarray:
        rot, _, _, w = parts()
        return spin(rot, w)

    def angmom_origin() -> np.ndarray:
        rot, arm, vc, w = parts()
        centre = states().pos[rows] + arm
        return spin(rot, w) + np.cross(centre, mass[:, None] * vc)

    def angvel_body() -> np.ndarray:
        rot, _, _, w = parts()
        return np.einsum("nji,nj->ni", rot, w)

    getters = {
        "kinetic_energy": kinetic_energy,
        "momentum": momentum,
        "angmom": angmom,
        "angmom_origin": angmom_origin,
        "angvel_body": angvel_body,
    }
    return getters[name]
