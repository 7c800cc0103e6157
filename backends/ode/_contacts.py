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
  A pair with a triangle-mesh geom keeps four of its contacts (``_manifold``), so worlds with meshes use it.

``dContactApprox1`` makes ODE bound friction by mu times the normal force (a Coulomb coefficient, the
scenario language's meaning) instead of by mu newtons. Each bound holds for one friction row, and ODE's
two rows default to directions fixed by the contact normal (``dPlaneSpace``: the world's x and y on a
floor), so a box sliding along a floor's diagonal meets sqrt(2)*mu*N. With ``friction_pyramid: slip``
(the default) each contact with a finite mu > 0 gets ``dContactFDir1`` along the two bodies' relative
velocity at the contact point, projected on the contact plane: the first row then opposes the slip and
the box decelerates at mu*g whatever its direction (the pyramid turns with the slip each substep).
The slip followed is the one the substep would make without friction: the relative velocity plus h times
the two bodies' relative acceleration from gravity and the applied forces (so a box at rest on a tilted
plane, or pushed, gets its first row along the load before it moves). Below ``_contact_surface.SLIP_SPEED``
the slip is numerical creep with no meaningful direction, and the contact keeps the direction it had the substep
before (hysteresis; ODE's default directions if it never had one): rows turned by noise every substep
made a resting column of boxes jitter and break loose (conformance 12). A sticking contact is inside the
pyramid, where its direction does not matter; it matters only at the limit. panda3d's surface table
fixes the mode of autoCollide's contacts, so such worlds use the callback.

A reported collide's pairs (points, depth) are those its contact joints used in the step that follows;
with ``contact_forces`` the normal force is read from joint feedback.

Per step only what arming feedback needs is done (one tuple per touching pair); the contact geoms,
depths and forces are read through panda3d only when ``contacts()`` is called.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Mapping
from typing import Any

from panda3d.core import EventQueue, LVecBase3f, Vec3
from panda3d.ode import (
    OdeContact,
    OdeContactGeom,
    OdeContactJoint,
    OdeJoint,
    OdeJointFeedback,
    OdeUtil,
)

from .._kit import contact_point, group_by_pair, sorted_points
from ..types import Contact, ContactPoint
from ._build import MAX_SURFACE_CLASSES, Scene
from ._contact_surface import (
    IMPACT_CFM,
    IMPACT_SPEED,
    MODE,
    MODE_FDIR1,
    MODE_SOFT,
    MODE_SOFT_FDIR1,
    approach_speed,
    ode_mu,
    predicted_slip,
    surface_parameters,
)
from ._manifold import reduce_contacts

CALLBACK_MAX_CONTACTS = 150  # PyODE's ode.collide() default, as the lab calls it
_JT_CONTACT = OdeJoint.JTContact
#: The getters ``_summaries`` maps over a pair's points (unbound: no attribute lookup per point).
_DEPTH, _NORMAL = OdeContactGeom.getDepth, OdeContactGeom.getNormal
_FORCE1, _DOT = OdeJointFeedback.getForce1, LVecBase3f.dot
_SET_FEEDBACK = OdeJoint.setFeedback
_SINK: deque[Any] = deque(maxlen=0)
_consume = _SINK.extend  # runs an iterator of calls for their effect, keeping nothing

#: One touching pair of the reported substep: (a, b, entry, first) with a < b its bodies, entry its
#: OdeCollisionEntry (contact geoms in ODE's order) and first the index of its first feedback slot in
#: the pool (its contacts' slots follow in that order), -1 when not armed.
_Record = tuple[int, int, Any, int]


class Collider:
    """Makes the contact joints of one substep and remembers the last reported one."""

    def __init__(
        self, scene: Scene, mode: str, contact_forces: bool, event_name: str, follow_slip: bool = True,
        step: float = 0.0, impact_cfm: bool = True,
    ) -> None:
        self.scene = scene
        self.contact_forces = contact_forces
        self._event = event_name
        self._queue = EventQueue.getGlobalEventQueue()
        self._index = scene.geom_index
        self._bodies = scene.bodies
        self._pool: list[OdeJointFeedback] = []
        self._used = 0
        self._pairs: list[_Record] = []
        self._report: list[Contact] | None = []
        self._reported: list[_Record] = []
        classes = max(scene.surface_class, default=0) + 1
        #: Surface classes pairs whose contacts follow the slip (finite mu > 0; 0 and inf have no direction).
        self._slipping = {key for key, s in scene.surfaces.items() if follow_slip and 0.0 < s.mu < math.inf}
        #: Impacts get a CFM of their own (``_impact_cfm``), a per-contact mode autoCollide cannot give.
        self._impacts = impact_cfm
        # autoCollide's table is indexed by a byte, and its mode has no dContactFDir1 nor a per-contact CFM:
        # the callback then.
        # Excluded pairs need the callback too: autoCollide contacts every pair the category bits allow.
        # Mesh pairs keep four contacts (_manifold), which only the callback can choose.
        auto = (classes <= MAX_SURFACE_CLASSES and not self._slipping and not impact_cfm and not scene.excluded
                and not scene.mesh_geoms)  # fmt: skip
        self.mode = mode if auto else "callback"
        self._auto = self.mode == "auto"
        self._event_set: str | None = None  # the collision event last given to the space ("": none)
        if self._auto:
            world, space = scene.world, scene.space
            world.initSurfaceTable(classes)
            cfm = world.getCfm()
            for (i, j), s in scene.surfaces.items():
                if i <= j:
                    world.setSurfaceEntry(i, j, ode_mu(s), s.bounce, s.bounce_vel, 0.0, cfm, 0.0, 0.0)
            space.setAutoCollideWorld(world)
            space.setAutoCollideJointGroup(scene.contact_group)
            for geom in scene.geoms:  # a compound body's geoms share its class
                space.setSurfaceType(geom, scene.surface_class[self._index[hash(geom.getId())]])
        else:
            self._params = {key: surface_parameters(s, MODE) for key, s in scene.surfaces.items()}
            self._params_fdir1 = {key: surface_parameters(scene.surfaces[key], MODE_FDIR1) for key in self._slipping}
            #: Per body: h / mass (0 for a static geom) and h * gravity (None with gravity off) for ``predicted_slip``.
            self._step = step
            self._per_mass = [0.0 if b is None else step / b.getMass().getMagnitude() for b in scene.bodies]
            gravity = scene.world.getGravity() * step
            self._gravity = [None if b is None or not b.getGravityMode() else gravity for b in scene.bodies]
            self._forces: Mapping[int, Any] = {}
            #: Friction direction per contact (geom i, geom j, k-th contact) of the last collide and this one.
            self._directions: dict[tuple[int, int, int], Any] = {}
            self._next_directions: dict[tuple[int, int, int], Any] = {}

    # --- per substep ---------------------------------------------------------------------------------

    def collide(self, report: bool, forces: Mapping[int, Any] | None = None) -> None:
        """Make this substep's contact joints; with ``report``, record the pairs (and arm feedback).

        ``forces``: body index -> the force (and torque) applied this substep, for the predicted slip.
        """
        self._used = 0
        space = self.scene.space
        if self._auto:
            event = self._event if report else ""
            if event != self._event_set:
                space.setCollisionEvent(event)
                self._event_set = event
            space.autoCollide()
            self._pairs = self._drain_events() if report else []
        else:
            self._pairs = []
            self._directions, self._next_directions = self._next_directions, {}
            self._forces = forces or {}
            space.collide(report, self._near_callback)

    def after_step(self, report: bool) -> None:
        """Keep the reported pairs (read lazily: feedback was filled by the step), empty the group."""
        if report:
            self._report = None
            self._reported = self._pairs
        self.scene.contact_group.empty()

    def contacts(self) -> list[Contact]:
        if self._report is None:
            self._report = _summaries(self._reported, self._pool, len(self._bodies))
        return list(self._report)

    def points(self) -> list[ContactPoint]:
        """The reported substep's contact points (the contract's ``contact_points``): ODE's normal points
        into geom 1 (moving geom 1 along it by the depth separates them), so the point's normal from geom 1
        to geom 2 is its negation; the force is |F1 . n| of the joint's feedback (NaN when not armed)."""
        index, pool, out = self._index, self._pool, []
        for _, _, entry, slot in self._reported:
            i, j = index[hash(entry.getGeom1().getId())], index[hash(entry.getGeom2().getId())]
            for k, geom in enumerate(entry.getContactGeoms()):
                n = geom.getNormal()
                force = math.nan if slot < 0 else abs(pool[slot + k].getForce1().dot(n))
                out.append(contact_point(i, j, geom.getPos(), -n, geom.getDepth(), force))
        return sorted_points(out)

    # --- auto ----------------------------------------------------------------------------------------

    def _drain_events(self) -> list[_Record]:
        """This collide's pairs, from the collision events autoCollide threw, in their order."""
        queue, name = self._queue, self._event
        empty, dequeue = queue.isQueueEmpty, queue.dequeueEvent
        entries: list[Any] = []  # OdeCollisionEntry
        others: list[Any] = []
        while not empty():
            event = dequeue()
            if event.name == name:
                entries.append(event.getParameter(0).getTypedRefCountValue())  # OdeCollisionEntry
            else:
                others.append(event)
        for event in others:  # not ours: put back
            queue.queueEvent(event)
        if self.contact_forces:
            return self._arm_auto_feedback(entries)
        index = self._index
        return [_record(index[hash(e.getGeom1().getId())], index[hash(e.getGeom2().getId())], e, -1) for e in entries]

    def _arm_auto_feedback(self, entries: list[Any]) -> list[_Record]:
        """Attach feedback to the contact joints autoCollide made (C++ objects we hold no handle to).

        ODE prepends each joint to its bodies' joint lists, so a body's first K joints are its K newest
        contact joints, newest first; their creation order is the collision events' order. A pair's
        joints are found through its first geom's body (the second's when the first is static).
        """
        index, bodies = self._index, self._bodies
        seen: dict[int, int] = {}  # body index -> contacts so far (its contact joints, oldest first)
        get = seen.get
        plan: list[tuple[int, int, Any, int, int, int]] = []  # (i, j, entry, owner, owner's earlier contacts, count)
        total = 0
        for e in entries:
            i, j = index[hash(e.getGeom1().getId())], index[hash(e.getGeom2().getId())]
            count = e.getNumContacts()
            total += count
            if bodies[i] is not None:
                start = get(i, 0)
                seen[i] = start + count
                if bodies[j] is not None:
                    seen[j] = get(j, 0) + count
                plan.append((i, j, e, i, start, count))
            else:
                start = get(j, 0)
                seen[j] = start + count
                plan.append((i, j, e, j, start, count))
        pool = self._pool
        if total > len(pool):
            pool.extend([OdeJointFeedback() for _ in range(total - len(pool))])
        records: list[_Record] = []
        append = records.append
        used = 0
        for i, j, e, owner, start, count in plan:
            joint = bodies[owner].getJoint  # type: ignore[union-attr]
            top = seen[owner] - 1 - start  # index of the pair's first contact joint
            first = joint(top)
            if first.getJointType() != _JT_CONTACT:  # the order assumption broke: no force
                append(_record(i, j, e, -1))
                continue
            first.setFeedback(pool[used])
            if count > 1:  # the pair's other joints, newest first: top-1 ... top-count+1 (one map, no loop)
                _consume(map(_SET_FEEDBACK, map(joint, range(top - 1, top - count, -1)), pool[used + 1 : used + count]))
            append(_record(i, j, e, used))
            used += count
        self._used = used
        return records

    # --- callback ------------------------------------------------------------------------------------

    def _near_callback(self, report: bool, geom1: Any, geom2: Any) -> None:
        scene = self.scene
        i, j = scene.geom_index[hash(geom1.getId())], scene.geom_index[hash(geom2.getId())]
        if (i, j) in scene.excluded:  # collision:exclude-pairs (ODE skips two geoms of one body itself)
            return
        entry = OdeUtil.collide(geom1, geom2, CALLBACK_MAX_CONTACTS)
        if entry.getNumContacts() == 0:
            return
        meshes = scene.mesh_geoms
        if meshes and (hash(geom1.getId()) in meshes or hash(geom2.getId()) in meshes):
            entry = reduce_contacts(entry)  # four, as the other engines keep of a hull (_manifold)
        key = (scene.surface_class[i], scene.surface_class[j])
        params = self._params[key]
        body1, body2 = scene.bodies[i], scene.bodies[j]
        follow = key in self._slipping
        arm = report and self.contact_forces
        first = self._used if arm else -1
        impacts = self._impacts
        for k, geom in enumerate(entry.getContactGeoms()):
            contact = OdeContact()
            contact.setGeom(geom)
            slip = self._direction((i, j, k), body1, body2, geom) if follow else None
            if impacts and approach_speed(body1, body2, geom) > IMPACT_SPEED:
                mode = MODE_SOFT if slip is None else MODE_SOFT_FDIR1
                contact.setSurface(surface_parameters(scene.surfaces[key], mode, self._impact_cfm(i, j)))
            elif slip is None:
                contact.setSurface(params)
            else:
                contact.setSurface(self._params_fdir1[key])
            if slip is not None:
                contact.setFdir1(slip)
            joint = OdeContactJoint(scene.world, scene.contact_group, contact)
            joint.attach(body1, body2)
            if arm:
                joint.setFeedback(self._feedback())
        if report:
            self._pairs.append(_record(i, j, entry, first))

    def _direction(self, key: tuple[int, int, int], body1: Any, body2: Any, geom: Any) -> Any:
        """The contact's first friction direction: its predicted slip, else the last one it had, else None."""
        slip = predicted_slip(body1, body2, geom, self._kick(key[0]), self._kick(key[1]))
        if slip is None:
            slip = self._directions.get(key)
            if slip is None:
                return None
        self._next_directions[key] = slip
        return slip

    def _impact_cfm(self, i: int, j: int) -> float:
        """The CFM of an impact's contact rows: :data:`IMPACT_CFM` of the row's own inverse mass, times h.

        ODE adds CFM/h to each row's diagonal, whose mass part is at least ``w = 1/m1 + 1/m2`` (the
        rotational terms only add to it). The contact row then reaches ``1/(1 + CFM/(h*w))`` of its target
        velocity change in the step: the world's CFM 1e-5 leaves a 100 kg ball at h 1 ms half of it, the
        next steps bounce again on what is left (e_eff 0.16 instead of 0.5, measured), and without bounce
        the soft row stores the impact as a spring that throws the ball back (e_eff 0.20). A CFM relative to
        ``w`` makes the impact the same for every mass (1e-4 of the velocity change lost), never softer than
        the world's.
        """
        w = self._per_mass[i] + self._per_mass[j]  # h/m1 + h/m2
        return min(self.scene.world.getCfm(), IMPACT_CFM * w)

    def _kick(self, i: int) -> Any:
        """h * (F/m + g) for body ``i``: the velocity the substep adds to it before contacts (None: none)."""
        kick = self._gravity[i]
        force = self._forces.get(i)
        if force is not None:
            push = Vec3(force[0], force[1], force[2]) * self._per_mass[i]
            kick = push if kick is None else kick + push
        return kick

    def _feedback(self) -> OdeJointFeedback:
        if self._used == len(self._pool):
            self._pool.append(OdeJointFeedback())
        fb = self._pool[self._used]
        self._used += 1
        return fb


def _record(i: int, j: int, entry: Any, first: int) -> _Record:
    """A pair's record, its bodies in order (a < b)."""
    return (i, j, entry, first) if i < j else (j, i, entry, first)


def _summaries(records: list[_Record], pool: list[OdeJointFeedback], n_bodies: int) -> list[Contact]:
    """One Contact per pair (the kit's grouping), from its contact geoms and, when armed, their feedback.

    The panda3d getters are mapped as unbound methods over each pair's geoms and feedback slots: the same
    calls (and the same float32 dot products) as a loop over the points, about half the Python around them.
    """
    first: list[int] = []
    second: list[int] = []
    depth: list[float] = []
    force: list[float] = []
    for a, b, entry, slot in records:
        geoms = entry.getContactGeoms()
        k = len(geoms)
        first += [a] * k
        second += [b] * k
        depth += map(_DEPTH, geoms)
        if slot < 0:
            force += [math.nan] * k
        else:
            # A contact row's force is along its normal and the friction rows are orthogonal to it, so
            # |F1 . n| is that contact's normal force whichever body is the joint's first.
            force += map(abs, map(_DOT, map(_FORCE1, pool[slot : slot + k]), map(_NORMAL, geoms)))
    return group_by_pair(n_bodies, first, second, depth, force)
