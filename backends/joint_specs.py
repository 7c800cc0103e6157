"""Compiled joints (:class:`JointSpec`: kind, axes, anchor, stops), their motors, own dynamics and mimic
couplings; re-exported by :mod:`backends.types`, whose docstring states the conventions."""

from __future__ import annotations

from dataclasses import dataclass

from .basic_types import JointKind, Vec3


@dataclass(frozen=True)
class Motor:
    """An ODE velocity motor: target rate ``vel`` and the largest force or torque ``fmax`` it may apply."""

    vel: float
    fmax: float


@dataclass(frozen=True)
class JointDynamics:
    """A joint's own dynamics (docs/semantics.md, "Joint dynamics"), in the joint coordinate's units (hinge:
    N m, rad; slider: N, m). Damping and friction loss are realised by the runner with the joint's velocity
    motor (``runner.sim.joint_dynamics``): every engine with ``joint:motor`` runs them. Effort and velocity
    limits cap what the runner commands that motor. Armature and stiffness are the adapter's
    (``joint:armature``, ``joint:stiffness``)."""

    damping: float = 0.0  # N m s/rad or N s/m: a force -damping * rate
    frictionloss: float = 0.0  # N m or N: dry friction, the force that holds the joint still up to this bound
    armature: float = 0.0  # kg m^2 or kg: inertia added to the coordinate (a rotor's reflected inertia)
    stiffness: float = 0.0  # N m/rad or N/m: a spring force -stiffness * (position - springref)
    springref: float = 0.0  # where the spring is relaxed, in the coordinate measured from the start
    effort: float | None = None  # the largest force a motor or servo may apply (caps fmax); None: no cap
    velocity: float | None = None  # the largest rate a motor or servo may command; None: no cap

    @property
    def dissipative(self) -> bool:
        """Whether the runner drives the joint's motor for damping or friction loss."""
        return self.damping > 0 or self.frictionloss > 0


NO_DYNAMICS = JointDynamics()


@dataclass(frozen=True)
class JointSpec:
    """One joint of a compiled world, engine-neutral: its kind, bodies, anchor, axes, limits, motor and dynamics."""

    name: str
    kind: JointKind
    body: str
    other: str | None  # None: the environment (the static world)
    axis: Vec3 = (1.0, 0.0, 0.0)  # world frame, unit (slider, hinge; universal: first axis)
    axis2: Vec3 | None = None  # universal: second axis, world frame, unit
    anchor: Vec3 = (0.0, 0.0, 0.0)  # world frame (hinge, ball, universal)
    lo: float | None = None  # stops: metres (slider) or radians (hinge), from the start pose
    hi: float | None = None
    #: restitution of the stops, 0..1 (ODE dParamBounce); 0: no bounce
    stop_bounce: float = 0.0
    #: a soft stop as a spring-damper (N/m or N m/rad; N s/m or N m s/rad), ODE's dParamStopERP/CFM with
    #: ERP = h k / (h k + c) and CFM = 1 / (h k + c) for a step h; None: rigid (the engine's default stop)
    stop_stiffness: float | None = None
    stop_damping: float | None = None
    motor: Motor | None = None  # initial motor; the runner may change it with set_motor
    dynamics: JointDynamics = NO_DYNAMICS


@dataclass(frozen=True)
class JointCoupling:
    """A joint whose position is its leader's, scaled and shifted (URDF `<mimic>`): ``joint`` = ``multiplier`` x
    ``leader`` + ``offset``, both positions counted from the start as every JointSpec's (so ``offset`` is 0
    when the start already satisfies it). Both are sliders or hinges; capability ``joint:mimic``."""

    joint: str  # the follower's CompiledWorld joint name
    leader: str
    multiplier: float
    offset: float = 0.0  # m or rad

    def engine_terms(self, follower_sign: float, leader_sign: float) -> tuple[float, float]:
        """(ratio, offset) of the coupling in an engine's coordinates ``e = sign * q`` of each joint:
        e_joint = ratio * e_leader + offset."""
        return self.multiplier * follower_sign * leader_sign, follower_sign * self.offset
