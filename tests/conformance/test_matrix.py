"""The suite's machinery on the pure-Python backends: raw numbers, the matrix, crashes and time-outs, the command.

Small suites are written to a temporary folder. `fake` integrates exactly (semi-implicit Euler, no
contacts), so its free-fall numbers are known to the last bit; `crash` behaves like `fake` and then kills
or hangs its own process after a given number of steps (backends/crash.py).
"""

from __future__ import annotations

import json
import wave
from pathlib import Path

import pytest

from runner.cli.main import main
from runner.conformance import broken, build_matrix, discover, markdown, run_backend
from runner.conformance import matrix as matrix_module
from runner.conformance.cases import DEFAULT_SUITE
from runner.conformance.pool import BackendRun
from runner.conformance.worker import run_case
from runner.errors import ScenarioValidationError

HEADER = "# yaml-language-server: $schema=../../runner/schema/scenario.schema.json\n# z = z0 - g*dt^2*n*(n+1)/2\n"


def _fall(name: str, tol: str = "1e-9", duration: float = 0.1, extra: str = "") -> str:
    return HEADER + (
        f"schema_version: 1\nscenario: {name}\ndescription: falls\n"
        f"world: {{gravity: [0, 0, -10], dt: 0.01, duration: {duration}}}\n"
        "bodies:\n  ball: {sphere: 0.1, mass: 1, pos: [0, 0, 10]}\n"
        f"{extra}"
        "assertions:\n"
        "  - name: height\n    at: end\n    value: ball.pos.z\n"
        "    near: 10 - g*dt*dt*round(duration/dt)*(round(duration/dt) + 1)/2\n"
        f"    tol: {tol}\n"
    )


def _suite(folder: Path, files: dict[str, str]) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    for name, text in files.items():
        (folder / name).write_text(text)
    return folder


def test_worker_keeps_the_raw_numbers_behind_each_verdict(tmp_path: Path) -> None:
    sound = tmp_path / "beep.wav"
    with wave.open(str(sound), "wb") as w:
        w.setnchannels(1), w.setsampwidth(2), w.setframerate(1000), w.writeframes(b"\0\0" * 500)
    extra = (
        "sounds: {beep: beep.wav}\n"
        "intervals: {seq: {sequence: [{wait: 0.03}, {func: [{send: ping}]}, {sound: beep}]}}\n"
        "on: {start: [{start: seq}]}\n"
    )
    text = _fall("raw", tol="{default: 1e-9, fake: 0.5}", extra=extra) + (
        "  - {name: lowest, min: ball.pos.z, near: 9.9, tol: 0.1}\n"
        "  - {name: ping-time, event: ping, first: 0.03, tol: 1e-9}\n"
        "  - {name: ping-count, event: ping, count: 1}\n"
        "  - {name: beep-time, sound: beep, played_at: 0.03, tol: 1e-9}\n"
        "  - {name: bound, at: end, value: ball.pos.z, min: 0}\n"
        "  - {name: condition, at: end, check: ball.pos.z > 0}\n"
    )
    path = _suite(tmp_path, {"raw.yaml": text}) / "raw.yaml"
    result = run_case(path, None, "fake")
    assert result["status"] == "passed"
    checks = {c["name"]: c for c in result["checks"]}
    z10 = 10 - 10 * 0.01**2 * 10 * 11 / 2  # 9.945, exactly as fake integrates
    assert checks["height"]["measured"] == pytest.approx(z10, abs=1e-12)
    assert checks["height"]["target"] == pytest.approx(z10, abs=1e-12)
    assert checks["height"]["tol"] == 0.5  # the backend's own tolerance
    assert checks["lowest"]["measured"] == pytest.approx(z10, abs=1e-12) and checks["lowest"]["target"] == 9.9
    assert checks["ping-time"]["measured"] == pytest.approx(0.03) and checks["ping-time"]["target"] == 0.03
    assert (checks["ping-count"]["measured"], checks["ping-count"]["target"]) == (1.0, 1.0)
    assert checks["beep-time"]["measured"] == pytest.approx(0.03)
    assert checks["bound"]["measured"] == pytest.approx(z10) and checks["bound"]["target"] is None
    assert checks["condition"]["measured"] is None and checks["condition"]["passed"]


