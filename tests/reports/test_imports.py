"""The import comparison of `scenario compare` (reports/imports.py, imports_render.py, runner/exec/imports.py).

The comparison's logic is checked on reads written here (what flags, within which tolerance, what the output
escapes); the real thing on kuka_arm.yaml read back from every installed engine, in this process (about 3 s)
and through the CLI (`--imports-only`: builds every engine's world in workers, steps none; about 5 s). Engine
lists come from the registry.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from backends.registry import get_backend, installed_backends
from backends.types import Precision
from reports.build import write_report
from reports.imports import FLOAT32_DIGITS, NOT_REPORTED, READ, ROUNDINGS, compare, tolerance
from reports.imports_render import markdown_section, summary, terminal_lines
from runner.exec.cases import Case
from runner.exec.imports import file_digits, import_job
from runner.language.load import load_scenario

from .conftest import KUKA, CompareRun, scenario

EPS32, EPS64 = Precision.FLOAT32.eps, Precision.FLOAT64.eps


def _read(backend: str, eps: float, mass: float = 1.0, lo: float | None = -1.0, damping: list[Any] | None = None,
          name: str = "r.link") -> dict[str, Any]:  # fmt: skip
    body = {"mass": mass, "inertia": [0.1, 0.2, 0.3], "com": [0.0, 0.0, 0.1], "shapes": 1, "reach": 1.0}
    joint = {"kind": "hinge", "axis": [0.0, 0.0, 1.0], "lo": lo, "hi": 1.0, "damping": damping or [None, 0.0],
             "frictionloss": [None, 0.0], "effort": [None, None], "velocity": [None, None]}  # fmt: skip
    return {"backend": backend, "status": READ, "eps": eps, "version": "1", "bodies": {name: body},
            "joints": {"r.joint": joint}, "notes": []}  # fmt: skip


def _table(tables: list[Any], title: str) -> Any:
    return next(t for t in tables if t.title == title)


def test_the_tolerance_is_the_formats_and_the_files() -> None:
    assert tolerance(EPS64, EPS64, 17) == ROUNDINGS * EPS64
    assert tolerance(EPS32, EPS64, 17) == ROUNDINGS * EPS32  # the coarser format rules
    assert tolerance(EPS64, EPS64, 12) == 0.5e-11  # kuka: 12 digits
    assert tolerance(EPS64, EPS64, 2) == 0.5 * 10.0 ** (1 - FLOAT32_DIGITS)  # a hand-written file: float32's digits


def test_a_float32_rounding_is_no_difference_but_a_mass_beyond_it_is() -> None:
    """One float32 rounding of 1.1 (2.4e-8 relative) is within 8 eps32 (9.5e-7); 3e-6 more is not."""
    mass32 = float(np.float32(1.1))
    reads = [_read("a", EPS64, 1.1), _read("b", EPS32, mass32), _read("c", EPS64, 1.1 * (1 + 3e-6))]
    mass = _table(compare(reads, 17), "mass").rows[0]
    assert not mass.agree
    assert [b for b, c in mass.cells.items() if c.flagged] == ["c"]  # a and b agree: the larger group
    assert mass.cells["c"].text == "1.1000033"  # 9 digits where engines differ
    alike = _table(compare(reads[:2], 17), "mass").rows[0]
    assert alike.agree and alike.agreed() == "1.1"


def test_a_missing_stop_and_the_engines_own_damping_are_flagged() -> None:
    reads = [_read("a", EPS64), _read("b", EPS64), _read("c", EPS64, lo=None, damping=[0.5, 0.0])]
    tables = compare(reads, 17)
    limits, damping = _table(tables, "joint limits").rows[0], _table(tables, "damping").rows[0]
    assert limits.cells["c"].flagged and limits.cells["c"].text == "none .. 1"
    assert damping.cells["c"].flagged and damping.cells["c"].text == "0.5 engine"
    # the same damping carried by the runner's motor on the others is no difference
    same = [_read("a", EPS64, damping=[None, 0.5]), _read("b", EPS64, damping=[0.5, 0.0])]
    row = _table(compare(same, 17), "damping").rows[0]
    assert row.agree and {c.text for c in row.cells.values()} == {"0.5 runner", "0.5 engine"}


def test_an_engine_that_cannot_report_is_said_so_and_not_flagged() -> None:
    reads = [_read("a", EPS64), _read("b", EPS64), {"backend": "c", "status": NOT_REPORTED, "eps": EPS64}]
    section = {"scenario": "s", "variant": "base", "digits": 17, "reads": reads}
    lines = terminal_lines(section)
    assert "  c: not reported" in lines
    assert not any("≠" in line for line in lines)
    assert summary(section) == "the 2 engines imported the model alike"


def test_markdown_escapes_the_files_names() -> None:
    reads = [_read("a", EPS64, name="r.li|nk*"), _read("b", EPS64, 2.0, name="r.li|nk*")]
    md = markdown_section({"scenario": "s_1", "variant": "base", "digits": 17, "reads": reads})
    assert "r.li\\|nk\\*" in md and "r.li|nk*" not in md and "s\\_1" in md
    row = next(line for line in md.splitlines() if line.startswith("| r.li"))
    assert re.split(r"(?<!\\)\|", row.strip("|"))[2].strip() == "**≠ 2**"  # b departs; a is the first group


def test_file_digits_are_the_most_precise_number(tmp_path: Path) -> None:
    urdf = tmp_path / "m.urdf"
    urdf.write_text('<robot name="r"><link name="a"><inertial><mass value="0.00120"/>'
                    '<origin xyz="1.57079632679 -2e-3 0"/></inertial></link></robot>')  # fmt: skip
    assert file_digits([str(urdf)]) == 12


def test_kuka_on_every_engine_differs_only_in_the_damping_the_engine_holds() -> None:
    """kuka_arm's seven joints are all servo-driven: the runner applies no damping to them (its motor is the
    servo's), and an engine that holds the URDF's damping itself (``native_damping``) still damps them. That is
    the one difference; the masses, inertias, COMs, shapes, axes and stops agree within the tolerance on every
    engine (ODE's float32 included)."""
    engines = installed_backends()
    if len(engines) < 2:
        pytest.skip("needs two engines")
    reads = [{"backend": b, **import_job(Case(str(KUKA), None, b))} for b in engines]
    assert all(r["status"] == READ for r in reads), reads
    tables = compare(reads, file_digits([load_scenario(KUKA).robots["arm"].file]))
    differing = {t.title for t in tables if t.differences}
    native = sorted(b for b in engines if get_backend(b).native_damping)
    others = sorted(set(engines) - set(native))
    if not native or not others:
        assert differing == set()
        return
    assert differing == {"damping"}
    damping = _table(tables, "damping")
    assert all(not r.agree for r in damping.rows) and len(damping.rows) == 7
    if len(native) != len(others):
        smaller = native if len(native) < len(others) else others
        for row in damping.rows:
            assert sorted(b for b, c in row.cells.items() if c.flagged) == smaller
    for row in damping.rows:
        for b in native:
            assert row.cells[b].text.endswith("0.5 engine")


def test_compare_shows_the_import_table_before_any_step() -> None:
    """`scenario compare kuka_arm.yaml --imports-only` on every installed engine: the tables, the flag, exit 0,
    and nothing run (no report)."""
    engines = installed_backends()
    done = scenario("compare", str(KUKA), "--imports-only", "--backends", ",".join(engines), "-j", "2")
    assert done.returncode == 0, done.stdout + done.stderr
    out = done.stdout
    assert "How each engine imported the robots of kuka-arm · base (before any step)" in out
    for b in engines:
        assert f"{b} " in out.splitlines()[1]  # the engines line
    assert "  mass [kg]: all 7 agree" in out
    assert "    arm.lbr_iiwa_link_1  4" in out and "    arm.lbr_iiwa_link_7  0.3" in out
    assert "  joint limits [rad or m, from the start]: all 7 agree" in out
    assert "    arm.lbr_iiwa_joint_7  -3.05433 .. 3.05433" in out
    assert "  collision shapes [count]: all 7 agree: 1" in out
    native = [b for b in engines if get_backend(b).native_damping]
    if native and len(native) < len(engines):
        assert "damping [N m s/rad or N s/m]: 7 of 7 differ" in out
    assert "comparing" not in out  # no run started


@pytest.mark.slow
def test_the_comparison_report_shows_the_imports(kuka_compare: CompareRun, tmp_path: Path) -> None:
    """The shared kuka_arm comparison (about 12 s): the table is printed before the runs start, kept beside the
    traces, shown in report.md and report.html, and a report rebuilt from the traces shows it the same."""
    out = kuka_compare.done.stdout
    assert out.index("How each engine imported the robots of kuka-arm") < out.index("comparing 1 case(s)")
    assert (kuka_compare.traces / "imports.json").is_file()
    md = (kuka_compare.out / "report.md").read_text(encoding="utf-8")
    assert "## How each engine imported the robots: kuka-arm · base" in md
    assert "**mass \\[kg\\]\\: all 7 agree**" in md
    html = (kuka_compare.out / "report.html").read_text(encoding="utf-8")
    assert '<section class="imports">' in html and "principal inertia about the COM" in html
    again = tmp_path / "again"
    write_report([kuka_compare.traces], again)
    section = md[md.index("## How each engine imported") :]
    rebuilt = (again / "report.md").read_text(encoding="utf-8")
    assert rebuilt[rebuilt.index("## How each engine imported") :] == section  # the links to traces differ
