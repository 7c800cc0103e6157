"""The benchmark's hand-written loops (bench/raw_*.py) do the same physics as the runner on each engine.

The overhead ratio in bench/results.md compares the runner with these loops, so they must build the same
world with the same settings: after 0.2 s of a small pile, every body is where the runner's trace puts
it, to the trace's resolution (1e-9 m). About 1 s per engine.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from backends.registry import is_installed
from bench import measure
from runner.sim.run import trace_path


@pytest.mark.parametrize("backend", sorted(measure.RAW_LOOPS))
def test_raw_loop_matches_the_runner(backend: str, tmp_path: Path) -> None:
    if not is_installed(backend):
        pytest.skip(f"engine not installed: {backend}")
    loaded = measure.pile((2, 1, 2), 0.2)
    world, steps = measure.world_of(loaded)
    raw = measure.run_raw(backend, world, measure.adapter_settings(backend, world), steps, read=False)
    timing = measure.run_runner(loaded, backend, tmp_path)
    assert timing.steps == steps == 50
    final = measure.final_from_trace(str(trace_path(tmp_path, loaded, backend)))
    assert np.abs(final[:, :3] - raw.final[:, :3]).max() <= 1e-9
    assert np.abs(final[:, 7:10] - raw.final[:, 7:10]).max() <= 1e-9
    # orientations and spins too (a quaternion and its negation are one orientation): the loops' reads
    # convert each engine's own form (PyBullet x y z w, DART rotation vectors, ODE float32) like the adapter
    quat, raw_quat = final[:, 3:7], raw.final[:, 3:7]
    assert np.minimum(np.abs(quat - raw_quat).max(axis=1), np.abs(quat + raw_quat).max(axis=1)).max() <= 1e-9
    assert np.abs(final[:, 10:13] - raw.final[:, 10:13]).max() <= 1e-9
    # and the boxes moved: they fell 1 cm onto the ground or each other, then came to rest
    assert np.abs(final[1:, 2] - np.array([b.pos[2] for b in world.bodies[1:]])).max() > 0.005
    # the instrumented parts add up: engine, trace and the runner's own work are each a positive share
    assert 0 < timing.engine_step < timing.seconds and 0 < timing.trace < timing.seconds and timing.runner_own > 0


def _engine_line(path: Path) -> int:
    """The line of ``ENGINE = "<name>"`` in bench/seed_loop.py, bench/startup.py or bench/worlds.py."""
    return next(i for i, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
                if line.startswith("ENGINE = "))  # fmt: skip


def test_bench_takes_its_engines_from_the_registry() -> None:
    """No engine's registry name is written in bench/ outside the engines' own loops (raw_<name>.py and the
    seed's ODE loop and the start-up benchmark of issue 29's MuJoCo target, whose one name is each one's
    ENGINE constant): the benchmarks list what the registry lists, so a fifth engine joins them by its
    registry line."""
    import ast

    from backends.registry import list_backends
    from bench import __main__ as cli

    names = {e.name for e in list_backends()}
    assert set(cli.ENGINES) == {e.name for e in list_backends() if not e.opt_in} and set(measure.RAW_LOOPS) <= names
    wrong = []
    for path in sorted((Path(measure.__file__).parent).glob("*.py")):
        if path.stem.startswith("raw_") and path.stem[4:] in names:
            continue
        own = path.stem in ("seed_loop", "startup", "worlds")  # a benchmark of one engine, named once
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value in names:
                if own and node.lineno == _engine_line(path):
                    continue
                wrong.append(f"{path.name}:{node.lineno} {node.value!r}")
    assert not wrong, "engine names in bench/: " + ", ".join(wrong)
