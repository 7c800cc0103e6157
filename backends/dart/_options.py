"""The ``backend_options.dart`` block (imports no engine)."""

from __future__ import annotations

from dataclasses import dataclass

from .._kit import BackendOptions, option

#: DART's collision detectors by option value (``_build.DETECTORS`` maps them to dartpy classes).
DETECTOR_NAMES = ("ode", "fcl", "bullet", "dart")


@dataclass(frozen=True)
class DartOptions(BackendOptions):
    collision_detector: str = option(
        "ode", "ode | fcl | bullet | dart: DART's collision detector (default ode: ODE-like contact sets, 4 points "
        "for a box on a plane)", choices=DETECTOR_NAMES,
    )  # fmt: skip
    max_engine_dt: float | None = option(
        None, "longest DART step in seconds (default: dt / substeps); shorter engine steps make deep landings "
        "penetrate less, since DART corrects penetration at 1 mm/s at most", minimum=0.0, min_exclusive=True,
    )  # fmt: skip
