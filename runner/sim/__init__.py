"""Stage 3, simulation: the step loop and what it drives.

:mod:`runner.sim.session` is the loop (docs/semantics.md, "Step order"); actions, kinematic bodies,
intervals, collision events and assertions are its parts; :mod:`runner.sim.run` runs one case here and
writes its trace. The engine is reached only through the :class:`backends.base.Backend` contract.
"""
