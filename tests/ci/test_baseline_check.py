"""`scenario baseline` then `scenario check` on PyBullet: a match, a changed surface, tolerances, engine versions."""

from __future__ import annotations

import re
import shutil
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from backends.registry import engine_version
from runner.ci.golden_read import read_golden
from runner.ci.regression import check_cases, golden_path
from runner.language.load import load_scenario

from .conftest import FACTORY, cli

GOLDEN = "factory-physics__door-stays-closed__pybullet.golden"


def test_baseline_then_check_passes(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, text = cli(capsys, "baseline", FACTORY, "--backend", "pybullet", "--dir", tmp_path / "b")
    assert code == 0, text
    assert sorted(p.name for p in (tmp_path / "b").iterdir()) == sorted(
        f"factory-physics__{v}__pybullet.golden"
        for v in ("door-stays-closed", "door-opens-with-the-box-on-it", "door-moves-away-box-falls",
                  "reset-box-on-closed-door")
    )  # fmt: skip
    golden = read_golden(tmp_path / "b" / GOLDEN)
    assert golden.header["engine"] == engine_version("pybullet") and golden.header["every"] == "2"  # 0.1 s / 0.04
    code, text = cli(capsys, "check", FACTORY, "--baseline", tmp_path / "b", "--out", tmp_path / "t")
    assert code == 0, text
    assert "4/4 cases match their baselines and pass" in text and "warning" not in text


def test_changed_surface_fails_at_the_first_contact(
    factory_goldens: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """bounce only acts when the box first hits the door: every state before that contact is identical, and the
    step that resolves it (the one that ends at the first `box-into-door`) already differs."""
    copy = tmp_path / "bouncier.yaml"
    text = FACTORY.read_text()
    copy.write_text(text.replace("surface: {bounce: 0.2,", "surface: {bounce: 0.5,", 1))
    assert copy.read_text() != text
    out = tmp_path / "out"
    code, output = cli(capsys, "check", copy, "--variant", "door-stays-closed", "--baseline", factory_goldens,
                       "--out", out)  # fmt: skip
    assert code == 1, output
    golden = read_golden(factory_goldens / GOLDEN)
    contact = next(t for t, name, _ in golden.events if name == "box-into-door")
    assert contact == pytest.approx(1.0)  # landing step 25, see the scenario's comments
    found = re.search(r"first divergence: t=([0-9.]+) s, body `box`, (\w+)\.(\w)", output)
    assert found is not None, output
    assert float(found.group(1)) == contact
    assert found.group(2) in ("pos", "vel")
    assert "note: the scenario file differs" in output
    svg = out / GOLDEN.replace(".golden", ".divergence.svg")
    root = ET.parse(svg).getroot()
    ns = "{http://www.w3.org/2000/svg}"
    marks = [g.get("class", "") for g in root.iter(f"{ns}g")]
    assert root.tag == f"{ns}svg" and marks.count("mark-line role-mark layer_1_marks") == 2  # baseline and run
    assert any(c.startswith("mark-area role-mark") for c in marks)  # the tolerance band
    texts = {t.text for t in root.iter(f"{ns}text")}
    assert {f"first divergence {contact:g} s", "this run", "t (s)"} <= texts
    assert any(t and t.startswith("box.") and t.endswith(("(m)", "(m/s)")) for t in texts)  # the axis names its unit
    assert f"plot: {svg}" in output

    (outcome,) = check_cases([(load_scenario(copy, "door-stays-closed"), "pybullet")], factory_goldens, tmp_path / "o")
    assert outcome.comparison is not None and outcome.comparison.first is not None
    assert all(c.first_over is None or c.first_over >= contact for c in outcome.comparison.changes)
    assert outcome.comparison.first.signal == "box.vel.z"  # the largest excess at that time: the rebound
    assert float(outcome.comparison.first.got) > float(outcome.comparison.first.expected) > 0


def _perturb(path: Path, time: str, delta: float) -> float:
    """Add ``delta`` to the box's pos.z on its line at ``time``; returns the new value."""
    lines = path.read_text().splitlines()
    i = next(i for i, line in enumerate(lines) if line.startswith(f"body {time} box pos "))
    parts = lines[i].split()
    parts[6] = f"{float(parts[6]) + delta:.9g}"
    lines[i] = " ".join(parts)
    path.write_text("\n".join(lines) + "\n")
    return float(parts[6])


def test_tolerances_from_the_file_and_the_command_line(
    factory_goldens: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    goldens = tmp_path / "b"
    goldens.mkdir()
    path = goldens / GOLDEN
    shutil.copy(factory_goldens / GOLDEN, path)
    moved = _perturb(path, "3", 5e-6)  # beyond the default 1e-6 + 1e-6 * 0.2
    args = ["check", FACTORY, "--variant", "door-stays-closed", "--baseline", goldens, "--out", tmp_path / "t"]
    code, output = cli(capsys, *args)
    assert code == 1
    assert f"first divergence: t=3 s, body `box`, pos.z: expected {moved:.9g}" in output
    assert cli(capsys, *args, "--atol", "pos=1e-5")[0] == 0
    assert cli(capsys, *args, "--atol", "1e-5")[0] == 0
    assert cli(capsys, *args, "--atol", "vel=1e-5")[0] == 1  # another field's tolerance does not help
    path.write_text(path.read_text().replace("tolerance default atol=1e-06", "tolerance box.pos atol=1e-05\n"
                                             "tolerance default atol=1e-06"))  # fmt: skip
    assert cli(capsys, *args)[0] == 0
    code, output = cli(capsys, "baseline", FACTORY, "--variant", "door-stays-closed", "--dir", goldens)
    assert code == 0, output
    assert "tolerance box.pos atol=1e-05\n" in path.read_text()  # re-recording keeps the file's tolerances


def test_engine_version_change_warns_and_names_what_moved(
    factory_goldens: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    goldens = tmp_path / "b"
    goldens.mkdir()
    path = goldens / GOLDEN
    installed = engine_version("pybullet")
    path.write_text((factory_goldens / GOLDEN).read_text().replace(f"engine {installed}\n", "engine 0.0.1\n"))
    args = ["check", FACTORY, "--variant", "door-stays-closed", "--baseline", goldens, "--out", tmp_path / "t"]
    code, output = cli(capsys, *args)
    assert code == 0, output
    assert f"pybullet {installed} is installed but the baseline was recorded with 0.0.1; no signal moved" in output
    _perturb(path, "2", 4e-7)  # inside the tolerance: still a pass, but it moved
    code, output = cli(capsys, *args)
    assert code == 0, output
    assert "signals that moved: box.pos.z (max 4e-07 at 2 s)" in output


def test_missing_baseline_is_bad_input(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, output = cli(capsys, "check", FACTORY, "--variant", "door-stays-closed", "--baseline", tmp_path, "--out",
                       tmp_path / "t")  # fmt: skip
    assert code == 2
    assert f"no baseline {golden_path(tmp_path, load_scenario(FACTORY, 'door-stays-closed'), 'pybullet')}" in output
    assert "record it with `scenario baseline" in output