def _run(backend: str, results: dict[str, dict], version: str = "1") -> BackendRun:
    return BackendRun(backend, version, results, 1.0, 1)


def _result(measured: float, passed: bool = True) -> dict:
    check = {"name": "height", "passed": passed, "measured": measured, "target": 9.945, "tol": 1e-3}
    return {"status": "passed" if passed else "failed", "message": "", "checks": [check], "wall_seconds": 0.1}


def test_matrix_errors_against_the_formula_and_the_reference(tmp_path: Path) -> None:
    cases = discover(_suite(tmp_path / "s", {"a.yaml": _fall("a")}))
    runs = {
        "ode": _run("ode", {"a": _result(9.9451)}),
        "pybullet": _run("pybullet", {"a": _result(9.9449)}),
        "dart": _run("dart", {"a": _result(9.9, passed=False)}),
        "mujoco": _run("mujoco", {}),  # its worker never reported: not run
    }
    m = build_matrix(cases, runs, "suite")
    cells = m["cases"][0]["checks"][0]["cells"]
    assert cells["ode"]["error"] == pytest.approx(1e-4) and cells["ode"]["vs_reference"] is None
    assert cells["pybullet"]["error"] == pytest.approx(-1e-4)
    assert cells["pybullet"]["vs_reference"] == pytest.approx(-2e-4)
    assert cells["dart"]["status"] == "fail" and cells["dart"]["vs_reference"] == pytest.approx(-0.0451)
    assert cells["mujoco"] == {"status": "not run"}
    assert m["reference"] == "ode" and not m["passed"] and broken(m)
    assert [b["passed"] for b in m["backends"]] == [1, 1, 0, 0]
    text = markdown(m)
    assert "| `a` | falls | ✅ 1/1 | ✅ 1/1 | ❌ 0/1 | ❌ not run |" in text
    assert "✅ 0.0001 ≤ 0.001<br>Δode -2.00e-04" in text  # |measured - expected| against the tolerance
    assert "❌ 0.045 > 0.001" in text
    json.dumps(m, allow_nan=False)  # JSON-ready


def test_a_case_refused_up_front_is_counted_apart_and_leaves_the_matrix_passing(tmp_path: Path) -> None:
    # the worker's status for UnsupportedFeature (ODE's resting columns, issue 27): an answer, not a breakage,
    # where the suite expects that refusal; anywhere else it fails the matrix
    suite = tmp_path / "s"
    cases = discover(_suite(suite, {"a.yaml": _fall("a"), "b.yaml": _fall("b")}))
    (suite / matrix_module.EXPECTED_REFUSALS_FILE).write_text(json.dumps({"b.yaml": ["ode"]}))
    refusal = {"status": "unsupported", "message": "ode: a column of 5 | at most 4", "checks": [], "wall_seconds": 0}
    runs = {
        "ode": _run("ode", {"a": _result(9.9451), "b": refusal}),
        "mujoco": _run("mujoco", {"a": _result(9.9451), "b": _result(9.9451)}),
    }
    m = build_matrix(cases, runs, "suite")
    assert m["passed"] and not broken(m)
    assert [(b["passed"], b["refused"]) for b in m["backends"]] == [(1, 1), (2, 0)]
    text = markdown(m)
    assert "| `b` | falls | ⛔ refused | ✅ 1/1 |" in text
    assert "Refused up front by ode: ode: a column of 5 \\| at most 4" in text  # the message, escaped
    assert "3 pass, 0 known limits, 1 refused of 4 case runs" in text
    broken_b = {"a": _result(9.9451), "b": refusal | {"status": "failed"}}
    failed = build_matrix(cases, {**runs, "mujoco": _run("mujoco", broken_b)}, "suite")
    assert not failed["passed"]  # a failure stays a failure
    (suite / matrix_module.EXPECTED_REFUSALS_FILE).write_text(json.dumps({"b.yaml": ["mujoco"]}))
    assert not build_matrix(cases, runs, "suite")["passed"]  # a refusal the suite does not expect fails it


