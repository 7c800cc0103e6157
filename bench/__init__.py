"""Benchmarks of the runner against the engines it drives (``python -m bench``; see bench/README.md).

The benchmarks import the engines directly (the hand-written loops in ``bench/raw_*.py``): they measure
the engines themselves, so the rule that only ``backends/`` imports an engine does not apply here.
"""
