"""Stage 2, compiling: a loaded scenario becomes what a run needs.

:mod:`runner.compile.world` builds the engine-neutral :class:`backends.types.CompiledWorld` (masses,
poses, joint frames, surfaces); :mod:`runner.compile.program` adds handlers, intervals, inputs, assertions
and expressions, compiled once.
"""
