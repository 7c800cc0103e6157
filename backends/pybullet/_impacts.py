"""Bullet's contact ERP off for the substeps in which a bouncing contact is hit (ODE's bounce, not a sum).

A btMultiBody contact row asks for ``e*v + erp2*depth/h``: the push-out of the landing step's
penetration is added to the rebound (+0.047 on e 0.5 at 1 m/s, dt 0.5-4 ms; more at 4.4 m/s), where
ODE's row takes the larger of the two. Split impulse would keep them apart, but Bullet implements it for
rigid bodies only (``useSplitImpulse`` changes nothing on multibodies, measured); ``contactERP`` 0 for
good leaves penetrations for ever (a ball dropped 1 m at dt 10 ms rests 1.5 cm deep). So, in worlds where
a pair bounces, each substep first runs Bullet's collision detection at the current poses (the contacts
its step will use) and, when a bouncing pair approaches faster than the restitution threshold, sets the
contact ERP to 0 for that substep only; otherwise Bullet's default is back. Worlds without bouncing
pairs never call it: their steps are Bullet's own.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from operator import itemgetter

import numpy as np
import pybullet as p

#: A contact point's bodyUniqueIdA, bodyUniqueIdB, linkIndexA, linkIndexB; positionOnA, positionOnB and
#: contactNormalOnB (pointing towards A).
_IDS, _GEOMETRY = itemgetter(1, 2, 3, 4), itemgetter(5, 6, 7)
#: Bullet's default contact ERP (``m_erp2``) as PhysicsServerCommandProcessor sets it [read], and as the
#: push-out of a 3.955 mm penetration at h 0.01 measures it: 0.03156 m/s = erp2 * depth / h.
DEFAULT_CONTACT_ERP = 0.08


class ImpactErp:
    """Per substep: contact ERP 0 when a bouncing contact is hit, Bullet's default otherwise."""

    def __init__(
        self, c: int, lut: list[list[int]], restitution: Sequence[float], threshold: float, gravity_kick: float
    ) -> None:
        self._c = c
        self._lut = np.array(lut, dtype=np.int64)  # (multibody, link + 1) -> body index
        self._bounces = np.array([r > 0.0 for r in restitution], dtype=bool)
        #: Bullet bounces when the approach speed after the substep's gravity exceeds ``threshold``.
        self._threshold = threshold - gravity_kick
        self._off = False
        self.active = bool(self._bounces.any())

    def before_substep(self, rows: Callable[[], np.ndarray]) -> None:
        """Set the contact ERP for the coming substep; ``rows()`` gives the bodies' states (13 per row)."""
        c = self._c
        p.performCollisionDetection(physicsClientId=c)
        impact = self._impact(p.getContactPoints(physicsClientId=c), rows)
        if impact != self._off:
            p.setPhysicsEngineParameter(contactERP=0.0 if impact else DEFAULT_CONTACT_ERP, physicsClientId=c)
            self._off = impact

    def _impact(self, points: Sequence[tuple], rows: Callable[[], np.ndarray]) -> bool:
        """Whether a bouncing pair's contact point approaches faster than the threshold (vectorised:
        a pile's resting contacts are many)."""
        if not points:
            return False
        ids = np.array(list(map(_IDS, points)), dtype=np.int64)
        a, b = self._lut[ids[:, 0], ids[:, 2] + 1], self._lut[ids[:, 1], ids[:, 3] + 1]
        keep = self._bounces[a] & self._bounces[b]
        if not keep.any():
            return False
        kept = [cp for cp, k in zip(points, keep.tolist(), strict=True) if k]
        a, b = a[keep], b[keep]
        geometry = np.array(list(map(_GEOMETRY, kept)), dtype=np.float64).reshape(-1, 3, 3)  # on A, on B, normal
        state = rows()
        rel = _point_velocity(state[a], geometry[:, 0]) - _point_velocity(state[b], geometry[:, 1])
        approach = -np.einsum("ij,ij->i", rel, geometry[:, 2])
        return bool((approach > self._threshold).any())


def _point_velocity(rows: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Bodies' velocities at world points: v + w x (p - x), a row's position being its centre of mass."""
    return rows[:, 7:10] + np.cross(rows[:, 10:13], points - rows[:, 0:3])
