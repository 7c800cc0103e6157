"""Per-check, per-backend tolerances of the shared backend suite.

``tol(check, backend)`` returns the backend's own line when there is one, else ``"default"``. Every
value carries a comment with what was measured and why the tolerance is what it is. Backend owners
add their own lines; the defaults are ODE's analytic expectations with float64 rounding room.
"""

from __future__ import annotations

_TOLERANCES: dict[str, dict[str, float]] = {
    # Free fall, |z - analytic| and |v - analytic| in m and m/s over 40 steps of 0.01 s.
    # Semi-implicit Euler is exact up to float64 rounding.
    # pybullet: max error 1.8e-15 (the engine integrates exactly this way).
    # ode: max error 2.8e-7 m / 1.4e-6 m/s: single-precision ODE stores float32 (ulp 2.4e-7 at 2 m) and
    # rounds each of the 40 velocity updates of 0.0981 m/s in float32.
    "free_fall": {"default": 1e-6, "ode": 3e-6},
    # One-step force: v after steps 1 and 2 (m/s), ODE's 2.5706 / 2.1782 to 1e-4 (brief).
    # pybullet: 2.570563 / 2.178163 with and without 10 substeps (error < 1e-12).
    "one_step_force": {"default": 1e-4},
    # Spin-up, relative error of tau*dt/I per axis.
    # pybullet: 1.5e-16 for box, rotated box and sphere (localInertiaDiagonal set exactly).
    "inertia": {"default": 1e-3},
    # Slider motor velocity, relative (issue 3: acceleration = fmax/m within 1 %).
    # pybullet: 0 error at every step (0.0100, 0.1000, 0.2500, 0.3000 at 0.04, 0.4, 1.0, 1.2 s).
    # With 4 substeps, asked for 0.004 m/s (test_motor_force_with_substeps_is_the_mean): pybullet, dart
    # 0.004 exactly, mujoco +3.7e-9; ode 0.0039650 (-0.87 %): CFM softens the unsaturated motor row, each
    # substep gives lambda = (dv/h)/(1/m + CFM/h) (test_ode.py), 42.9, 12.2 and 3.5 N after the 100 N one.
    "motor_velocity": {"default": 0.01},
    # Motor force while accelerating, relative to fmax; and |force| allowed once at speed, in N.
    # pybullet: exactly 100.0 for steps 1-29, exactly 0.0 from step 32.
    # With 4 substeps (mean of 100, 60, 0, 0 = 40 N): pybullet, dart 40.0, mujoco 40.00000015, ode 39.650
    # (-0.87 %, the soft row above: 100 + 42.9 + 12.2 + 3.5 over 4).
    "motor_force": {"default": 0.01},
    # Mean motor force against m*v/dt when the motor is the only force along the axis, relative: float64
    # rounding; ode reads float32 velocities (ulp 2.4e-7 relative at worst), measured 4.6e-8.
    "momentum": {"default": 1e-9, "ode": 5e-7},
    "motor_force_idle": {"default": 1.0},
    # A fixed joint holding a 1 kg bob 0.5 m from its anchor, and two glued boxes, position drift in m.
    # Reduced-coordinate joints hold exactly; ODE's CFM makes joints slightly soft (notes §0).
    "joint_hold": {"default": 1e-4},
    # Slider stop, m (notes §5: ODE 0.1001, PyBullet 0.1000, MuJoCo 0.1004, DART 0.1000).
    # pybullet: 0.10000001 after 3 s pushing at 100 N.
    "slider_stop": {"default": 1e-3},
    # Hinge stop, rad (notes §5: ODE, PyBullet, DART 0.5236, MuJoCo 0.5241). pybullet: 0.52359878.
    "hinge_stop": {"default": 2e-3},
    # Distance of a hinged or ball-jointed bob's centre from the anchor (0.5 m), m.
    # pybullet: < 1e-15 (reduced coordinates cannot stretch).
    # ode: 0.50287 m after 0.3 s swinging at dt 0.01 (0.50082 at 0.005, 0.50004 at 0.001): ODE joints
    # are velocity constraints with ERP correction, so the anchor drifts with omega^2*r*h^2; at rest
    # (hinge stop) it holds to 1e-5.
    "pivot_distance": {"default": 1e-3, "ode": 4e-3},
    # Passive hinge / ball pendulum angle after 0.3 s, relative to a semi-implicit Euler integration
    # of the physical pendulum at the same dt (0.8825 rad). pybullet: 2.5e-16 relative, hinge and ball
    # (its multibody integrates joint coordinates by exactly that scheme).
    "pendulum": {"default": 0.02},
    # Carried distance of a cube on a kinematic platform, relative to 0.3 m (brief: 5 %).
    # pybullet: 0.29605 m (-1.3 %: the cube slips while friction, mu*g, brings it to 0.3 m/s;
    # notes §4: ODE 0.297). Also the turntable's carried cube (speed against omega*r, spin against omega;
    # its angle and radius have derived windows in the test): after 1 s its angle is 0.9773 (pybullet,
    # mujoco), 0.9775 (dart, ode) of the window 0.949..1.0; radius 0.5042, 0.5046, 0.5024, 0.5024 m; speed
    # 0.8 %, 0.9 %, 0.5 %, 0.5 % above 0.5 m/s (omega times that radius); spin 1.0000 rad/s on all four.
    # Given no angular velocity (only turned poses) the cube stays at angle 0.0000 on all four.
    "kinematic_carry": {"default": 0.05},
    # Kinematic pose after a step, m and quaternion components: the contract says "exactly".
    "kinematic_pose": {"default": 1e-9},
    # Summed contact normal force of a resting 13.5 kg box, relative to m*g.
    # pybullet: 132.4350 N of 132.4350 N, 4 points, depth 2.0e-5 m, after 1 s of rest.
    "contact_force": {"default": 0.05},
    # Resting height of a shape's centre above a plane, m.
    # pybullet: -1.2e-5 to -1.7e-5 m for box, sphere, capsule, cylinder (and the 30 degree ramp).
    # dart: -3.77 mm for all four shapes after 1 s: the 1 cm drop lands 4.7 mm deep in one 0.01 s step,
    # and DART removes penetration at 1 mm/s at most (ContactConstraint's max error-reduction velocity,
    # not settable from dartpy; docs/backends/dart.md). The bound is that one step of approach.
    # mujoco: -1.2e-6 to -4.9e-6 m at rest for all four shapes, -1.1e-6 m sliding down the 30 degree ramp
    # (it hovered +2.2 mm before the Coulomb correction of docs/backends/mujoco.md).
    "resting_height": {"default": 2e-3, "dart": 5e-3},
    # Quaternion and angular velocity of a freely spinning cube after 0.5 s.
    # pybullet: 5.6e-17 (Bullet integrates the rotation exactly for constant omega).
    # ode: 1.5e-5 (w, z after 1 rad): ODE's default rotation update is first order, each step turns
    # 2*atan(w*h/2) instead of w*h, 3.3e-5 rad short after 50 steps of 0.02 rad (the lab's mode).
    "orientation": {"default": 1e-6, "ode": 3e-5},
    # Apex ratio of a bouncing sphere, absolute around e^2 = 0.25.
    # pybullet: 0.2694 (e = 0.519 for bounce 0.5) at dt 0.001; 0.306, 0.298, 0.314 at dt 0.004, 0.01,
    # 0.04. Needs the adapter's 1 mm contactBreakingThreshold: with Bullet's 0.02 m a contact point
    # exists several steps before impact and the rebound is lost (ratio 0.0000 at dt 0.001).
    # ode: 0.1929, which is ODE's own answer: with CFM 1e-5 the contact row at dt 0.001 meets only
    # (1/m)/(1/m + CFM/dt) = 0.96 of the 4.71 m/s velocity change, so v_out = 1.377 not 1.566 m/s and
    # the ratio is (1.377/3.132)^2 = 0.193 (notes section 6: ODE e = 0.161 for bounce 0.2 at 1 ms).
    "restitution": {"default": 0.05, "ode": 0.06},
    # Largest speed component of a box resting on a bounce-0.2 plane at dt 0.04 (steps 26-75), m/s.
    # pybullet: 1.8e-5 with the adapter's restitution threshold of bounce_vel + 1.5 g h; with threshold
    # 0 the box bounced at 0.32 m/s every step (Bullet's approach speed includes the step's gravity).
    "rest_jitter": {"default": 0.01},
    # Stop distance of a sliding box, relative to the semi-implicit Coulomb distance (0.3978 m at
    # dt 0.01; 0.408 m continuous); also the pair-surface and ramp checks.
    # pybullet: +9e-6 (0.39779 m), pair surfaces < 1e-4, ramp speed 7e-9. Needs the adapter's plane as
    # a box: on Bullet's GEOM_PLANE a sliding box keeps 1-2 points, rocks, sinks 1.9 cm, +3.7 %.
    # mujoco: stop -4e-7, pair surfaces +1.4e-5 / -1e-7, ramp +1.5e-3 (ODE +2.0e-3: the cube starts exactly
    # touching and lands 1 mm deep in step 1 on both); before the Coulomb correction +0.11 % and +2.1 %.
    "friction": {"default": 0.03, "mujoco": 3e-3},
    # One step of free fall read back at once, m: the contract says "exactly". Also states read right
    # after the build or a reset_body (pose, velocities, joint coordinates at 0). pybullet: < 1e-15.
    # ode: 4.9e-8 m (box z) and 5.3e-8 m (door x): float32 positions, one ulp at 2 m is 2.4e-7.
    "fresh_states": {"default": 1e-9, "ode": 2.5e-7},
}


def tol(check: str, backend: str) -> float:
    """The tolerance of ``check`` for ``backend`` (its own line, else the default)."""
    try:
        per_backend = _TOLERANCES[check]
    except KeyError:
        raise KeyError(f"no tolerance for check `{check}`; known: {', '.join(sorted(_TOLERANCES))}") from None
    return per_backend.get(backend, per_backend["default"])