def test_the_expected_refusals_name_cases_of_the_suite() -> None:
    names = {p.name for p in DEFAULT_SUITE.glob("*.yaml")}
    expected = {"16_stacking_heights.yaml", "07_restitution.yaml", "07b_bounce_vel_below.yaml",
                "07c_bounce_vel_above.yaml", "17_restitution_grid.yaml", "19_joint_reaction.yaml"}  # fmt: skip
    assert set(matrix_module.expected_refusals(DEFAULT_SUITE)) == expected <= names


def test_matrix_without_the_reference_and_all_passing(tmp_path: Path) -> None:
    cases = discover(_suite(tmp_path / "s", {"a.yaml": _fall("a")}))
    m = build_matrix(cases, {"pybullet": _run("pybullet", {"a": _result(9.945)})}, "suite")
    assert m["reference"] is None and m["passed"] and not broken(m)
    assert m["cases"][0]["checks"][0]["cells"]["pybullet"]["vs_reference"] is None


LIMIT = "{measured: %s, cause: float32 rounding, doc: docs/backends/ode.md#deviations}"


def _off(name: str, tol: str, limit: str = "", off: str = "0.01") -> str:
    """The free fall, expected `off` metres too high: `fake` (exact) deviates by exactly that."""
    text = _fall(name, tol=tol).replace("near: 10 - g", f"near: 10 + {off} - g")
    return text + (f"    known_limits: {{fake: {limit}}}\n" if limit else "")


def _matrix(tmp_path: Path, files: dict[str, str]) -> dict:
    suite = _suite(tmp_path / "s", files)
    cases = discover(suite)
    return build_matrix(cases, {"fake": run_backend("fake", cases, timeout=60)}, "suite")


def _problems(m: dict) -> dict[str, str]:
    return {p["case"]: p["problem"] for p in m["audit"]}


def test_overrides_that_are_stale_or_too_wide_fail_the_matrix(tmp_path: Path) -> None:
    m = _matrix(
        tmp_path,
        {
            "stale.yaml": _off("stale", "{default: 1e-9, fake: 0.5}", off="0"),  # the default passes it
            "wide.yaml": _off("wide", "{default: 1e-3, fake: 0.031}"),  # > 3 x 0.01
            "fits.yaml": _off("fits", "{default: 1e-3, fake: 0.029}"),  # needed, < 3 x 0.01
        },
    )
    problems = _problems(m)
    assert problems["stale"].startswith("stale override: measured error 0 is within the default tolerance 1e-09")
    assert problems["wide"].startswith("override too wide: tolerance 0.031 is more than 3 x the measured error 0.01")
    assert "fits" not in problems
    assert all(c["runs"]["fake"]["status"] == "passed" for c in m["cases"])  # every verdict passed, yet:
    assert not m["passed"]
    assert "## Tolerance problems" in markdown(m)


def test_a_known_limit_runs_at_the_default_tolerance_and_shows_its_measured_deviation(tmp_path: Path) -> None:
    m = _matrix(tmp_path, {"lim.yaml": _off("lim", "1e-3", LIMIT % "0.01")})
    assert m["passed"] and not m["audit"] and not broken(m)
    case = m["cases"][0]
    cell = case["checks"][0]["cells"]["fake"]
    assert cell["status"] == "known limit" and cell["tol"] == 1e-3  # judged at the default
    assert cell["error"] == pytest.approx(-0.01, abs=1e-12)
    assert case["runs"]["fake"]["status"] == "known limit"
    assert (m["backends"][0]["passed"], m["backends"][0]["known_limits"]) == (0, 1)
    text = markdown(m)
    assert "⚠️ known limit: measured 0.01 (float32 rounding; [doc](backends/ode.md#deviations))" in text
    assert "| `lim` | falls | ⚠️ 0/1, 1 known limit |" in text
    assert "0 pass, 1 known limit of 1 case runs" in text


