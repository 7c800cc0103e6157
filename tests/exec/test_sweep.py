"""`scenario sweep`: parameter parsing, the cross product, the CSV/JSON table, the SVG plot, exit codes.

Runs short box piles on PyBullet (0.4 s); about 4 s in all.
"""

from __future__ import annotations

import csv
import json
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from reports.trace_reader import read_trace
from runner.cli.commands.sweep import parse_params, split_values
from runner.cli.main import main
from runner.cli.sweep_metrics import check_metrics, final_values
from runner.cli.sweep_table import plot
from runner.errors import UsageError
from runner.language.load import load_scenario
from runner.sim.run import run_loaded

ROOT = Path(__file__).resolve().parents[2]
PILE = ROOT / "scenarios" / "box_pile.yaml"
FACTORY = ROOT / "scenarios" / "factory_physics.yaml"


def test_values_split_on_top_level_commas_only() -> None:
    assert split_values("1, 2.5,inf") == ["1", "2.5", "inf"]
    assert split_values("[0, 0, 1],[1, 0, 0]") == ["[0, 0, 1]", "[1, 0, 0]"]
    assert split_values("{a: 1, b: 2},x") == ["{a: 1, b: 2}", "x"]
    with pytest.raises(UsageError):
        split_values("1,,2")


def test_params_are_set_paths_and_declared_names() -> None:
    grid = parse_params(["count=1,2", "world.dt=0.01,0.02", "surface.mu=0.5,.inf", "description=a,b"], {"count"})
    assert grid == [("params.count", [1, 2]), ("world.dt", [0.01, 0.02]), ("surface.mu", [0.5, float("inf")]),
                    ("description", ["a", "b"])]  # fmt: skip
    with pytest.raises(UsageError, match="twice"):
        parse_params(["count=1", "params.count=2"], {"count"})
    with pytest.raises(UsageError, match="NAME=v1"):
        parse_params(["count"], {"count"})


def test_sweep_writes_the_cross_product_table_and_plot(tmp_path: Path) -> None:
    code = main([
        "sweep", str(PILE), "--param", "count=2,4", "--backends", "pybullet", "--all-variants",
        "--set", "world.duration=0.4", "--metric", "max(crate.pos.z)", "--metric", "count('start')",
        "--out", str(tmp_path), "-q",
    ])  # fmt: skip
    assert code == 1  # 0.4 s is too short for the pile-settles window: a failed assertion, exit 1
    table = json.loads((tmp_path / "sweep.json").read_text())
    assert table["parameters"] == ["params.count"]
    assert [r["params"]["params.count"] for r in table["rows"]] == [2, 4]
    assert table["assertions"] == ["pile-settles", "top-box-height", "column-stays-aligned", "lowest-box-on-the-ground"]
    for row in table["rows"]:
        n = row["params"]["params.count"]
        assert row["status"] == "failed" and row["failed"] == 1 and not row["verdicts"]["pile-settles"]["passed"]
        # the boxes have landed: the top one 0.3 m per box above the lowest one's centre (0.15)
        assert row["metrics"]["max(crate.pos.z)"] == pytest.approx(0.15 + 0.3 * (n - 1), abs=0.01 * n)
        assert row["metrics"]["count('start')"] == 1
        assert (tmp_path / row["trace"]).is_file()
    rows = list(csv.DictReader((tmp_path / "sweep.csv").read_text().splitlines()))
    assert [r["params.count"] for r in rows] == ["2", "4"]
    assert [r["pile-settles"] for r in rows] == ["FAIL", "FAIL"]
    assert float(rows[1]["max(crate.pos.z)"]) == table["rows"][1]["metrics"]["max(crate.pos.z)"]
    svg = ET.fromstring((tmp_path / "sweep.svg").read_text())
    ns = "{http://www.w3.org/2000/svg}"
    lines = [g for g in svg.iter(f"{ns}g") if g.get("class", "").startswith("mark-line role-mark")]
    assert len(lines) == 2  # one per numeric metric, one series (one backend, one variant)
    paths = [p.get("d", "") for g in lines for p in g.iter(f"{ns}path")]
    assert len(paths) == 2 and all(d.count("L") == 1 for d in paths)  # two points each: count 2 and 4
    texts = {t.text for t in svg.iter(f"{ns}text")}
    assert {"count", "max(crate.pos.z)", "box_pile.yaml: sweep over count"} <= texts


