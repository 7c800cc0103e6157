"""Every command in the README and docs/, run as written, in the order written.

A fenced block tagged `sh` is a list of commands (a trailing backslash continues a line; `# -> exit N` at
the end of a line is the exit code the text promises, 0 otherwise). A block tagged `yaml FILE` is a listing
of FILE: it is written before the commands after it run (the tutorial grows its file this way). Each
document runs in its own folder, where `scenarios/`, `docs/` and `runner/` are the repository's (read only)
and `baselines/` a copy; `scenario`, `pytest` and `python` are the environment's. The commands not run here
are listed in SKIPPED with the reason, and must match exactly, so that no new command escapes unseen.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

from tests.paths import ROOT

DOCUMENTS = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
EXIT = re.compile(r"#\s*->\s*exit\s+(\d+)\s*$")
COMMENT = re.compile(r"\s{2,}#.*$")  # a comment after a command (two spaces or more before the #)
SKIPPED = {
    "make test": "this suite (it runs the test that runs the documented commands)",
    "make demo": "run by hand before each release (4 variants on every engine, then `compare`: about 2 min)",
    "git add baselines && git commit -m \"Baselines\"": "version control, not the tool",
    "FUZZ_CASES=20000 FUZZ_STRUCTURED=20000 FUZZ_FILES=5000 FUZZ_FAULTS=200 FUZZ_CONCURRENT=20 .venv/bin/python -m "
    "pytest -q "
    "-p no:cacheprovider tests/reliability":
        "`make fuzz` itself (about an hour); its figures are in docs/reliability.md",
    "python bench/gpu_batch.py": "needs a CUDA device (without one it refuses by name, exit 2; "
    "tests/backends/test_mujoco_warp_cli.py checks that refusal)",
    "python bench/gpu_batch.py --device cuda:1 --worlds 1,64,1024,8192,32768 --steps 200 --out gpu.md":
        "needs a second CUDA device",
    "scenario sweep scenarios/box_pile.yaml --param count=10,50,100,200 --backend pybullet,mujoco,dart "
    "--executor ray --ray-address auto --out sweeps/pile":
        "needs a Ray cluster (tests/exec/test_ray.py runs a local one)",
}  # fmt: skip


@dataclass(frozen=True)
class Step:
    document: Path
    line: int
    command: str | None = None  # a shell command, or
    expected: int = 0
    listing: tuple[str, str] | None = None  # (file name, text) to write


def steps(document: Path) -> list[Step]:
    out: list[Step] = []
    lines = document.read_text(encoding="utf-8").splitlines()
    i = 0
    while i < len(lines):
        info = lines[i].strip()[3:].strip() if lines[i].strip().startswith("```") else None
        if info is None or not info:
            i += 1
            continue
        start = i
        body: list[str] = []
        i += 1
        while i < len(lines) and not lines[i].strip().startswith("```"):
            body.append(lines[i])
            i += 1
        i += 1
        kind, _, name = info.partition(" ")
        if kind == "yaml" and name:
            out.append(Step(document, start + 1, listing=(name.strip(), "\n".join(body) + "\n")))
        elif kind in ("sh", "console", "bash"):
            out += _commands(document, start + 1, body)
    return out


def _commands(document: Path, first: int, body: list[str]) -> list[Step]:
    out: list[Step] = []
    pending = ""
    for k, raw in enumerate(body):
        line = raw.rstrip()
        if line.endswith("\\"):
            pending += line[:-1].rstrip() + " "
            continue
        line = pending + line.strip()
        pending = ""
        match = EXIT.search(line)
        expected = int(match.group(1)) if match else 0
        command = COMMENT.sub("", line).strip()
        if command:
            out.append(Step(document, first + k + 1, command, expected))
    return out


ALL = [s for d in DOCUMENTS for s in steps(d)]


def test_the_documents_hold_commands_and_every_skip_is_one_of_them() -> None:
    commands = {s.command for s in ALL if s.command}
    assert len(commands) >= 20
    assert set(SKIPPED) <= commands, set(SKIPPED) - commands


def _sandbox(folder: Path) -> None:
    for name in ("scenarios", "docs", "runner"):
        (folder / name).symlink_to(ROOT / name)
    shutil.copytree(ROOT / "baselines", folder / "baselines")


@pytest.mark.parametrize("document", [d for d in DOCUMENTS if any(s.document == d for s in ALL)],
                         ids=lambda d: str(d.relative_to(ROOT)))  # fmt: skip
def test_every_documented_command_runs_as_written(document: Path, tmp_path: Path) -> None:
    _sandbox(tmp_path)
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ.get('PATH', '')}",
           "COLUMNS": "160"}  # fmt: skip
    ran = 0
    for step in (s for s in ALL if s.document == document):
        if step.listing is not None:
            name, text = step.listing
            (tmp_path / name).write_text(text, encoding="utf-8")
            continue
        assert step.command is not None
        if step.command in SKIPPED:
            continue
        done = subprocess.run(["bash", "-c", step.command], cwd=tmp_path, env=env, capture_output=True, text=True,
                              timeout=900)  # fmt: skip
        where = f"{document.relative_to(ROOT)}:{step.line}: {step.command}"
        output = f"{done.stdout[-3000:]}\n{done.stderr[-3000:]}"
        assert done.returncode == step.expected, f"{where}\nexit {done.returncode}\n{output}"
        assert "Traceback" not in done.stderr, f"{where}\n{done.stderr[-3000:]}"
        ran += 1
    assert ran or all(s.command in SKIPPED for s in ALL if s.document == document and s.command)


def examples(document: Path) -> list[tuple[int, str]]:
    """Whole scenarios shown in a document (```yaml blocks with a `schema_version:` line), with their line."""
    found, lines, i = [], document.read_text(encoding="utf-8").splitlines(), 0
    while i < len(lines):
        if lines[i].strip() == "```yaml":
            j = next(k for k in range(i + 1, len(lines)) if lines[k].strip().startswith("```"))
            text = "\n".join(lines[i + 1 : j]) + "\n"
            if re.search(r"^schema_version:", text, re.MULTILINE):
                found.append((i + 1, text))
            i = j
        i += 1
    return found


def test_every_scenario_shown_in_the_documents_is_valid(tmp_path: Path) -> None:
    from runner.compile.program import build_program
    from runner.errors import ScenarioValidationError
    from runner.language.load import BASE_CASE, load_scenario, variant_names

    shown = [(d, line, text) for d in DOCUMENTS for line, text in examples(d)]
    assert shown
    for document, line, text in shown:
        path = tmp_path / "example.yaml"
        path.write_text(text)
        try:
            for name in variant_names(path):
                build_program(load_scenario(path, None if name == BASE_CASE else name))
        except ScenarioValidationError as exc:
            pytest.fail(f"the scenario at {document.relative_to(ROOT)}:{line} is refused:\n{exc}")


def test_the_tutorials_last_listing_is_the_committed_file() -> None:
    listings = [s.listing for s in ALL if s.listing and s.document.name == "tutorial.md"]
    assert listings and listings[-1] == ("drop.yaml", (ROOT / "docs" / "tutorial" / "drop.yaml").read_text())
