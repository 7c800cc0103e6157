"""One command line: the same flags on every command (runner/cli/options.py), folders everywhere, `--set` wherever
a scenario is loaded, and the silent mistakes of the command line refused with their exact messages."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from reports.trace_format import LAYOUT_FILE
from runner.cli.main import main
from runner.language.files import scenario_files
from tests.paths import ROOT

PILE = str(ROOT / "scenarios" / "box_pile.yaml")
SMALL = """\
schema_version: 1
scenario: small
world: {dt: 0.01, duration: 0.1}
bodies:
  ball: {sphere: 0.1, mass: 1, pos: [0, 0, 1]}
assertions:
  - {name: falls, at: end, value: ball.vel.z, near: -0.1*9.81, tol: 1e-6}
"""
UNDECLARED = (
    "error: <command line>: --set params.cont: unknown parameter `cont` (a dotted path replaces a value, it does "
    "not declare one); did you mean `count`?"
)


def run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    code = main([str(a) for a in argv])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def small(tmp_path: Path, text: str = SMALL) -> str:
    path = tmp_path / "small.yaml"
    path.write_text(text)
    return str(path)


@pytest.mark.parametrize("command", ["run", "validate", "compare", "baseline", "check"])
def test_an_undeclared_parameter_is_refused_with_the_closest_name(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, command: str
) -> None:
    extra = {"run": ["--no-trace"], "compare": ["--out", tmp_path], "baseline": ["--baseline", tmp_path],
             "check": ["--baseline", tmp_path, "--out", tmp_path]}.get(command, [])  # fmt: skip
    code, _, err = run(capsys, command, PILE, "--set", "params.cont=3", "--backend", "pybullet", *extra)
    assert code == 2 and err.strip() == UNDECLARED


def test_a_sweep_over_an_undeclared_parameter_is_refused(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    code, _, err = run(capsys, "sweep", PILE, "--param", "params.cont=3,4", "--out", tmp_path)
    assert code == 2 and err.strip() == UNDECLARED.replace("--set", "--param")
    code, _, err = run(capsys, "sweep", PILE, "--param", "cont=3,4", "--out", tmp_path)
    assert code == 2 and err.strip() == "error: `--param cont=3,4`: unknown parameter `cont`; did you mean `count`?"
    assert not (tmp_path / "sweep.json").exists()


def test_a_misspelt_set_path_names_the_argument(capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = run(capsys, "run", PILE, "--set", "world.dtt=0.01", "--no-trace")
    assert code == 2 and err.strip() == "error: <command line>: --set world.dtt: unknown key `dtt`; did you mean `dt`?"


def test_validate_refuses_what_run_refuses(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    path = small(tmp_path, SMALL + "backend_options: {pybullet: {solver_iteration: 10}}\n")
    messages = []
    for command in (["validate"], ["run", "--no-trace"]):
        code, _, err = run(capsys, *command, path)
        assert code == 2
        messages.append(err)
    assert messages[0] == messages[1]
    assert "unknown option `solver_iteration` of backend `pybullet`; did you mean `solver_iterations`?" in messages[0]


def test_one_backend_flag_takes_a_list_or_all(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    path = small(tmp_path)
    code, out, _ = run(capsys, "run", path, "--backend", "pybullet,fake", "--no-trace", "-q")
    assert code == 0 and "2/2 runs passed" in out
    code, out, _ = run(capsys, "run", path, "-b", "pybullet", "-b", "fake", "--no-trace", "--json")
    assert code == 0 and out.count('"backend": "pybullet"') == 1 and out.count('"backend": "fake"') == 1
    from backends.registry import installed_backends

    code, out, _ = run(capsys, "run", path, "--backend", "all", "--no-trace", "-q")
    assert code == 0 and f"{len(installed_backends())}/{len(installed_backends())} runs passed" in out
    code, _, err = run(capsys, "run", path, "--backend", "pybullet,mujocoo", "--no-trace")
    assert code == 2 and "Did you mean `mujoco`?" in err


def test_folders_are_taken_by_every_command_recursing_like_pytest(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    everything = sorted((ROOT / "scenarios").rglob("*.yaml"))
    assert scenario_files([ROOT / "scenarios"]) == everything and len(everything) > 15
    # a folder and its subfolder: each file once; a file named twice: twice (as given)
    assert scenario_files([ROOT / "scenarios", ROOT / "scenarios" / "conformance"]) == everything
    twice = ROOT / "scenarios" / "factory_physics.yaml"
    assert scenario_files([twice, twice]) == [twice, twice]
    code, out, err = run(capsys, "validate", ROOT / "scenarios")
    assert code == 0 and out.count("ok ") == len(everything)  # the robot examples included (scenarios/robots/)
    folder = tmp_path / "cases" / "deeper"
    folder.mkdir(parents=True)
    small(folder)
    (folder / "notes.yaml").write_text("just: notes\n")  # not a scenario: not collected from a folder
    code, _, _ = run(capsys, "baseline", tmp_path / "cases", "--backend", "fake", "--baseline", tmp_path / "golden")
    assert code == 0 and [p.name for p in (tmp_path / "golden").iterdir()] == ["small__base__fake.golden"]
    code, out, _ = run(capsys, "check", tmp_path / "cases", "--backend", "fake", "--baseline", tmp_path / "golden",
                       "--out", tmp_path / "out", "--set", "description=checked")  # fmt: skip
    assert code == 0 and "1/1 cases match" in out
    code, _, err = run(capsys, "validate", tmp_path / "golden")
    assert code == 2 and "found none" in err


def test_the_pytest_plugin_collects_what_a_folder_stands_for() -> None:
    done = subprocess.run(
        [sys.executable, "-m", "pytest", "--collect-only", "-q", "-p", "no:cacheprovider", "--scenario-backends",
         "fake", "scenarios/"], capture_output=True, text=True, cwd=ROOT, timeout=300,
    )  # fmt: skip
    collected = sorted({line.split("::")[0] for line in done.stdout.splitlines() if "::" in line})
    assert collected == [str(p.relative_to(ROOT)) for p in scenario_files([ROOT / "scenarios"])], done.stdout[-2000:]


VARIANT = """\
schema_version: 1
scenario: small
params: {h: 1.0}
world: {dt: 0.01, duration: 0.5}
bodies:
  ball: {sphere: 0.1, mass: 1, pos: [0, 0, 1]}
