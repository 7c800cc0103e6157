"""The `scenario` command as a user runs it: exit codes, messages, outputs."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from runner.language.schema import schema_text
from tests.engines import ENGINES
from tests.paths import ROOT, SCENARIOS

CLI = [sys.executable, "-m", "runner"]


def scenario(*args: str, cwd: Path = ROOT) -> subprocess.CompletedProcess[str]:
    return subprocess.run([*CLI, *args], capture_output=True, text=True, cwd=cwd, timeout=300)


def test_validate_misspelt_key_names_file_line_column_and_suggests(tmp_path: Path) -> None:
    text = (ROOT / "scenarios" / "factory_physics.yaml").read_text()
    bad = tmp_path / "bad.yaml"
    bad.write_text(
        text.replace("  box: {box: [0.3, 0.3, 0.3], density: 500", "  box: {box: [0.3, 0.3, 0.3], densty: 500")
    )
    line = next(i for i, row in enumerate(bad.read_text().splitlines(), 1) if "densty" in row)
    col = bad.read_text().splitlines()[line - 1].index("densty") + 1
    done = scenario("validate", str(bad))
    assert done.returncode == 2
    assert f"{bad}:{line}:{col}: bodies.box.densty: unknown key `densty`; did you mean `density`?" in done.stderr
    assert "Traceback" not in done.stderr


def test_validate_all_example_scenarios() -> None:
    done = scenario("validate", *map(str, SCENARIOS))
    assert done.returncode == 0, done.stderr
    assert done.stdout.count("ok ") == len(SCENARIOS)


def test_every_example_declares_the_committed_schema() -> None:
    for path in SCENARIOS:
        first = path.read_text().splitlines()[0]
        assert first == "# yaml-language-server: $schema=../runner/schema/scenario.schema.json", path


def test_committed_schema_is_in_sync() -> None:
    committed = (ROOT / "runner" / "schema" / "scenario.schema.json").read_text()
    assert committed == schema_text(), "run `make schema` and commit runner/schema/scenario.schema.json"


def test_run_json_exit_zero_and_traces(tmp_path: Path) -> None:
    done = scenario(
        "run", str(ROOT / "scenarios" / "factory_intervals.yaml"), "--all-variants", "--json", "--out", str(tmp_path)
    )
    assert done.returncode == 0, done.stderr
    results = json.loads(done.stdout)["results"]
    assert [r["variant"] for r in results] == ["door-closed", "door-opened-first", "space-twice", "open-then-close"]
    assert all(r["status"] == "passed" for r in results)
    assert all(Path(r["trace"]).exists() for r in results)


def test_failing_assertion_exits_one_with_the_verdict_table(tmp_path: Path) -> None:
    done = scenario(
        "run",
        str(ROOT / "scenarios" / "factory_intervals.yaml"),
        "--variant",
        "door-closed",
        "--set",
        "bodies.box.pos=[1, 0, 1.5]",
        "--out",
        str(tmp_path),
    )
    assert done.returncode == 1
    assert "FAIL" in done.stdout and "collision-fires-once" in done.stdout


def test_a_time_after_the_end_is_bad_input_naming_it(tmp_path: Path) -> None:
    """Shortening the run below the times its assertions name is refused up front, not failed at the end."""
    path = ROOT / "scenarios" / "factory_intervals.yaml"
    done = scenario("run", str(path), "--variant", "door-closed", "--set", "world.duration=1.0", "--out",
                    str(tmp_path))  # fmt: skip
    assert done.returncode == 2, done.stdout
    assert "is after the end of the run (world.duration 1 s)" in done.stderr
    assert f"{path}:" in done.stderr and "Traceback" not in done.stderr


def test_unknown_backend_and_variant_are_bad_input(tmp_path: Path) -> None:
    path = str(ROOT / "scenarios" / "factory_intervals.yaml")
    done = scenario("run", path, "--backend", "pybulet", "--out", str(tmp_path))
    assert done.returncode == 2 and "Did you mean `pybullet`?" in done.stderr
    done = scenario("run", path, "--variant", "door-closd", "--out", str(tmp_path))
    assert done.returncode == 2 and "unknown variant `door-closd`" in done.stderr


def test_blow_up_exits_three_naming_body_and_time(tmp_path: Path) -> None:
    src = tmp_path / "boom.yaml"
    src.write_text("""schema_version: 1
scenario: boom
world: {dt: 0.01, duration: 1}
bodies:
  rocket: {sphere: 0.1, density: 1000, pos: [0, 0, 1]}
on:
  start: [{force: {body: rocket, value: [0, 0, 1.0e9]}}]
assertions:
  - {name: alive, at: end, check: time > 0}
""")
    done = scenario("run", str(src), "--backend", "fake", "--out", str(tmp_path))
    assert done.returncode == 3
    assert "body `rocket`" in done.stdout and "t=0.0100" in done.stdout
    assert "last good state" in done.stdout
    inspect = scenario("inspect", str(tmp_path / "boom__base__fake.mcap"))
    assert inspect.returncode == 0 and "engine-failure" in inspect.stdout


def test_backends_lists_versions() -> None:
    done = scenario("backends")
    assert done.returncode == 0
    for name in ENGINES:
        assert name in done.stdout
    text = " ".join(done.stdout.split())  # rich wraps long cells
    assert "ODE 0.13.1" in text and "MuJoCo " in text and "DART " in text  # the engines' own versions


def test_a_rerun_replaces_its_own_trace_and_refuses_a_file_it_did_not_write(tmp_path: Path) -> None:
    path = str(ROOT / "scenarios" / "factory_intervals.yaml")
    assert scenario("run", path, "--backend", "fake", "--out", str(tmp_path), "-q").returncode == 0
    trace = tmp_path / "factory-intervals__door-closed__fake.mcap"
    before = trace.read_bytes()
    again = scenario("run", path, "--backend", "fake", "--out", str(tmp_path), "-q")
    assert again.returncode == 0, again.stderr
    assert trace.read_bytes() == before  # the same run again: the same bytes, in place
    trace.write_bytes(b"someone's notes")
    refused = scenario("run", path, "--backend", "fake", "--out", str(tmp_path), "-q")
    assert refused.returncode == 2 and "was not written by scenario" in refused.stderr and "--force" in refused.stderr
    assert trace.read_bytes() == b"someone's notes"
    assert scenario("run", path, "--backend", "fake", "--out", str(tmp_path), "-q", "--force").returncode == 0
    assert trace.read_bytes() == before


def test_isolate_reports_a_segfault_as_exit_three_and_keeps_the_trace(tmp_path: Path) -> None:
    done = scenario("run", str(ROOT / "scenarios" / "factory_physics.yaml"), "--variant", "door-stays-closed",
                    "--backend", "crash", "--isolate", "--out", str(tmp_path), "-q")
    assert done.returncode == 3
    assert "crashed (signal 11)" in done.stdout
    partial = tmp_path / "factory-physics__door-stays-closed__crash.mcap.partial"
    recovered = scenario("inspect", str(partial), "--recover")
    assert recovered.returncode == 0, recovered.stderr
    assert "factory-physics" in recovered.stdout
