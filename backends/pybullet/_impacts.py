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

import numpy as np
import pybullet as p

#: Bullet's default contact ERP (``m_erp2``) as PhysicsServerCommandProcessor sets it [read], and as the
#: push-out of a 3.955 mm penetration at h 0.01 measures it: 0.03156 m/s = erp2 * depth / h.
DEFAULT_CONTACT_ERP = 0.08


class ImpactErp:
    """Per substep: contact ERP 0 when a bouncing contact is hit, Bullet's default otherwise."""

    def __init__(
        self, c: int, lut: list[list[int]], restitution: Sequence[float], threshold: float, gravity_kick: float
    ) -> None:
        self._c = c
        self._lut = lut  # (multibody, link + 1) -> body index
        self._bounces = [r > 0.0 for r in restitution]
        #: Bullet bounces when the approach speed after the substep's gravity exceeds ``threshold``.
        self._threshold = threshold - gravity_kick
        self._off = False
        self.active = any(self._bounces)

    def before_substep(self, rows: Callable[[], np.ndarray]) -> None:
        """Set the contact ERP for the coming substep; ``rows()`` gives the bodies' states (13 per row)."""
        c = self._c
        p.performCollisionDetection(physicsClientId=c)
        impact = self._impact(p.getContactPoints(physicsClientId=c), rows)
        if impact != self._off:
            p.setPhysicsEngineParameter(contactERP=0.0 if impact else DEFAULT_CONTACT_ERP, physicsClientId=c)
            self._off = impact

    def _impact(self, points: Sequence[tuple], rows: Callable[[], np.ndarray]) -> bool:
        lut, bounces = self._lut, self._bounces
        state: np.ndarray | None = None
        for cp in points:
            a, b = lut[cp[1]][cp[3] + 1], lut[cp[2]][cp[4] + 1]
            if not (bounces[a] and bounces[b]):
                continue
            if state is None:
                state = rows()
            normal = np.asarray(cp[7])  # on B, pointing towards A
            rel = _point_velocity(state[a], cp[5]) - _point_velocity(state[b], cp[6])
            if -float(rel @ normal) > self._threshold:
                return True
        return False


def _point_velocity(row: np.ndarray, point: Sequence[float]) -> np.ndarray:
    """A body's velocity at a world point: v + w x (p - x), the row's position being its centre of mass."""
    return row[7:10] + np.cross(row[10:13], np.asarray(point) - row[0:3])
