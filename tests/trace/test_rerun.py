"""Traces in Rerun: `rerun mcap convert` (rerun-sdk's own CLI, with its Foxglove decoder) of every case of
scenarios/ and scenarios/conformance/ gives each body's pose at each recorded step as a Transform3D
(child frame = the body, parent frame = world), read back with rerun's own RRD reader.

rerun-sdk is the optional `viewers` extra (a 170 MB wheel); skipped without it, and SCENARIO_REQUIRE_RERUN=1
(set by .ci/run, which installs the extra) turns the skip into a failure.
"""

from __future__ import annotations

import importlib.util
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from reports.trace_reader import read_trace
from runner.language.files import scenario_files
from runner.language.load import load_files
from tests.paths import ROOT

REQUIRED = os.environ.get("SCENARIO_REQUIRE_RERUN") == "1"
RERUN = shutil.which("rerun", path=str(Path(sys.executable).parent)) or shutil.which("rerun")
INSTALLED = RERUN is not None and importlib.util.find_spec("rerun") is not None
pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(not INSTALLED and not REQUIRED, reason="rerun-sdk is not installed (pip install '.[viewers]')"),
]
ENV = {**os.environ, "RERUN_ANALYTICS": "0"}  # no usage reports from the CLI


@pytest.fixture(scope="module")
def traces(tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    if not INSTALLED:
        pytest.fail("SCENARIO_REQUIRE_RERUN=1 but rerun-sdk is not installed (pip install '.[viewers]')")
    out = tmp_path_factory.mktemp("rerun")
    done = subprocess.run(
        [sys.executable, "-m", "runner", "run", "scenarios", "scenarios/conformance", "--all-variants", "--out",
         str(out), "-j", "2", "--quiet"],
        cwd=ROOT, capture_output=True, text=True, timeout=900,
    )  # fmt: skip
    assert done.returncode in (0, 1), done.stderr[-3000:]
    found = sorted(out.glob("*.mcap"))
    cases = load_files(scenario_files([ROOT / "scenarios"]), None, True, ())
    assert len(found) == len(cases) > 30  # every variant of every scenario, conformance included
    return found


def _transforms(rrd: Path) -> tuple[list[int], list[str], list[str], np.ndarray, np.ndarray]:
    """(log times, child frames, parent frames, translations, quaternions x y z w) of every Transform3D row."""
    from rerun.chunk import RrdReader

    times: list[int] = []
    child: list[str] = []
    parent: list[str] = []
    translation, rotation = [], []
    for chunk in RrdReader(rrd).stream().to_chunks():
        batch = chunk.to_record_batch()
        if "Transform3D:translation" not in batch.schema.names:
            continue
        times += [t.value for t in batch.column("message_log_time")]
        child += [c[0] for c in batch.column("Transform3D:child_frame").to_pylist()]
        parent += [p[0] for p in batch.column("Transform3D:parent_frame").to_pylist()]
        translation += [v[0] for v in batch.column("Transform3D:translation").to_pylist()]
        rotation += [v[0] for v in batch.column("Transform3D:quaternion").to_pylist()]
    return times, child, parent, np.array(translation, dtype=np.float32), np.array(rotation, dtype=np.float32)


def test_every_trace_gives_the_bodies_transforms_in_rerun(traces: list[Path], tmp_path: Path) -> None:
    assert RERUN is not None
    for path in traces:
        rrd = tmp_path / f"{path.stem}.rrd"
        done = subprocess.run([RERUN, "mcap", "convert", str(path), "-o", str(rrd)], capture_output=True, text=True,
                              env=ENV, timeout=300)  # fmt: skip
        assert done.returncode == 0, f"{path.name}: {done.stderr[-2000:]}"
        trace = read_trace(path)
        times, child, parent, translation, rotation = _transforms(rrd)
        assert set(parent) == {"world"}, path.name
        steps = [round(t * 1e9) for t in trace.times.tolist()]
        for name, series in trace.bodies.items():  # every body, at every recorded step, where the trace has it
            rows = [i for i, c in enumerate(child) if c == name]
            assert sorted(times[i] for i in rows) == steps, f"{path.name}: {name}"
            order = sorted(rows, key=lambda i: times[i])
            np.testing.assert_array_equal(translation[order], series.pos.astype(np.float32), err_msg=path.name)
            xyzw = series.quat[:, [1, 2, 3, 0]].astype(np.float32)  # Rerun stores Foxglove's x, y, z, w
            np.testing.assert_array_equal(rotation[order], xyzw, err_msg=path.name)