def test_variants_and_backends_multiply_and_a_text_parameter_has_no_plot(tmp_path: Path) -> None:
    code = main([
        "sweep", str(FACTORY), "--param", "description=a,b", "--backends", "pybullet,fake", "--all-variants",
        "--out", str(tmp_path), "-q",
    ])  # fmt: skip  (the whole runs: a shorter world.duration is refused, the assertions' times are after its end)
    table = json.loads((tmp_path / "sweep.json").read_text())
    variants = {r["variant"] for r in table["rows"]}
    assert len(table["rows"]) == 2 * len(variants) * 2 and len(variants) == 4
    assert {r["backend"] for r in table["rows"]} == {"pybullet", "fake"}
    assert not (tmp_path / "sweep.svg").exists()
    assert code in (1, 3)


def test_bad_values_and_metrics_are_refused_before_anything_runs(tmp_path: Path) -> None:
    assert main(["sweep", str(PILE), "--param", "world.dt=-1", "--out", str(tmp_path)]) == 2
    assert main(["sweep", str(PILE), "--param", "size=1", "--out", str(tmp_path)]) == 2  # neither param nor key
    assert main(["sweep", str(PILE), "--param", "count=2", "--metric", "max(", "--out", str(tmp_path)]) == 2
    assert main(["sweep", str(PILE), "--param", "count=2", "--backends", "nope", "--out", str(tmp_path)]) == 2
    assert not (tmp_path / "sweep.json").exists()


def test_metrics_are_the_last_recorded_state(tmp_path: Path) -> None:
    loaded = load_scenario(PILE, None, (("world.duration", 0.3), ("params.count", 3)))
    result = run_loaded(loaded, "pybullet", tmp_path)
    texts = ["max(crate.pos.z)", "min(crate.pos.z)", "count('start')", "contact('crate_0', 'ground')", "time",
             "sum(crate.vel.z)"]  # fmt: skip
    values = final_values(loaded, Path(result.trace), texts, "pybullet")
    trace = read_trace(result.trace)
    z = [trace.bodies[f"crate_{i}"].pos[-1][2] for i in range(3)]
    assert values["max(crate.pos.z)"] == max(z) and values["min(crate.pos.z)"] == min(z)
    assert values["count('start')"] == 1
    assert values["time"] == pytest.approx(0.3)
    # three 0.3 m boxes dropped 2 cm apart have landed on each other after 0.3 s: the top at 0.75 +- 1 cm
    assert values["max(crate.pos.z)"] == pytest.approx(0.15 + 0.3 * 2, abs=0.01)
    assert values["contact('crate_0', 'ground')"] is True
    assert abs(values["sum(crate.vel.z)"]) < 0.1  # nearly at rest


def test_metrics_that_no_trace_holds_are_refused() -> None:
    model = load_scenario(PILE).model
    check_metrics(["max(crate.pos.z)", "contact('crate_0', 'ground')", "param.count * time"], model)
    for bad in ("crate.mass", "playing('x')", "max(", "box.pos.z"):
        with pytest.raises(UsageError, match="--metric"):
            check_metrics([bad], model)


def test_plot_draws_one_line_per_series_against_the_first_numeric_parameter() -> None:
    rows = [
        {"params": {"params.count": c, "surface.mu": m}, "variant": "base", "backend": "pybullet", "passed": p,
         "failed": 1 - p, "metrics": {"top": 0.3 * c}}
        for c, m, p in ((1, 0.5, 1), (2, 0.5, 1), (3, 0.5, 0), (1, 1.0, 1), (2, 1.0, 0), (3, 1.0, 0))
    ]  # fmt: skip
    svg = plot({"file": "x.yaml", "parameters": ["params.count", "surface.mu"], "metrics": ["top"], "rows": rows})
    root = ET.fromstring(svg)
    ns = "{http://www.w3.org/2000/svg}"
    groups = [g for g in root.iter(f"{ns}g") if g.get("class", "").startswith("mark-line role-mark")]
    lines = [p.get("d", "") for g in groups for p in g.iter(f"{ns}path")]
    assert len(lines) == 2  # mu=0.5 and mu=1.0
    first = [(float(a), float(b)) for a, b in re.findall(r"([-0-9.e]+),([-0-9.e]+)", lines[0])]
    assert [x for x, _ in first] == sorted(x for x, _ in first) and len(first) == 3
    assert first[0][1] > first[-1][1]  # higher values are drawn higher (smaller y)
    assert "mu=0.5" in svg and "mu=1.0" in svg