def test_a_known_limit_that_passes_or_measures_worse_than_documented_fails(tmp_path: Path) -> None:
    m = _matrix(
        tmp_path,
        {
            "gone.yaml": _off("gone", "1e-3", LIMIT % "0.01", off="0"),  # the engine meets the check now
            "worse.yaml": _off("worse", "1e-3", LIMIT % "0.009"),  # measures 0.01: > 0.009 x 1.05
            "fine.yaml": _off("fine", "1e-3", LIMIT % "0.0096"),  # 0.01 <= 0.0096 x 1.05
        },
    )
    problems = _problems(m)
    assert problems["gone"].startswith("known limit no longer needed: passes at the default tolerance")
    assert problems["worse"].startswith("known limit worse than documented: measured 0.01")
    assert "fine" not in problems
    assert {c["id"]: c["runs"]["fake"]["status"] for c in m["cases"]} == {
        "fine": "known limit", "gone": "failed", "worse": "known limit"
    }  # fmt: skip
    assert not m["passed"]


def test_command_fails_on_a_stale_override(tmp_path: Path) -> None:
    suite = _suite(tmp_path / "s", {"a.yaml": _fall("a", tol="{default: 1e-9, fake: 0.5}")})
    assert main(["conformance", "--backends", "fake", "--suite", str(suite), "--out", str(tmp_path / "o")]) == 1


def test_a_known_limit_cannot_also_widen_the_tolerance(tmp_path: Path) -> None:
    suite = _suite(tmp_path / "s", {"a.yaml": _off("a", "{default: 1e-3, fake: 0.02}", LIMIT % "0.01")})
    with pytest.raises(ScenarioValidationError, match="fake: a known limit is judged at the default tolerance"):
        discover(suite)


@pytest.mark.slow
def test_a_crash_or_a_hang_costs_one_case_only(tmp_path: Path) -> None:
    """A SIGSEGV and a hang (killed at the time-out) each mark their case; fresh workers run the rest.

    About 4 s: three worker processes and the 2 s time-out."""
    crash = "backend_options: {crash: {after_steps: 3, signal: SIGSEGV}}\n"
    hang = "backend_options: {crash: {after_steps: 3, fault: hang}}\n"
    suite = _suite(
        tmp_path / "s",
        {
            "a.yaml": _fall("a", extra=crash),
            "b.yaml": _fall("b"),  # 10 steps: before the crash backend's default fault at 30
            "c.yaml": _fall("c", extra=hang),
            "d.yaml": _fall("d"),
        },
    )
    run = run_backend("crash", discover(suite), timeout=2.0)
    status = {k: v["status"] for k, v in run.results.items()}
    assert status == {"a": "crashed (signal 11)", "b": "passed", "c": "timed out after 2 s", "d": "passed"}
    assert run.workers == 3


def test_command_exit_codes_and_outputs(tmp_path: Path) -> None:
    good = _suite(tmp_path / "good", {"a.yaml": _fall("a"), "b.yaml": _fall("b", duration=0.2)})
    out = tmp_path / "out"
    doc = tmp_path / "doc" / "conformance.md"
    assert (
        main(["conformance", "--backends", "fake", "--suite", str(good), "--out", str(out), "--markdown", str(doc)])
        == 0
    )
    matrix = json.loads((out / "conformance.json").read_text())
    assert matrix["passed"] and [c["id"] for c in matrix["cases"]] == ["a", "b"]
    assert doc.read_text() == (out / "conformance.md").read_text()
    bad = _suite(
        tmp_path / "bad", {"a.yaml": _fall("a"), "z.yaml": _fall("z", tol="1e-12").replace("10 - g", "11 - g")}
    )
    assert main(["conformance", "--backends", "fake", "--suite", str(bad), "--out", str(out)]) == 1
    assert main(["conformance", "--backends", "fake,nope", "--suite", str(good), "--out", str(out)]) == 2
    assert main(["conformance", "--backends", "fake", "--suite", str(tmp_path / "none"), "--out", str(out)]) == 2
    crashing = _suite(
        tmp_path / "crashing", {"a.yaml": _fall("a", extra="backend_options: {crash: {after_steps: 2}}\n")}
    )
    assert main(["conformance", "--backends", "crash", "--suite", str(crashing), "--out", str(out)]) == 3
