"""Every trace of scenarios/ (conformance included) on every backend, opened in the real Foxglove Studio.

"The traces of scenarios/" are what ``scenario run scenarios scenarios/conformance --backend B`` writes:
one per scenario file (its first variant, or its base case), robots/ included, on each of the four
backends. A file's variants share its channels and schemas (they change parameters, inputs and
assertions, not the trace's format), so one trace per file and backend covers every schema Foxglove must
decode; opening all 256 variant traces took 14 minutes of CI for no schema more.

The Foxglove Studio web bundle (npm ``@foxglove/studio-base@1.48.0``, installed by ``make foxglove``) is
served on 127.0.0.1 and driven in headless Chromium over the DevTools protocol (tests/trace/
foxglove_studio.py): one server, one browser, one page; each trace is mounted in a fresh Studio with the
layout ``scenario run`` wrote beside it for its scenario (``<scenario>.foxglove-layout.json``), and the
test waits (polling, no fixed sleep) until Foxglove shows, for that trace:

* 0 entries in its Problems list (a channel whose schema it cannot parse is a problem),
* every channel of the trace in its topic list,
* in the Plot panel's legend, a body's z equal to a value the trace holds for it,
* in the 3D panel, coloured pixels: with the layout's frames' axes and links hidden and a grey grid, only
  the scene has colour (the bodies in their palette, the collision solids in amber; static bodies are grey
  and every scenario has a body that is not static).

Besides, every scenario file of ``scenarios/`` and
``scenarios/robots/`` is run by a command of its own into one folder, on one engine (MuJoCo when installed),
so that each command adds its scenario's layout to those already there: all of them must still be there,
and each of those traces, opened with its layout, must show in Foxglove's Plot legends

* every quantity its assertions read (the trace's ``asserted`` metadata) as a row of the layout Foxglove
  loaded, each row's path naming a series of the trace;
* the value of that series (read from the trace with our reader) at the playback time, at the start and
  after seeking (typing a time into the playback time field, which takes simulated seconds with the
  "SEC" time format) to times where every series that varies in the trace has changed: so a series that
  is not constant in the trace is not constant in Foxglove, and Foxglove's clock reads simulated seconds;
* no panel problem: no panel's error boundary, no plot path flagged with an error.

Skipped when Chromium or the bundle is missing; SCENARIO_REQUIRE_FOXGLOVE=1 (set by .ci/run) turns that
skip into a failure, and then every one of the four backends must be installed.
"""

from __future__ import annotations

import json
import math
import os
import re
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest
from mcap.reader import make_reader

from backends.errors import UnsupportedFeature
from backends.registry import create_backend, is_installed
from reports import trace_format as tf
from reports.trace_reader import read_trace
from runner.compile.program import build_program
from runner.language.load import load_files
from tests.engines import ENGINES
from tests.paths import ROOT
from tests.reports.cdp import find_chromium

from .foxglove_plots import Series, plot_rows, seek_times, series, shows
from .foxglove_studio import Studio, View, bundle_folder, bundle_installed

BACKENDS = ENGINES
FOLDERS = (ROOT / "scenarios", ROOT / "scenarios" / "conformance")
REQUIRED = os.environ.get("SCENARIO_REQUIRE_FOXGLOVE") == "1"
CHROMIUM = find_chromium()
BUNDLE = bundle_folder()
MISSING = [what for what, ok in (("Chromium (apt-get install chromium)", CHROMIUM is not None),
                                 (f"the Foxglove Studio bundle in {BUNDLE} (make foxglove)", bundle_installed(BUNDLE)))
           if not ok]  # fmt: skip
MIN_PIXELS = 100  # coloured pixels in the 3D panel (about 10 x 10): the camera frames the bodies at their start
#: Studio 1.48 can lose its 3D panel's subscription while it starts (see Studio.open): everything else shows,
#: the bodies never do. Seen on 36 of 212 first mounts in one CI run (17 %), and 3 of 12 mounts of one trace
#: alone: 4 mounts left a 0.17^4 x 212 = 0.2 chance of a red run with every trace right; with 8, 1e-4.
ATTEMPTS = 8
#: seconds with every other sign of a loaded trace and no body drawn before the mount is taken as that race
#: (a good mount draws the bodies within a second or two of its plots on a loaded two-core machine); waiting
#: out TIMEOUT instead cost 36 x 20 s of one CI run's Foxglove lane
STALL = 8.0
TIMEOUT = 20.0  # seconds for one mount: a ready trace takes 2-8 s on a loaded two-core machine

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(bool(MISSING) and not REQUIRED, reason=f"not installed: {', '.join(MISSING)}"),
]


