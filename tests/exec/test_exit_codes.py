"""One exit code and one first message line per kind of failure, whatever runs the case (issues 14, 27).

The cells of ``tests/exec/exit_table.py`` (the script that prints the table for docs/reliability.md), run as a
user runs the command: a runtime expression error, a `send` loop, an engine abort, a full disk, a missing
engine, a capability the engine lacks, a failed assertion, a known limit (an expected failure: exit 0), a
known limit that passes (exit 1), a read-only output, an integer overflow, an oversized mesh (refused when the
scenario is loaded) and a worker over its memory ceiling (exit 3), each serially, with ``-j 2``,
``--isolate``, ``--trace-process``, on Ray (a cluster started with ``ray start --head``, when the ``ray``
extra is installed), as a row of ``compare``, through ``check`` (against a golden file recorded first) and
through the pytest plugin; then `compare`'s agreement outcomes with ``--max-divergence``. 104 commands and 13
baselines, two at a time, and 2 comparisons (72 commands and 9 baselines took 10 min 17 s with Ray on the
shared 2-core machine while other work ran; the memory row's 8 commands and baseline, 23 s without Ray).
"""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from backends.registry import is_installed
from tests.exec.exit_table import (
    AGREEMENTS,
    PATHS,
    PYTEST_KINDS,
    ROWS,
    Agreement,
    Cell,
    Row,
    agreements,
    environment,
    ray_cluster,
    table,
)

pytestmark = pytest.mark.slow
NEEDED = {"ode": is_installed("ode"), "pybullet": is_installed("pybullet")}
HAS_RAY = importlib.util.find_spec("ray") is not None


@pytest.fixture(scope="module")
def cells() -> Iterator[dict[str, dict[str, Cell]]]:
    if not all(NEEDED.values()):
        pytest.skip(f"engine not installed: {', '.join(n for n, ok in NEEDED.items() if not ok)}")
    paths = [p for p in PATHS if p != "ray" or HAS_RAY]
    if HAS_RAY:
        with ray_cluster() as address:
            rows = table(paths, ray=address)
    else:
        rows = table(paths)
    yield {row.name: found for row, found in rows}


@pytest.mark.parametrize("row", ROWS, ids=[r.name for r in ROWS])
def test_one_exit_code_and_one_first_line_on_every_path(cells: dict[str, dict[str, Cell]], row: Row) -> None:
    found = cells[row.name]
    codes = {path: cell.code for path, cell in found.items()}
    assert set(codes.values()) == {row.code}, {p: (c.code, c.line, c.output[-3000:]) for p, c in found.items()}
    lines = {cell.line for cell in found.values()}
    assert len(lines) == 1 and "Traceback" not in "".join(c.output for c in found.values()), lines
    (line,) = lines
    assert line and line.split(":")[0] in ("error", "crashed (signal 6)", "output error", "engine failure", "failed",
                                           "known limit", "over memory")  # fmt: skip
    if row.code == 0:  # an expected failure: named with its figure on every path, not a failure
        assert line.startswith("known limit: rests on pybullet: measured 0.1 (documented 0.1)"), line
    elif "known limit" in row.name:
        assert line == "failed: 1 of 1 assertions: rests", line
        assert "known limit no longer needed: rests on pybullet now passes" in found["serial"].output


def test_compare_exits_by_its_own_rule(cells: dict[str, dict[str, Cell]]) -> None:
    """`compare` exits 1 when a run does not pass (the row says why), 0 when every run passes (a known limit
is an expected failure); a full disk under its report is 74; a scenario refused when it is loaded (an
oversized mesh), before any run, is bad input: 2."""
    own = {name: found["compare"].command_code for name, found in cells.items()}
    expected = {r.name: 74 if r.full_disk or r.read_only else 2 if r.refused_on_load else 1 if r.code else 0
                for r in ROWS}  # fmt: skip
    assert own == expected


