"""Running cases elsewhere: one child-process protocol, and the executors built on it.

Every way of running a case outside the command's process goes through it: ``scenario run`` (serially,
``-j N``, ``--isolate``, ``--trace-process``), Ray, ``compare``, ``sweep``, ``baseline``, ``check``, the
pytest plugin and the conformance suite.

* :mod:`runner.exec.pool`: the parent's side: worker processes (forked), jobs, time limits, signals
  passed on, and how each job ended (returned, crashed by signal N, timed out, interrupted);
* :mod:`runner.exec.child`: the worker's side: its own process group, its output captured, interruptions
  held until a safe point, jobs run one at a time;
* :mod:`runner.exec.transport`: what crosses the boundary: exceptions with their class, run results;
* :mod:`runner.exec.cases`: a case, the job that runs it, and :class:`~runner.exec.cases.CaseResult`;
* :mod:`runner.exec.exits`: the one mapping from how something ended to an exit code and first line;
* :mod:`runner.exec.executors`: the :class:`~runner.exec.executors.Executor` protocol, local and Ray.
"""
