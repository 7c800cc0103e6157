"""The bench's batched-worlds section (bench/worlds.py): its variants make one batch and its table renders."""

from __future__ import annotations

import pytest

pytest.importorskip("mujoco_warp")

from backends.registry import get_backend  # noqa: E402
from bench import worlds  # noqa: E402


def test_the_variants_differ_in_mass_height_and_bounce_and_make_one_batch() -> None:
    variants = [worlds.box_drop(k) for k in range(27)]
    keys = {(v.bodies[1].mass, v.bodies[1].pos[2], v.default_surface.bounce) for v in variants}
    assert len(keys) == 27  # 3 masses x 3 heights x 3 bounces, each once
    batch = get_backend("mujoco_warp").world_batch()
    assert batch is not None and batch.why_not(variants) is None


def test_a_measurement_renders_with_its_target_row() -> None:
    figs = worlds.run([1, 3], "cpu", steps=4, warmup=2, log=lambda _: None)
    assert [f.worlds for f in figs] == [1, 3] and all(f.steps == 4 for f in figs)
    assert all(f.engine_s > 0 and f.batch_s > 0 and f.reads_s > 0 for f in figs)
    text = "\n".join(worlds.render(figs, worlds.GPU_NOTE))
    assert "| cpu | 3 |" in text and "not measured: no GPU in this task" in text
    ((goal, _, _, _),) = worlds.target_rows(figs)
    assert "1 -> 3 worlds" in goal