@pytest.mark.parametrize("row", ROWS, ids=[r.name for r in ROWS])
def test_pytest_reports_each_row_as_run_judges_it(cells: dict[str, dict[str, Cell]], row: Row) -> None:
    """The plugin's item carries `run`'s first line and exit code (checked above with every path); pytest's own
    verdict is of the same kind: an error for what stopped the case (bad input, a refused capability, a
    missing engine, a crash, a full disk), a failure for a failed assertion, an xfail for a known limit; and
    pytest exits by its own rule, 1 when an item failed or errored, else 0."""
    cell = cells[row.name]["pytest"]
    assert cell.kind == PYTEST_KINDS.get(row.code, "ERROR"), cell.output[-3000:]
    assert cell.command_code == (0 if row.code == 0 else 1), cell.output[-3000:]


def test_check_exits_as_run(cells: dict[str, dict[str, Cell]]) -> None:
    """`check`'s own exit code is its case's (most_severe of one): the code `run` gives, on every row."""
    assert {n: found["check"].command_code for n, found in cells.items()} == {r.name: r.code for r in ROWS}


@pytest.fixture(scope="module")
def agreed() -> dict[str, Cell]:
    if not (NEEDED["pybullet"] and is_installed("mujoco")):
        pytest.skip("engine not installed: pybullet and mujoco are compared")
    return {row.name: cell for row, cell in agreements()}


@pytest.mark.parametrize("row", AGREEMENTS, ids=[r.name for r in AGREEMENTS])
def test_compare_agreement_outcomes(agreed: dict[str, Cell], row: Agreement) -> None:
    """Every assertion passes; with --max-divergence, engines apart by more than it fail `compare` (exit 1),
    engines within it pass (exit 0)."""
    cell = agreed[row.name]
    assert cell.code == row.code, cell.output[-3000:]
    assert "Traceback" not in cell.output, cell.output[-3000:]


def test_the_ray_column_ran(cells: dict[str, dict[str, Cell]]) -> None:
    if not HAS_RAY:
        pytest.skip("the `ray` extra is not installed: pip install 'physics-scenarios[ray]'")
    assert all("ray" in found for found in cells.values())


LIMIT_ROWS = [r for r in ROWS if "known limit" in r.name]


@pytest.mark.parametrize("row", LIMIT_ROWS, ids=[r.name for r in LIMIT_ROWS])
def test_known_limits_exit_alike_in_sweep_and_pytest(tmp_path: Path, row: Row) -> None:
    """The known-limit rows through `scenario sweep` and the pytest plugin (`pytest scenarios/`, the CI
    workflow of docs/ci.md): the same exit code as `run`; pytest reports the expected failure as an xfail,
    and the known limit that passes as a failure (strict)."""
    if not NEEDED["pybullet"]:
        pytest.skip("engine not installed: pybullet")
    source = tmp_path / "limit.yaml"
    source.write_text(row.text)
    sweep = [sys.executable, "-m", "runner", "sweep", str(source), "--backend", "pybullet", "--param",
             "world.dt=0.04,0.02", "--out", str(tmp_path / "sweep")]  # fmt: skip
    plugin = [sys.executable, "-m", "pytest", "-p", "runner.ci.pytest_plugin", "-p", "no:cacheprovider", "-q", "-rxX",
              "--scenario-backends", "pybullet", "--scenario-out", str(tmp_path / "py"), str(source)]  # fmt: skip
    done = {name: subprocess.run(cmd, capture_output=True, text=True, timeout=600, env=environment(), cwd=tmp_path)
            for name, cmd in (("sweep", sweep), ("pytest", plugin))}  # fmt: skip
    assert {n: d.returncode for n, d in done.items()} == {"sweep": row.code, "pytest": row.code}, {
        n: d.stdout[-3000:] + d.stderr[-2000:] for n, d in done.items()
    }
    verdict = "known limit" if row.code == 0 else "FAIL"
    assert (tmp_path / "sweep" / "sweep.csv").read_text().count(f",{verdict},") == 2  # both dt
    summary = done["pytest"].stdout
    if row.code == 0:
        assert "1 xfailed" in summary and "XFAIL limit.yaml::base[pybullet] - known limit: rests on pybullet" in summary
    else:
        assert "1 failed" in summary and "known limit no longer needed: rests on pybullet now passes" in summary
