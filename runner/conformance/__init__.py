"""The conformance suite: the promised semantics, checked against analytic values and the `ode` reference.

``discover(suite)`` lists the cases (every variant of every scenario in ``scenarios/conformance/``),
``run_suite(cases, backends)`` runs them in worker processes of runner.exec (one engine per process), ``build_matrix``
turns the results into the matrix (check x backend: error against the analytic value, difference from
``ode``, pass/fail), and ``markdown`` / ``console`` render it. ``scenario conformance`` is the command.
"""

from __future__ import annotations

from runner.conformance.cases import DEFAULT_SUITE, Case, Check, discover
from runner.conformance.matrix import REFERENCE, broken, build_matrix
from runner.conformance.pool import BackendRun, run_backend, run_suite
from runner.conformance.render import console, markdown

__all__ = [
    "DEFAULT_SUITE",
    "REFERENCE",
    "BackendRun",
    "Case",
    "Check",
    "broken",
    "build_matrix",
    "console",
    "discover",
    "markdown",
    "run_backend",
    "run_suite",
]
