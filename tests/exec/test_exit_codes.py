"""One exit code and one first message line per kind of failure, whatever runs the case (issue 14).

The cells of ``tests/exec/exit_table.py`` (the script that prints the table for docs/reliability.md), run
as a user runs the command: a runtime expression error, a `send` loop, an engine abort, a full disk, a
missing engine and a failed assertion, each serially, with ``-j 2``, ``--isolate``, ``--trace-process``,
on Ray (a cluster started with ``ray start --head``, when the ``ray`` extra is installed) and as a row of
``compare``. About a minute (30 commands, two at a time), plus about 40 s for Ray.
"""

from __future__ import annotations

import importlib.util
from collections.abc import Iterator

import pytest

from backends.registry import is_installed
from tests.exec.exit_table import PATHS, ROWS, Cell, Row, ray_cluster, table

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
    assert line and line.split(":")[0] in ("error", "crashed (signal 6)", "output error", "engine failure", "failed")


def test_compare_exits_by_its_own_rule(cells: dict[str, dict[str, Cell]]) -> None:
    """`compare` exits 1 when a run does not pass (the row says why); a full disk under its report is 74."""
    own = {name: found["compare"].command_code for name, found in cells.items()}
    assert own == {r.name: 74 if r.full_disk else 1 for r in ROWS}


def test_the_ray_column_ran(cells: dict[str, dict[str, Cell]]) -> None:
    if not HAS_RAY:
        pytest.skip("the `ray` extra is not installed: pip install 'physics-scenarios[ray]'")
    assert all("ray" in found for found in cells.values())
