"""Contact generation: collide, one contact joint per contact point with the pair's surface, report.

Two ways, selected by the ``collide`` option, that make the same contact joints:

* ``auto`` (default): ``OdeSpace.autoCollide()`` runs ODE's near-callback in C++. Every body in a pair
  override gets its own surface class (``space.setSurfaceType``), the others share class 0, and
  ``world.setSurfaceEntry`` fills the class-by-class table. panda3d's entry always uses the mode
  ``dContactBounce | dContactSoftCFM | dContactApprox1``; soft CFM is set to the world's CFM, which is
  what ODE uses for a contact without it, so the rows equal the callback's. It makes at most 16 contacts
  per pair (ODE's primitive colliders make at most 12 here, box-cylinder).
* ``callback``: the lab's pattern, ``space.collide`` with a Python near-callback, ``OdeUtil.collide``
  (150 contacts at most) and an ``OdeContactJoint`` per contact, mode ``dContactBounce | dContactApprox1``.

``dContactApprox1`` makes ODE bound friction by mu times the normal force (a Coulomb coefficient, the
scenario language's meaning) instead of by mu newtons. The report (pairs, points, depth) comes from
the last substep's collision; with ``contact_forces`` the normal force is read from joint feedback.
"""

from __future__ import annotations

import math
from typing import Any

from panda3d.core import EventQueue
from panda3d.ode import (
    OdeContact,
    OdeContactJoint,
    OdeJoint,
    OdeJointFeedback,
    OdeSurfaceParameters,
    OdeUtil,
)

from ..types import Contact, Surface
from ._build import MAX_SURFACE_CLASSES, Scene

CALLBACK_MAX_CONTACTS = 150  # PyODE's ode.collide() default, as the lab calls it
_MODE = OdeSurfaceParameters.MFContactBounce | OdeSurfaceParameters.MFContactApprox1


class _Pair:
    """One touching pair in the last substep: its contact geoms and (when armed) feedback slots."""

    __slots__ = ("a", "b", "geoms", "owner", "start", "feedback")

    def __init__(self, i: int, j: int, geoms: tuple[Any, ...]) -> None:
        self.a, self.b = (i, j) if i < j else (j, i)
        self.geoms = geoms  # OdeContactGeom, in ODE's order
        self.owner = -1  # the body whose joint list holds this pair's contact joints
        self.start = 0  # how many contacts that body had in earlier pairs of this collide
        self.feedback: list[OdeJointFeedback] = []