variants:
  short:
    set: {world.duration: 0.2, params.h: 2.0}
    assertions:
      - {name: ends, at: end, value: time + 0*param.h, near: 0.3, tol: 1e-9}
      - {name: param, at: end, value: param.h, near: 3.0, tol: 0}
"""


def test_set_beats_a_variants_set_for_the_same_path(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    """The variant's `set:` silently beat `--set` (the variant was applied last); the rule: the command line
    is applied after the variant, so it wins for every path both set, on every command that loads."""
    path = small(tmp_path, VARIANT)
    code, out, err = run(capsys, "run", path, "--variant", "short", "--set", "world.duration=0.3", "--set",
                         "params.h=3.0", "--backend", "pybullet", "--no-trace")  # fmt: skip
    assert code == 0, out + err
    code, out, err = run(capsys, "run", path, "--variant", "short", "--backend", "pybullet", "--no-trace")
    assert code == 1 and "failed: 2 of 2 assertions: ends, param" in out + err, out + err


def test_layout_takes_a_folder_as_its_help_says(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    """`scenario layout FOLDER` was refused ("expected a scenario file, found a folder") though `--help` said
    folders are taken; it now collects a folder like every other command."""
    folder = tmp_path / "cases" / "deeper"
    folder.mkdir(parents=True)
    small(folder)
    code, _, err = run(capsys, "layout", tmp_path / "cases", "--out", tmp_path / "out")
    assert code == 0 and (tmp_path / "out" / LAYOUT_FILE).is_file(), err
    assert "ball" in (tmp_path / "out" / LAYOUT_FILE).read_text()  # the folder's scenario's body
