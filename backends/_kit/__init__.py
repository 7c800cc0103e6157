"""What every adapter needs once (issue 14, "a backend kit"); docs/backends/README.md shows how an adapter uses it.

* :mod:`.options`: typed ``backend_options`` blocks, checked before any engine object exists;
* :mod:`.motion`: the kinematic track, the one-step forces, substep means and substep times;
* :mod:`.contacts`: contact points grouped per body pair, and engine steps merged into the scenario step.

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