class Collider:
    """Makes the contact joints of one substep and remembers the last reported one."""

    def __init__(self, scene: Scene, mode: str, contact_forces: bool, event_name: str) -> None:
        self.scene = scene
        self.contact_forces = contact_forces
        self._event = event_name
        self._pool: list[OdeJointFeedback] = []
        self._used = 0
        self._pairs: list[_Pair] = []
        self._report: list[Contact] | None = []
        self._reported: list[_Pair] = []
        self._seen: dict[int, int] = {}
        classes = max(scene.surface_class, default=0) + 1
        # autoCollide's table is indexed by a byte; beyond that, the callback does every pair.
        self.mode = mode if classes <= MAX_SURFACE_CLASSES else "callback"
        if self.mode == "auto":
            world, space = scene.world, scene.space
            world.initSurfaceTable(classes)
            cfm = world.getCfm()
            for (i, j), s in scene.surfaces.items():
                if i <= j:
                    world.setSurfaceEntry(i, j, _mu(s), s.bounce, s.bounce_vel, 0.0, cfm, 0.0, 0.0)
            space.setAutoCollideWorld(world)
            space.setAutoCollideJointGroup(scene.contact_group)
            for geom, cls in zip(scene.geoms, scene.surface_class, strict=True):
                space.setSurfaceType(geom, cls)
        else:
            self._params = {key: _surface_parameters(s) for key, s in scene.surfaces.items()}

    # --- per substep ---------------------------------------------------------------------------------

    def collide(self, report: bool) -> None:
        """Make this substep's contact joints; with ``report``, record the pairs (and arm feedback)."""
        self._pairs = []
        self._used = 0
        if self.mode == "auto":
            self.scene.space.setCollisionEvent(self._event if report else "")
            self.scene.space.autoCollide()
            if report:
                self._drain_events()
                if self.contact_forces:
                    self._arm_auto_feedback()
        else:
            self.scene.space.collide(report, self._near_callback)

    def after_step(self, report: bool) -> None:
        """Keep the reported pairs (read lazily: feedback was filled by the step), empty the group."""
        if report:
            self._report = None
            self._reported = self._pairs
        self.scene.contact_group.empty()

    def contacts(self) -> list[Contact]:
        if self._report is None:
            pairs = sorted(self._reported, key=lambda p: (p.a, p.b))
            self._report = [_summary(p) for p in pairs]
        return list(self._report)

    # --- auto ----------------------------------------------------------------------------------------

    def _drain_events(self) -> None:
        queue = EventQueue.getGlobalEventQueue()
        index, bodies = self.scene.geom_index, self.scene.bodies
        seen: dict[int, int] = {}  # body index -> contacts so far (its contact joints, oldest first)
        others = []
        while not queue.isQueueEmpty():
            event = queue.dequeueEvent()
            if event.name != self._event:
                others.append(event)
                continue
            entry = event.getParameter(0).getPtr().getValue()  # OdeCollisionEntry
            i, j = index[hash(entry.getGeom1().getId())], index[hash(entry.getGeom2().getId())]
            pair = _Pair(i, j, entry.getContactGeoms())
            pair.owner = i if bodies[i] is not None else j
            pair.start = seen.get(pair.owner, 0)
            for x in (i, j):
                if bodies[x] is not None:
                    seen[x] = seen.get(x, 0) + len(pair.geoms)
            self._pairs.append(pair)
        self._seen = seen
        for event in others:  # not ours: put back
            queue.queueEvent(event)

    def _arm_auto_feedback(self) -> None:
        """Attach feedback to the contact joints autoCollide made (C++ objects we hold no handle to).

        ODE prepends each joint to its bodies' joint lists, so a body's first K joints are its K newest
        contact joints, newest first; their creation order is the collision events' order.
        """
        bodies, seen, pool = self.scene.bodies, self._seen, self._pool
        total = sum(len(p.geoms) for p in self._pairs)
        pool.extend(OdeJointFeedback() for _ in range(total - len(pool)))
        used = 0
        for pair in self._pairs:
            body = bodies[pair.owner]
            top = seen[pair.owner] - 1 - pair.start  # index of the pair's first contact joint
            first = body.getJoint(top)  # type: ignore[union-attr]
            if first.getJointType() != OdeJoint.JTContact:  # the order assumption broke: no force
                continue
            count = len(pair.geoms)
            pair.feedback = pool[used : used + count]
            used += count
            first.setFeedback(pair.feedback[0])
            for k in range(1, count):
                body.getJoint(top - k).setFeedback(pair.feedback[k])  # type: ignore[union-attr]
        self._used = used

    # --- callback ------------------------------------------------------------------------------------

    def _near_callback(self, report: bool, geom1: Any, geom2: Any) -> None:
        entry = OdeUtil.collide(geom1, geom2, CALLBACK_MAX_CONTACTS)
        if entry.getNumContacts() == 0:
            return
        scene = self.scene
        i, j = scene.geom_index[hash(geom1.getId())], scene.geom_index[hash(geom2.getId())]
        params = self._params[(scene.surface_class[i], scene.surface_class[j])]
        body1, body2 = scene.bodies[i], scene.bodies[j]
        geoms = entry.getContactGeoms()
        arm = report and self.contact_forces
        pair = _Pair(i, j, geoms)
        for geom in geoms:
            contact = OdeContact()
            contact.setGeom(geom)
            contact.setSurface(params)
            joint = OdeContactJoint(scene.world, scene.contact_group, contact)
            joint.attach(body1, body2)
            if arm:
                fb = self._feedback()
                joint.setFeedback(fb)
                pair.feedback.append(fb)
        if report:
            self._pairs.append(pair)

    def _feedback(self) -> OdeJointFeedback:
        if self._used == len(self._pool):
            self._pool.append(OdeJointFeedback())
        fb = self._pool[self._used]
        self._used += 1
        return fb


def _summary(pair: _Pair) -> Contact:
    force = math.nan
    if pair.feedback:
        # A contact row's force is along its normal and the friction rows are orthogonal to it, so
        # |F1 . n| is that contact's normal force whichever body is the joint's first.
        force = 0.0
        for fb, geom in zip(pair.feedback, pair.geoms, strict=True):
            force += abs(fb.getForce1().dot(geom.getNormal()))
    depth = max(geom.getDepth() for geom in pair.geoms)
    return Contact(pair.a, pair.b, len(pair.geoms), max(0.0, depth), force)


def _mu(surface: Surface) -> float:
    return OdeUtil.getInfinity() if math.isinf(surface.mu) else surface.mu


def _surface_parameters(surface: Surface) -> OdeSurfaceParameters:
    params = OdeSurfaceParameters()
    params.setMode(_MODE)
    params.setMu(_mu(surface))
    params.setBounce(surface.bounce)
    params.setBounceVel(surface.bounce_vel)
    return params