#: every scenario file `scenario run FOLDERS` collects (recursively, each once): robots/ included
FILES = sorted({p for folder in FOLDERS for p in folder.rglob("*.yaml")})
#: the files whose asserted quantities are checked in Foxglove's plots: one command each, one folder
PLOTTED_FILES = sorted([*(ROOT / "scenarios").glob("*.yaml"), *(ROOT / "scenarios" / "robots").glob("*.yaml")])
#: the first installed that runs the file plots it: MuJoCo, then PyBullet, then the registry's others
PLOT_ENGINES = sorted(ENGINES, key=lambda b: {"mujoco": 0, "pybullet": 1}.get(b, 2))
SEEK_TIMEOUT = 15.0  # seconds for Foxglove to show a seek's time and values


def _accepted(backend: str, files: list[Path] = FILES) -> int:
    """The cases of ``files`` that ``backend`` runs: all but those it refuses up front (no trace then), for
    a capability it does not declare or a limit its build checks (ODE's resting columns, conformance 16)."""
    count = 0
    for case in load_files(files, None, False):
        try:
            with create_backend(backend, build_program(case).world):
                count += 1
        except UnsupportedFeature:
            pass
    return count


def _run(files: list[Path], backend: str, out: Path) -> subprocess.CompletedProcess[str]:
    """The command users run: it also writes the layouts beside the traces."""
    return subprocess.run(
        [sys.executable, "-m", "runner", "run", *map(str, files), "--backend", backend, "--out", str(out),
         "-j", "2", "--quiet"],
        cwd=ROOT, capture_output=True, text=True, timeout=900,
    )  # fmt: skip


def _plotted_traces(root: Path, backends: list[str]) -> dict[Path, str]:
    """Each file of PLOTTED_FILES run by its own command into ``root``, on the first engine of
    PLOT_ENGINES that runs all its cases: {file: engine}. Every command's layout must still be in ``root`` after
    the others."""
    engines = {}
    for file in PLOTTED_FILES:
        cases = len(load_files([file], None, False))
        engine = next(b for b in PLOT_ENGINES if b in backends and _accepted(b, [file]) == cases)
        done = _run([file], engine, root)
        assert done.returncode in (0, 1), f"{file.name} on {engine}: {done.stderr[-3000:]}"
        engines[file] = engine
    names = {case.model.scenario for case in load_files(PLOTTED_FILES, None, False)}
    kept = {p.name for p in root.glob("*.foxglove-layout.json")}
    lost = sorted(tf.scenario_layout_file(n) for n in names if tf.scenario_layout_file(n) not in kept)
    assert not lost, f"one command per scenario into {root}: layouts lost: {lost}"
    return engines


@dataclass
class Case:
    trace: Path
    layout: Path
    topics: set[str]
    z_label: str
    z_values: set[float]
    plotted: bool = False  # also check the asserted quantities in the plots (PLOTTED_FILES)


def _z_path(layout: Path, bodies: set[str]) -> tuple[str, str]:
    """(legend label, body) of the first plotted body height in ``layout`` for one of ``bodies``."""
    for path in json.loads(layout.read_text())["configById"]["Plot!asserted"]["paths"]:
        found = re.fullmatch(r'/tf\.transforms\[:\]\{child_frame_id=="([\w.]+)"\}\.translation\.z', path["value"])
        if found and found.group(1) in bodies:
            return path.get("label", path["value"]), found.group(1)
    raise AssertionError(f"{layout} plots no body height for {sorted(bodies)}")


