"""The ``backend_options.dart`` block (imports no engine)."""

from __future__ import annotations

from dataclasses import dataclass

from .._kit import BackendOptions, option

#: DART's collision detectors by option value (``_build.DETECTORS`` maps them to dartpy classes).
DETECTOR_NAMES = ("ode", "fcl", "bullet", "dart")
#: Largest mu ``friction: cone`` accepts. Measured on a 8 kg box held by friction under 0.4 m g, dt 0.01:
#: NsgsFrictionSolver stops at its sweep cap up to mu 100 (creep 2.6e-5 m in 1 s); at 200 it fails in 99
#: of 100 steps and at 1000 its impulses are NaN, which DART zeroes: the box falls through the floor.
MAX_CONE_MU = 100.0
#: NsgsFrictionSolver's sweep cap (DART's default 100; it stops earlier at its 1e-5 tolerance). Measured on
#: conformance 12 (4 boxes of 13.5 kg resting on each other, 10 s): at 100 and 300 sweeps the unconverged
#: friction lets the column slide (0.09 m/s, 2.2e-3 m drift), at 500 it reaches 1.2e-3 m/s, at 1000
#: 1.6e-5 m/s and 8.9e-5 m drift; the cost is paid only by contacts that do not converge sooner.
CONE_MAX_SWEEPS = 1000
#: The tallest column ``friction: auto`` leaves to the cone. The sweeps a column needs grow as the square
#: of its height (Gauss-Seidel carries a load one contact per sweep): 4 boxes need about 1000 (above), so a
#: taller column exceeds the cap. Measured (conformance 16, the column of conformance 12 at 5-30 boxes,
#: mu 1, 10 s): 5 boxes hold (1.7e-4 m/s), 10 slide at 0.17 m/s and drift 1.1 cm, 20 and 30 fall; with
#: the pyramid (Dantzig's exact LCP) all four stand still (0 m/s, drift < 1e-4 m). 4 is the height whose
#: need the cap is measured to meet.
MAX_CONE_STACK = 4


@dataclass(frozen=True)
class DartOptions(BackendOptions):
    collision_detector: str = option(
        "ode", "ode | fcl | bullet | dart: DART's collision detector (default ode: ODE-like contact sets, 4 points "
        "for a box on a plane)", choices=DETECTOR_NAMES,
    )  # fmt: skip
    max_engine_dt: float | None = option(
        None, "longest DART step in seconds (default: dt / substeps); shorter engine steps make deep landings "
        "penetrate less (a landing sinks one engine step of approach)", minimum=0.0, min_exclusive=True,
    )  # fmt: skip
    friction: str = option(
        "auto", "auto (default): cone when every pair that can touch has mu <= 100 and no column of more than 4 "
        "bodies stands at the start, else pyramid; cone: DART's "
        "NsgsFrictionSolver (1000 sweeps at most) with the exact Coulomb cone, mu*g in every direction "
        "(iterative: a body held by friction creeps ~1e-4 m/s), refused above mu 100 (its impulses turn NaN); "
        "pyramid: DART's Dantzig LCP, "
        "a friction box per tangent direction fixed to the contact normal's basis (sqrt(2)*mu*g on the "
        "diagonal of a floor)", choices=("auto", "cone", "pyramid"),
    )  # fmt: skip
