"""Output safety: a re-run replaces the tool's own files and nothing else without --force, two cases never
share a trace, a half-written trace never has the final name, and text from a scenario or an engine is
printed as text.

Found by this suite: two files with the same `scenario:` name run in one command wrote the same trace,
the second silently replacing the first (without --force); text from a scenario was read as Rich
markup, so an assertion named "[/x]" (or a wrong value "[/x]") ended `run`, `validate` and `inspect`
with a MarkupError traceback (exit 1), and "[bold]x" was printed as "x".
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import shutil
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from reports.trace_reader import read_trace

SOURCE = """\
schema_version: 1
scenario: {name}
world: {{gravity: [0, 0, -9.81], dt: 0.01, duration: 0.5}}
bodies:
  ball: {{sphere: 0.1, density: 1000, pos: [0, 0, {z}]}}
assertions:
  - {{name: falls, at: end, value: ball.vel.z, near: -g*0.5, tol: 1e-9}}
"""


def scenario(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "runner", *args], capture_output=True, text=True, cwd=cwd,
                          timeout=120)  # fmt: skip


def digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


@pytest.fixture
def source(tmp_path: Path) -> Path:
    path = tmp_path / "fall.yaml"
    path.write_text(SOURCE.format(name="fall", z=2))
    return path


def test_a_rerun_replaces_its_own_trace_without_a_flag(tmp_path: Path, source: Path) -> None:
    first = scenario("run", str(source), "--backend", "fake", "--out", "out", cwd=tmp_path)
    assert first.returncode == 0, first.stderr
    trace = tmp_path / "out" / "fall__base__fake.mcap"
    before = digest(trace)
    source.write_text(SOURCE.format(name="fall", z=3))  # a different run gives different bytes
    again = scenario("run", str(source), "--backend", "fake", "--out", "out", cwd=tmp_path)
    assert again.returncode == 0, again.stderr
    assert digest(trace) != before and read_trace(trace).bodies["ball"].pos[0, 2] == 3.0
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["fall.foxglove-layout.json",
                                                                    "fall__base__fake.cost.json",
                                                                    "fall__base__fake.mcap",
                                                                    "foxglove-layout.json"]  # fmt: skip


@pytest.mark.parametrize("name", ["fall__base__fake.mcap", "fall__base__fake.mcap.partial",
                                  "fall__base__fake.cost.json", "fall__base__fake.outcome.json"])  # fmt: skip
def test_a_file_the_tool_did_not_write_is_refused_without_force(tmp_path: Path, source: Path, name: str) -> None:
    out = tmp_path / "out"
    out.mkdir()
    (out / name).write_bytes(b"someone's notes")
    done = scenario("run", str(source), "--backend", "fake", "--out", "out", cwd=tmp_path)
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert f"out/{name} was not written by scenario" in done.stderr and "--force" in done.stderr, done.stderr
    assert sorted(p.name for p in out.iterdir()) == [name] and (out / name).read_bytes() == b"someone's notes"
    forced = scenario("run", str(source), "--backend", "fake", "--out", "out", "--force", cwd=tmp_path)
    assert forced.returncode == 0 and read_trace(out / "fall__base__fake.mcap").complete
    assert not any((out / n).exists() for n in ("fall__base__fake.mcap.partial", "fall__base__fake.outcome.json"))


def test_a_partial_left_by_a_killed_run_is_replaced(tmp_path: Path, source: Path) -> None:
    """What a killed run left (a .partial of this tool, even cut inside its header) is the tool's own."""
    first = scenario("run", str(source), "--backend", "fake", "--out", "out", cwd=tmp_path)
    assert first.returncode == 0, first.stderr
    out = tmp_path / "out"
    whole = (out / "fall__base__fake.mcap").read_bytes()
    for cut in (len(whole) // 2, 30, 5, 0):
        (out / "fall__base__fake.mcap").unlink()
        (out / "fall__base__fake.mcap.partial").write_bytes(whole[:cut])
        done = scenario("run", str(source), "--backend", "fake", "--out", "out", cwd=tmp_path)
        assert done.returncode == 0, (cut, done.stderr)
        assert not (out / "fall__base__fake.mcap.partial").exists()
        assert read_trace(out / "fall__base__fake.mcap").complete


def test_two_cases_never_write_the_same_trace(tmp_path: Path) -> None:
    for folder, z in (("a", 2), ("b", 5)):
        (tmp_path / folder).mkdir()
        (tmp_path / folder / "fall.yaml").write_text(SOURCE.format(name="same", z=z))
    for extra in ([], ["--force"]):
        done = scenario("run", "a/fall.yaml", "b/fall.yaml", "--backend", "fake", "--out", "out", *extra,
                        cwd=tmp_path)  # fmt: skip
        assert done.returncode == 2, done.stdout + done.stderr
        assert "same__base__fake.mcap" in done.stderr and "Traceback" not in done.stderr
        assert not (tmp_path / "out" / "same__base__fake.mcap").exists()


def test_an_unwritable_output_is_bad_input(tmp_path: Path, source: Path) -> None:
    (tmp_path / "out").write_text("a file where the folder should be")
    done = scenario("run", str(source), "--backend", "fake", "--out", "out", cwd=tmp_path)
    assert done.returncode == 2 and "Traceback" not in done.stderr and "out" in done.stderr


def test_no_trace_writes_nothing(tmp_path: Path, source: Path) -> None:
    done = scenario("run", str(source), "--backend", "fake", "--no-trace", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fall.yaml"]


@contextlib.contextmanager
def read_only_folder(folder: Path) -> Iterator[Path]:
    """A folder nothing can be written into: a read-only tmpfs (root, whom permissions do not stop), else
    mode 555."""
    folder.mkdir()
    mounted = os.geteuid() == 0 and shutil.which("mount") is not None and subprocess.run(
        ["mount", "-t", "tmpfs", "-o", "ro,size=32k", "tmpfs", str(folder)]).returncode == 0  # fmt: skip
    if not mounted:
        folder.chmod(0o555)
    try:
        yield folder
    finally:
        if mounted:
            subprocess.run(["umount", str(folder)], check=False)
        else:
            folder.chmod(0o755)


@pytest.mark.parametrize("where,options", [("out", []), ("out", ["--trace-process"]), ("out", ["-j", "2"]),
                                           ("out/sub", [])])  # fmt: skip
def test_a_read_only_output_is_an_output_error(tmp_path: Path, source: Path, where: str, options: list[str]) -> None:
    """A read-only `--out` exited 2 (bad input); it is an output that cannot take the trace, as a full disk:
    exit 74, "output error", on every path, and nothing is written."""
    with read_only_folder(tmp_path / "out"):
        done = scenario("run", str(source), "--backend", "fake", "--out", where, *options, cwd=tmp_path)
        assert done.returncode == 74, done.stdout + done.stderr
        assert "output error: cannot" in done.stderr and "Traceback" not in done.stderr, done.stderr
        assert list((tmp_path / "out").iterdir()) == []


MARKUP = """\
schema_version: 1
scenario: markup
world: {dt: 0.04, duration: 0.2}
bodies:
  box: {box: [0.3, 0.3, 0.3], density: 500, pos: [0, 0, 1]}
inputs: [{at: 0.04, event: "[/e]"}]
on:
  "[/e]": [{log: {message: "[/m]"}}]
assertions:
  - {name: "[/x]", at: end, check: time < 0}
  - {name: "[bold]y", at: end, check: time > 0}
"""


def test_scenario_text_is_printed_as_text_not_markup(tmp_path: Path) -> None:
    folder = tmp_path / "[red]dir"
    folder.mkdir()
    (folder / "m.yaml").write_text(MARKUP)
    (folder / "bad.yaml").write_text(MARKUP.replace("dt: 0.04", 'dt: "[/dt]"'))
    ok = scenario("validate", "[red]dir/m.yaml", cwd=tmp_path)
    assert ok.returncode == 0 and "[red]dir/m.yaml" in ok.stdout, ok.stdout + ok.stderr
    bad = scenario("validate", "[red]dir/bad.yaml", cwd=tmp_path)
    assert bad.returncode == 2 and "'[/dt]'" in bad.stderr and "Traceback" not in bad.stderr, bad.stderr
    run = scenario("run", "[red]dir/m.yaml", "--backend", "fake", "--out", "out", cwd=tmp_path)
    assert run.returncode == 1 and "Traceback" not in run.stderr, run.stderr
    assert "[/x]" in run.stdout and "[bold]y" in run.stdout
    inspect = scenario("inspect", "out/markup__base__fake.mcap", cwd=tmp_path)
    assert inspect.returncode == 0 and "Traceback" not in inspect.stderr, inspect.stderr
    assert "[/e]" in inspect.stdout and "[/x]" in inspect.stdout and "[bold]y" in inspect.stdout


def test_emoji_codes_in_locations_and_names_are_printed_as_text(tmp_path: Path) -> None:
    """Every error on line 100 printed as `file.yaml💯29:`: Rich replaced the emoji code `:100:` in the
    location (and `:smile:` in a name) unless the console is told not to."""
    folder = tmp_path / "[bold]d:smile:"
    folder.mkdir()
    bad = "# padding\n" * 97 + MARKUP.replace("dt: 0.04", 'dt: "[bold]x :100: [red]"')  # world: on line 100
    (folder / "bad.yaml").write_text(bad)
    named = MARKUP.replace("[bold]y", "[bold]y :100: :smile:")
    (folder / "m.yaml").write_text(named)
    shown = "[bold]d:smile:/bad.yaml:100:"
    done = scenario("validate", "[bold]d:smile:/bad.yaml", cwd=tmp_path)
    assert done.returncode == 2 and shown in done.stderr and "'[bold]x :100: [red]'" in done.stderr, done.stderr
    run = scenario("run", "[bold]d:smile:/m.yaml", "--backend", "fake", "--out", "out:100:", cwd=tmp_path)
    assert run.returncode == 1 and "[bold]y :100: :smile:" in run.stdout, run.stdout + run.stderr
    assert "out:100:/markup__base__fake.mcap" in run.stdout
    inspect = scenario("inspect", "out:100:/markup__base__fake.mcap", cwd=tmp_path)
    assert inspect.returncode == 0 and "[bold]y :100: :smile:" in inspect.stdout, inspect.stdout
    junit_run = scenario("run", "[bold]d:smile:/m.yaml", "--backend", "fake", "--out", "o2", "--junit", "j.xml",
                         cwd=tmp_path)  # fmt: skip
    assert junit_run.returncode == 1, junit_run.stderr
    junit = (tmp_path / "j.xml").read_text(encoding="utf-8")
    assert "[bold]y :100: :smile:" in junit, junit
    from reports.inspect import summary_text
    from reports.trace_reader import read_trace

    summary = summary_text(read_trace(tmp_path / "out:100:" / "markup__base__fake.mcap"))
    assert "[bold]y :100: :smile:" in summary, summary
    emoji = ("\N{HUNDRED POINTS SYMBOL}", "\N{SMILING FACE WITH OPEN MOUTH AND SMILING EYES}")
    for output in (done.stderr, run.stdout, run.stderr, inspect.stdout, junit, summary):
        assert not any(e in output for e in emoji), output