@pytest.fixture(scope="module")
def cases(tmp_path_factory: pytest.TempPathFactory) -> list[Case]:
    if MISSING:
        pytest.fail(f"SCENARIO_REQUIRE_FOXGLOVE=1 but not installed: {', '.join(MISSING)}")
    backends = [b for b in BACKENDS if is_installed(b)]
    if REQUIRED and len(backends) != len(BACKENDS):
        pytest.fail(f"SCENARIO_REQUIRE_FOXGLOVE=1 needs every backend; installed: {backends}")
    root = tmp_path_factory.mktemp("foxglove")
    for backend in backends:
        done = _run(list(FOLDERS), backend, root / backend)
        refusals = _accepted(backend) < len(load_files(FILES, None, False))  # a refused case exits 2 (bad input)
        assert done.returncode in ((0, 1, 2) if refusals else (0, 1)), done.stderr[-3000:]
        assert (root / backend / tf.LAYOUT_FILE).is_file()
    engines = {file.name: engine for file, engine in _plotted_traces(root / "plotted", backends).items()}
    out = []
    for trace_path in sorted(root.glob("*/*.mcap")):
        trace = read_trace(trace_path)
        file = trace.scenario[tf.KEY_SCENARIO_PATH]
        plotted = trace_path.parent.name == "plotted"
        if not plotted and engines.get(file) == trace_path.parent.name:
            continue  # the same trace (same scenario and engine) is opened from plotted/
        with open(trace_path, "rb") as f:
            summary = make_reader(f).get_summary()
            assert summary is not None, f"{trace_path} has no summary"
            topics = {c.topic for c in summary.channels.values()}
        layout = trace_path.parent / tf.scenario_layout_file(trace.scenario[tf.KEY_NAME])
        label, body = _z_path(layout, set(trace.bodies))
        out.append(Case(trace_path, layout, topics, label, set(trace.bodies[body].pos[:, 2].tolist()), plotted))
    expected = sum(_accepted(b) for b in backends)
    assert len(out) == expected, f"expected {expected} traces of scenarios/ over {backends}, found {len(out)}"
    return out


@pytest.fixture(scope="module")
def studio(tmp_path_factory: pytest.TempPathFactory, cases: list[Case]) -> Iterator[Studio]:
    assert CHROMIUM is not None
    root = cases[0].trace.parent.parent
    s = Studio(BUNDLE, root, tmp_path_factory.mktemp("chromium-profile"), CHROMIUM)
    try:
        yield s
    finally:
        s.close()


def _z_shown(case: Case, view: View) -> bool:
    try:
        return float(view.legend.get(case.z_label, "")) in case.z_values
    except ValueError:
        return False


def _ready(case: Case) -> Callable[[View], bool]:
    def ready(view: View) -> bool:
        return (view.problems == 0 and case.topics <= view.topics and _z_shown(case, view)
                and view.scene_pixels >= MIN_PIXELS)  # fmt: skip

    return ready


def _stalled(case: Case) -> Callable[[View], bool]:
    """The race of Studio.open: the trace loaded (no problem, its topics listed, its plot's value shown) and
    no body drawn."""

    def stalled(view: View) -> bool:
        return (view.problems == 0 and case.topics <= view.topics and _z_shown(case, view)
                and view.scene_pixels < MIN_PIXELS)  # fmt: skip

    return stalled


def _what_is_wrong(case: Case, view: View) -> str:
    wrong = []
    if view.problems != 0:
        wrong.append(f"{view.problems} problems: {view.problem_lines}")
    if not case.topics <= view.topics:
        wrong.append(f"topics missing from the list: {sorted(case.topics - view.topics)}")
    if not _z_shown(case, view):
        wrong.append(f"plot legend {case.z_label!r} = {view.legend.get(case.z_label)!r}, not a value of the trace")
    if view.scene_pixels < MIN_PIXELS:
        wrong.append(f"bodies not drawn: {view.scene_pixels} coloured pixels in the 3D panel")
    return "; ".join(wrong)


def _shown(text: str) -> float | None:
    """A legend value as a number (None for an empty one: no point yet); ValueError for anything else."""
    if text == "":
        return None
    return {"true": 1.0, "false": 0.0}[text] if text in ("true", "false") else float(text)


