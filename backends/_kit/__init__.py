"""What every adapter needs once (issue 14, "a backend kit"); docs/backends/README.md shows how an adapter uses it.

* :mod:`.options`: typed ``backend_options`` blocks, checked before any engine object exists;
* :mod:`.motion`: the kinematic track, the one-step forces, substep means and substep times;
* :mod:`.contacts`: contact points grouped per body pair, and engine steps merged into the scenario step;
* :mod:`.pairs`: which body pairs can touch (a dynamic body, not joined, not excluded);
* :mod:`.surfaces`: per-body friction and restitution for engines that combine two bodies' values by a rule
  (:class:`~.surfaces.Blend`) instead of taking ODE's per-pair surface;
* :mod:`.stacks`: the tallest column a world starts with, for the engines' stacking limits.
* :mod:`.coupling_solve`: one engine step that holds joint couplings (``joint:mimic``), by Newton steps on
  trial steps from the step's start (DART's coupler offsets, ODE's force pairs).

The contract itself (checks, error translation, calls after close) is :class:`backends.base.Backend`.
Nothing here imports an engine.
"""

from __future__ import annotations

from .contacts import SubstepContacts, contact_point, group_by_pair, merge_substeps, sorted_points
from .motion import KinematicPose, KinematicTrack, OneStepForces, SubstepMean, substep_times
from .options import BackendOptions, Rule, option

__all__ = [
    "BackendOptions",
    "KinematicPose",
    "KinematicTrack",
    "OneStepForces",
    "Rule",
    "SubstepContacts",
    "SubstepMean",
    "contact_point",
    "group_by_pair",
    "merge_substeps",
    "option",
    "sorted_points",
    "substep_times",
]
