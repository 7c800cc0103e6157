"""Every trace of scenarios/ (conformance included) on every backend, opened in the real Foxglove Studio.

"The traces of scenarios/" are what ``scenario run scenarios scenarios/conformance --backend B`` writes:
one per scenario file (its first variant, or its base case), robots/ included, on each of the four
backends. A file's variants share its channels and schemas (they change parameters, inputs and
assertions, not the trace's format), so one trace per file and backend covers every schema Foxglove must
decode; opening all 256 variant traces took 14 minutes of CI for no schema more.

The Foxglove Studio web bundle (npm ``@foxglove/studio-base@1.48.0``, installed by ``make foxglove``) is
served on 127.0.0.1 and driven in headless Chromium over the DevTools protocol (tests/trace/
foxglove_studio.py): one server, one browser, one page; each trace is mounted in a fresh Studio with the
layout ``scenario layout`` writes for its scenario file, and the test waits (polling, no fixed sleep) until
Foxglove shows, for that trace:

* 0 entries in its Problems list (a channel whose schema it cannot parse is a problem),
* every channel of the trace in its topic list,
* in the Plot panel's legend, a body's z equal to a value the trace holds for it,
* in the 3D panel, coloured pixels: with the layout's frames' axes and links hidden and a grey grid, only
  the scene has colour (the bodies in their palette, the collision solids in amber; static bodies are grey
  and every scenario has a body that is not static).

Skipped when Chromium or the bundle is missing; SCENARIO_REQUIRE_FOXGLOVE=1 (set by .ci/run) turns that
skip into a failure, and then every one of the four backends must be installed.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest
from mcap.reader import make_reader

from backends.errors import UnsupportedFeature
from backends.registry import create_backend, is_installed
from reports import trace_format as tf
from reports.trace_reader import read_trace
from runner.cli.layouts import layout_spec
from runner.compile.program import build_program
from runner.language.load import load_files
from runner.trace.layout import write_layout
from tests.paths import ROOT
from tests.reports.cdp import find_chromium

from .foxglove_studio import Studio, View, bundle_folder, bundle_installed

BACKENDS = ("pybullet", "mujoco", "dart", "ode")
FOLDERS = (ROOT / "scenarios", ROOT / "scenarios" / "conformance")
REQUIRED = os.environ.get("SCENARIO_REQUIRE_FOXGLOVE") == "1"
CHROMIUM = find_chromium()
BUNDLE = bundle_folder()
MISSING = [what for what, ok in (("Chromium (apt-get install chromium)", CHROMIUM is not None),
                                 (f"the Foxglove Studio bundle in {BUNDLE} (make foxglove)", bundle_installed(BUNDLE)))
           if not ok]  # fmt: skip
MIN_PIXELS = 100  # coloured pixels in the 3D panel (about 10 x 10): the camera frames the bodies at their start
ATTEMPTS = 4  # Studio 1.48 can lose a panel's subscriptions while it starts (see Studio.open): remount it
TIMEOUT = 20.0  # seconds for one mount: a ready trace takes 2-8 s on a loaded two-core machine

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(bool(MISSING) and not REQUIRED, reason=f"not installed: {', '.join(MISSING)}"),
]


#: every scenario file `scenario run FOLDERS` collects (recursively, each once): robots/ included
FILES = sorted({p for folder in FOLDERS for p in folder.rglob("*.yaml")})


def _accepted(backend: str) -> int:
    """The cases of FILES that ``backend`` runs: all but those it refuses up front (no trace then), for a
    capability it does not declare or a limit its build checks (ODE's resting columns, conformance 16)."""
    count = 0
    for case in load_files(FILES, None, False):
        try:
            with create_backend(backend, build_program(case).world):
                count += 1
        except UnsupportedFeature:
            pass
    return count


@dataclass
class Case:
    trace: Path
    layout: Path
    topics: set[str]
    z_label: str
    z_values: set[float]


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
    for backend in backends:  # the command users run: it also writes foxglove-layout.json beside the traces
        done = subprocess.run(
            [sys.executable, "-m", "runner", "run", *map(str, FOLDERS), "--backend", backend,
             "--out", str(root / backend), "-j", "2", "--quiet"],
            cwd=ROOT, capture_output=True, text=True, timeout=900,
        )  # fmt: skip
        refusals = _accepted(backend) < len(load_files(FILES, None, False))  # a refused case exits 2 (bad input)
        assert done.returncode in ((0, 1, 2) if refusals else (0, 1)), done.stderr[-3000:]
        assert (root / backend / tf.LAYOUT_FILE).is_file()
    layouts = {}
    for file in FILES:  # `scenario layout FILE`, per file
        layouts[file.name] = write_layout(root / "layouts" / file.stem, layout_spec(load_files([file], None, True)))
    out = []
    for trace_path in sorted(root.glob("*/*.mcap")):
        trace = read_trace(trace_path)
        with open(trace_path, "rb") as f:
            topics = {c.topic for c in make_reader(f).get_summary().channels.values()}
        layout = layouts[trace.scenario[tf.KEY_SCENARIO_PATH]]
        label, body = _z_path(layout, set(trace.bodies))
        out.append(Case(trace_path, layout, topics, label, set(trace.bodies[body].pos[:, 2].tolist())))
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


def _ready(case: Case) -> object:
    def ready(view: View) -> bool:
        return (view.problems == 0 and case.topics <= view.topics and _z_shown(case, view)
                and view.scene_pixels >= MIN_PIXELS)  # fmt: skip

    return ready


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


def test_every_trace_opens_in_foxglove_studio(studio: Studio, cases: list[Case]) -> None:
    failures, retried, seconds = [], [], []
    for i, case in enumerate(cases):
        mounts = 0
        while True:
            mounts += 1
            view = studio.open(case.trace, case.layout, _ready(case), timeout=2 * TIMEOUT if i == 0 else TIMEOUT)
            seconds.append(view.seconds)
            if _ready(case)(view) or view.problems or mounts == ATTEMPTS:  # a problem is no race: no second try
                break
        name = f"{case.trace.parent.name}/{case.trace.name}"
        if mounts > 1:
            retried.append(f"{name} ({mounts} mounts)")
        if not _ready(case)(view):
            failures.append(f"{name}: {_what_is_wrong(case, view)}")
            (case.trace.parent / f"{case.trace.stem}.foxglove.png").write_bytes(view.screenshot)
    print(f"\n{len(cases)} traces in Foxglove Studio: {sum(seconds):.0f} s, {max(seconds):.1f} s at most;"
          f" remounted: {retried or 'none'}")  # fmt: skip
    assert not failures, f"{len(failures)} of {len(cases)} traces:\n" + "\n".join(failures)