def _legend_shows(rows: dict[str, Series], view: View, t: float) -> list[str]:
    """The legend rows whose value is not their series' value at ``t``."""
    wrong = []
    for label, s in rows.items():
        expected = s.at(t)
        try:
            got = _shown(view.legend.get(label, "?"))
        except ValueError:
            got = math.nan
        both_nan = got is not None and expected is not None and math.isnan(got) and math.isnan(expected)
        if got != expected and not both_nan:
            wrong.append(f"{label} = {view.legend.get(label)!r}, the trace's {s.quantity} at {t:g} s is {expected!r}")
    return wrong


def _check_plots(studio: Studio, case: Case, view: View) -> list[str]:
    """The asserted quantities in the plots of the layout Foxglove loaded, each row's value that of the trace
    at the start and at the seek times, each varying series varying in Foxglove, no panel problem."""
    trace = read_trace(case.trace)
    rows = dict(plot_rows(case.layout))
    plotted = {label: s for label, path in rows.items() if (s := series(trace, path)) is not None}
    wrong = [f"{label}: {path} names nothing in the trace" for label, path in rows.items() if label not in plotted]
    wrong += [f"{label}: not in Foxglove's legend" for label in rows if label not in view.legend]
    asserted = json.loads(trace.scenario.get(tf.KEY_ASSERTED, "[]"))
    wrong += [f"asserted {q} is not plotted" for q in asserted if not shows(q, list(plotted.values()))]
    if view.clock is None or wrong or len(trace.times) < 3:
        return wrong + ([] if view.clock is not None else ["no playback time shown"])
    start = float((trace.times[0] + trace.times[1]) / 2)  # the first step's values (Foxglove opens at 0.099 s)
    readings = []
    for t in [start, *seek_times(list(plotted.values()), start, trace.times)]:
        studio.seek(t)
        deadline = time.monotonic() + SEEK_TIMEOUT
        while True:
            studio.read(view)
            wrong_at = _legend_shows(plotted, view, t)
            if (view.clock == f"{t:.9f}" and not wrong_at) or time.monotonic() > deadline:
                break
            time.sleep(0.2)
        if view.clock != f"{t:.9f}":
            wrong.append(f"at {t:.9f} s: the clock reads {view.clock!r}")
        wrong += [f"at {t:g} s: {w}" for w in wrong_at]
        readings.append((t, dict(view.legend)))
    for label, s in plotted.items():
        if not s.constant and len({legend.get(label) for _, legend in readings}) < 2:
            wrong.append(f"{label} varies in the trace but Foxglove showed {readings[0][1].get(label)!r} at "
                         f"{[round(t, 4) for t, _ in readings]} s")  # fmt: skip
    return wrong + view.panel_problems


def test_every_trace_opens_in_foxglove_studio(studio: Studio, cases: list[Case]) -> None:
    failures, retried, seconds = [], [], []
    for i, case in enumerate(cases):
        mounts = 0
        while True:
            mounts += 1
            view = studio.open(case.trace, case.layout, _ready(case), timeout=2 * TIMEOUT if i == 0 else TIMEOUT,
                               stalled=_stalled(case), stall_seconds=STALL)  # fmt: skip
            seconds.append(view.seconds)
            if _ready(case)(view) or view.problems or mounts == ATTEMPTS:  # a problem is no race: no second try
                break
        name = f"{case.trace.parent.name}/{case.trace.name}"
        if mounts > 1:
            retried.append(f"{name} ({mounts} mounts)")
        if not _ready(case)(view):
            failures.append(f"{name}: {_what_is_wrong(case, view)}")
            (case.trace.parent / f"{case.trace.stem}.foxglove.png").write_bytes(view.screenshot)
        elif case.plotted:
            wrong = _check_plots(studio, case, view)
            if wrong:
                failures.append(f"{name} with {case.layout.name}: " + "; ".join(wrong))
                (case.trace.parent / f"{case.trace.stem}.foxglove.png").write_bytes(studio.screenshot())
    print(f"\n{len(cases)} traces in Foxglove Studio: {sum(seconds):.0f} s, {max(seconds):.1f} s at most;"
          f" remounted: {retried or 'none'}")  # fmt: skip
    assert not failures, f"{len(failures)} of {len(cases)} traces:\n" + "\n".join(failures)
