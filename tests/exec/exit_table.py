"""The exit-code table: each kind of failure on each execution path, by running the real command.

    .venv/bin/python -m tests.exec.exit_table [--ray] [--markdown FILE]

Rows (one scenario each): a runtime expression error, a `send` loop, an engine abort (a 1 ug box on
ODE: SIGABRT inside the engine), a full disk (a 32 KiB tmpfs as the output folder; without root, a
32 KiB RLIMIT_FSIZE, the same ENOSPC/EFBIG path), a missing engine (`ghost`: registered by
``tests/exec/ghost/sitecustomize.py`` in every process, found but not importable), a capability the
engine lacks (a universal joint on PyBullet), a failed assertion, known limits, a read-only output, an
integer overflow, an oversized mesh, and a worker over its memory ceiling (the test-only ``crash`` backend's
``fault: allocate`` under ``SCENARIO_MEMORY_LIMIT=300``). Columns: ``run``
serially, with ``-j 2``, ``--isolate``, ``--trace-process``, on Ray (``--executor ray`` on a cluster
started here with ``ray start --head``, stopped after), as the row of ``compare`` (whose own exit code
follows its rule, 0 when every run passes, else 1; the row gives the code ``run`` gives), ``check``
(against a golden file recorded first with ``scenario baseline`` where the run completes) and the
pytest plugin (``pytest -p runner.ci.pytest_plugin``: the item's first line ends with ``[exit N]``, the
code ``run`` gives; pytest itself exits 0 or 1). A cell is the exit code and the first line of the
case's message. Then `compare`'s agreement outcomes: its own exit code with ``--max-divergence``. The
tests in ``tests/exec/test_exit_codes.py`` run the same cells.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import re
import resource
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

from tests.exec.cluster import MARKER, marked

ROOT = Path(__file__).resolve().parents[2]
GHOST = Path(__file__).resolve().parent / "ghost"
BIN = Path(sys.executable).parent

BOX = """\
schema_version: 1
scenario: {name}
world: {{dt: 0.04, duration: 0.4}}
bodies:
  ground: {{plane: {{}}, motion: static}}
  box: {{box: [0.3, 0.3, 0.3], density: 500, pos: [0, 0, 1]}}
"""


# the box falls straight down: x stays 0 exactly. Near 0.1 the check fails at tol 0.01 and is a known limit
# (exit 0); near 0 it passes, and the known limit that is no longer needed fails the run (exit 1)
LIMITED = """\
assertions:
  - name: rests
    at: end
    value: box.pos.x
    near: {near}
    tol: 0.01
    known_limits:
      pybullet: {{measured: 0.1, cause: the test's own offset, doc: docs/language.md#known-limits}}
"""


UNIVERSAL = """\
joints:
  hook: {type: universal, bodies: [box, environment], axis: [1, 0, 0], axis2: [0, 1, 0]}
"""


MESH_ROBOT = """\
<robot name="r">
  <link name="base">
    <inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><geometry><mesh filename="big.stl"/></geometry></collision>
  </link>
</robot>
"""


def oversized_mesh(folder: Path) -> None:
    """A robot whose collision mesh is a binary STL one byte over the limit (sparse: nothing written)."""
    from runner.language.mesh_limits import MAX_MESH_BYTES

    (folder / "robot.urdf").write_text(MESH_ROBOT)
    with (folder / "big.stl").open("wb") as handle:
        handle.write(b"\0" * 80 + (1).to_bytes(4, "little"))
        handle.truncate(MAX_MESH_BYTES + 1)


@dataclass(frozen=True)
class Row:
    name: str
    backend: str
    text: str
    code: int  # the exit code every path must give (compare: its row; pytest: the [exit N] of its report)
    full_disk: bool = False
    variant: str | None = None  # the variant `run` picks (the first): `check` and pytest would run them all
    read_only: bool = False
    files: Callable[[Path], None] | None = None  # writes the files the scenario names beside it
    refused_on_load: bool = False  # refused before any case starts: `compare` itself exits 2 (bad input)
    memory: str | None = None  # SCENARIO_MEMORY_LIMIT for the command (runner.exec.memory)


ROWS = [
    Row("runtime expression error", "pybullet",
        BOX.format(name="expr") + "assertions:\n  - {name: a, at: end, check: \"box.pos.z + 'a' > 0\"}\n", 2),
    Row("send loop", "pybullet",
        BOX.format(name="loop") + "on:\n  start: [{send: ping}]\n  ping: [{send: pong}]\n  pong: [{send: ping}]\n", 2),
    Row("engine abort (1 ug box on ODE)", "ode",
        "schema_version: 1\nscenario: tiny\nworld: {dt: 0.01, duration: 0.5}\nbodies:\n"
        "  ground: {plane: {}, motion: static}\n"
        "  grain: {box: [0.003, 0.003, 0.003], mass: 1e-9, pos: [0, 0, 0.1]}\n", 3),
    Row("full disk (32 KiB --out)", "pybullet", (ROOT / "scenarios" / "factory_physics.yaml").read_text(), 74,
        full_disk=True, variant="door-stays-closed"),
    Row("missing engine", "ghost", BOX.format(name="ghosted"), 3),
    Row("capability refused (universal joint on PyBullet)", "pybullet", BOX.format(name="hooked") + UNIVERSAL, 2),
    Row("failed assertion", "pybullet",
        BOX.format(name="fails") + "assertions:\n  - {name: flies, at: end, check: box.pos.z > 10}\n", 1),
    Row("known limit (expected failure)", "pybullet", BOX.format(name="limited") + LIMITED.format(near=0.1), 0),
    Row("known limit that passes", "pybullet", BOX.format(name="unlimited") + LIMITED.format(near=0), 1),
    Row("read-only output", "pybullet", BOX.format(name="readonly"), 74, read_only=True),
    Row("integer overflow", "pybullet", BOX.format(name="overflow").replace("bodies:", "state: {s: 3}\nbodies:") +
        "inputs: [{at: 0, event: sq, repeat: {every: 0.04, count: 9}}]\non:\n  sq: [{calc: {s: state.s * state.s}}]\n"
        "assertions:\n  - {name: big, at: end, value: state.s * floor(1e308) * floor(1e308), max: 0}\n", 1),
    Row("oversized mesh (a 25 MB STL)", "pybullet",
        BOX.format(name="bigmesh") + "robots:\n  r: {urdf: robot.urdf, pos: [1, 0, 1]}\n", 2, files=oversized_mesh,
        refused_on_load=True),
    Row("over memory (2000 MiB taken under SCENARIO_MEMORY_LIMIT=300)", "crash", BOX.format(name="hungry") +
        "backend_options:\n  crash: {fault: allocate, after_steps: 3, megabytes: 2000}\n", 3, memory="300"),
]  # fmt: skip

LANDING = """\
schema_version: 1
scenario: landing
world: {dt: 0.01, duration: 1.0}
bodies:
  ground: {plane: {}, motion: static}
  box: {box: [0.4, 0.4, 0.4], density: 500, pos: [0, 0, 0.5]}
"""


@dataclass(frozen=True)
class Agreement:
    """A row of `compare`'s agreement outcomes: every run passes; its exit code follows --max-divergence."""

    name: str
    max_divergence: float
    code: int


#: PyBullet and MuJoCo land the box within 2.3 mm of each other (measured: the largest gap, at 0.45 s), far
#: inside 0.05 m and far outside 1e-6 m: which side of the threshold they fall on does not hang on rounding
AGREEMENT_BACKENDS = "pybullet,mujoco"
AGREEMENTS = [
    Agreement("engines agree within --max-divergence 0.05 m", 0.05, 0),
    Agreement("engines differ beyond --max-divergence 1e-6 m", 1e-6, 1),
]

PATHS = ["serial", "-j 2", "--isolate", "--trace-process", "ray", "compare", "check", "pytest"]
#: pytest's report of an item (its short summary's word), by the exit code `run` gives: pytest exits 0 or 1
PYTEST_KINDS = {0: "XFAIL", 1: "FAILED"}  # any other code: "ERROR"


@dataclass(frozen=True)
class Cell:
    code: int  # the command's exit code (compare: the row's code; pytest: the item's [exit N])
    line: str  # the first line of the case's message, the output folder written OUT
    command_code: int  # the command's own exit code
    output: str
    kind: str = ""  # pytest: how it reported the item (PASSED, FAILED, ERROR, XFAIL)


def _source(folder: Path, row: Row) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{re.sub(r'[^a-z]+', '_', row.name)}.yaml"
    path.write_text(row.text)
    if row.files is not None:
        row.files(folder)
    return path


@contextlib.contextmanager
def output_folder(base: Path, full: bool, read_only: bool = False) -> Iterator[tuple[Path, dict[str, int]]]:
    """A folder for --out; for the full-disk row a 32 KiB tmpfs (root), else a 32 KiB file-size limit; for
    the read-only row a read-only tmpfs (root), else mode 555."""
    out = base / "out"
    out.mkdir(parents=True)
    limits: dict[str, int] = {}
    mounted = False
    if (full or read_only) and os.geteuid() == 0 and shutil.which("mount"):
        options = "ro,size=32k" if read_only else "size=32k"
        mounted = subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(out)]).returncode == 0
    if read_only and not mounted:
        out.chmod(0o555)
    if full and not mounted:
        limits["fsize"] = 32 * 1024
    try:
        yield out, limits
    finally:
        if mounted:
            subprocess.run(["umount", str(out)], check=False)
        elif read_only:
            out.chmod(0o755)


def environment() -> dict[str, str]:
    """The command's environment: the ghost backend registered, Rich wide enough to keep lines whole, and
    Ray's token authentication off for the private cluster of :func:`ray_cluster` (listening on 127.0.0.1
    only; the shared ~/.ray/auth_token may be rewritten by other clusters on the machine)."""
    env = {**os.environ, "SCENARIO_GHOST_BACKEND": "1", "COLUMNS": "400", "SCENARIO_DEBUG": "0",
           "RAY_AUTH_MODE": "disabled"}  # fmt: skip
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(GHOST), str(ROOT), os.environ.get("PYTHONPATH")]))
    env.pop("PYTEST_CURRENT_TEST", None)
    return env


def _limits(limits: dict[str, int]) -> None:
    if "fsize" in limits:  # in the child, before exec: SIGXFSZ ignored so that writes fail with EFBIG
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limits["fsize"], limits["fsize"]))


def command(path: str, source: Path, backend: str, out: Path, ray: str = "auto",
            variant: str | None = None) -> list[str]:  # fmt: skip
    """The command of one cell (``check``: against the baselines in ``source``'s folder's ``../baselines``)."""
    cli = [sys.executable, "-m", "runner"]
    if path == "compare":
        return [*cli, "compare", str(source), "--backends", backend, "--out", str(out), "-j", "2"]
    if path in ("check", "baseline"):
        chosen = ["--variant", variant] if variant else []
        return [*cli, path, str(source), "--backend", backend, "--baseline", str(source.parent.parent / "baselines"),
                *(["--out", str(out)] if path == "check" else []), *chosen]  # fmt: skip
    if path == "pytest":  # the plugin, as `pytest scenarios/` runs it in CI (docs/ci.md)
        chosen = ["-k", variant] if variant else []
        return [sys.executable, "-m", "pytest", "-p", "runner.ci.pytest_plugin", "-p", "no:cacheprovider", "-rA",
                "-vv", "--scenario-backends", backend, "--scenario-out", str(out), *chosen, str(source)]  # fmt: skip
    extra = {"serial": [], "-j 2": ["-j", "2"], "--isolate": ["--isolate"], "--trace-process": ["--trace-process"],
             "ray": ["--executor", "ray", "--ray-address", ray]}[path]  # fmt: skip
    return [*cli, "run", str(source), "--backend", backend, "--out", str(out), *extra]


_ROW_LINE = re.compile(r"^ {6}(.*) \[exit (\d+)\]$")  # compare: "      <first line> [exit N]"
_CASE_LINE = re.compile(r"^  \S+ · \S+ · \S+: (.*)$")  # run's and check's summary: "  <scenario> · <variant> · ..."
_PYTEST_LINE = re.compile(r"^(PASSED|FAILED|ERROR|XFAIL|XPASS) \S+(?: - (.*))?$")  # pytest's short summary
_EXIT = re.compile(r"^(.*) \[exit (\d+)\]$")  # the plugin's first line: "<run's first line> [exit N]"


def _pytest_cell(stdout: str) -> tuple[int, str, str]:
    """The item's exit code (its ``[exit N]``; 0 for a pass or an xfail), first line and pytest's word for it."""
    for raw in stdout.splitlines():
        match = _PYTEST_LINE.match(raw)
        if match:
            kind, line = match.group(1), match.group(2) or ""
            found = _EXIT.match(line)
            if found:
                return int(found.group(2)), found.group(1), kind
            return (0 if kind in ("PASSED", "XFAIL") else -1), line, kind
    return -1, "", ""


def run_cell(row: Row, path: str, base: Path, ray: str = "auto") -> Cell:
    """Run ``row`` on ``path`` in a fresh folder under ``base`` (``ray``: the cluster's address)."""
    work = base / f"{re.sub(r'[^a-z0-9]+', '_', row.name)}-{re.sub(r'[^a-z0-9]+', '_', path)}"
    source = _source(work / "src", row)
    (work / "pytest.ini").write_text("[pytest]\n")  # pytest's rootdir: nothing of this repository's config
    env = {k: v for k, v in environment().items() if not k.startswith("PYTEST_")}
    if row.memory is not None:
        env["SCENARIO_MEMORY_LIMIT"] = row.memory
    if path == "check":  # its golden file first, where the run completes (a failed assertion is recorded too)
        subprocess.run(command("baseline", source, row.backend, work, variant=row.variant), capture_output=True,
                       timeout=600, env=env, cwd=work)  # fmt: skip
    with output_folder(work, row.full_disk, row.read_only) as (out, limits):
        done = subprocess.run(command(path, source, row.backend, out, ray, row.variant), capture_output=True, text=True,
                              timeout=600, env=env, cwd=work, preexec_fn=lambda: _limits(limits))  # fmt: skip
    text = done.stdout + done.stderr
    code, line, kind = done.returncode, "", ""
    if path == "pytest":
        code, line, kind = _pytest_cell(done.stdout)
    for raw in done.stdout.splitlines() if path != "pytest" else ():
        match = (_ROW_LINE if path == "compare" else _CASE_LINE).match(raw)
        if match:
            line = match.group(1)
            if path == "compare":
                code = int(match.group(2))
            break
    if not line:  # refused before any case ran: the command's first error line
        line = next((x for x in done.stderr.splitlines() if x.strip()), "")
    line = line.replace(str(out / "traces"), "OUT").replace(str(out), "OUT").replace(str(work), "WORK")
    return Cell(code, line.strip(), done.returncode, text, kind)


def agreement_cell(row: Agreement, base: Path) -> Cell:
    """`compare` of the landing box on PyBullet and MuJoCo with ``--max-divergence``; the line is its headline
    (not in the table: its words are the report's, its exit code is the rule tested here)."""
    work = base / f"agreement-{re.sub(r'[^a-z0-9]+', '_', row.name)}"
    source = work / "landing.yaml"
    work.mkdir(parents=True)
    source.write_text(LANDING)
    cmd = [sys.executable, "-m", "runner", "compare", str(source), "--backends", AGREEMENT_BACKENDS, "--out",
           str(work / "out"), "-j", "2", "--max-divergence", f"{row.max_divergence:g}"]  # fmt: skip
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=600, env=environment(), cwd=work)
    line = next((x for x in done.stdout.splitlines() if " runs pass" in x), "")
    return Cell(done.returncode, line.strip(), done.returncode, done.stdout + done.stderr)


@contextlib.contextmanager
def ray_cluster() -> Iterator[str]:
    """A local Ray cluster for the ``ray`` column (``ray start --head`` on a free port, with the ghost
    backend's environment); yields its address, named explicitly so that no other cluster on the machine
    is picked up by ``auto``."""
    ray = str(BIN / "ray")
    tmp = tempfile.mkdtemp(prefix="ray-")
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    marker = f"exit-table-{os.getpid()}-{port}"
    env = {**environment(), MARKER: marker}  # every process of this cluster carries it (see stop below)
    try:
        started = subprocess.run([ray, "start", "--head", "--num-cpus", "2", "--disable-usage-stats", "--temp-dir",
                                  tmp, "--include-dashboard", "false", "--node-ip-address", "127.0.0.1", "--port",
                                  str(port)], env=env, capture_output=True, text=True, timeout=300)  # fmt: skip
        if started.returncode != 0:
            raise RuntimeError(f"ray start failed: {started.stderr[-2000:]}")
        yield f"127.0.0.1:{port}"
    finally:
        # this cluster's processes only: `ray stop` would stop every Ray cluster of the user on the machine
        for pid in marked(marker):
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)
        shutil.rmtree(tmp, ignore_errors=True)


def table(paths: list[str], threads: int = 2, ray: str = "auto") -> list[tuple[Row, dict[str, Cell]]]:
    """Every cell, ``threads`` commands at a time."""
    from concurrent.futures import ThreadPoolExecutor

    with tempfile.TemporaryDirectory(prefix="exit-table-") as tmp, ThreadPoolExecutor(threads) as pool:
        futures = {(r.name, p): pool.submit(run_cell, r, p, Path(tmp), ray) for r in ROWS for p in paths}
        return [(r, {p: futures[r.name, p].result() for p in paths}) for r in ROWS]


def agreements(threads: int = 2) -> list[tuple[Agreement, Cell]]:
    from concurrent.futures import ThreadPoolExecutor

    with tempfile.TemporaryDirectory(prefix="exit-table-") as tmp, ThreadPoolExecutor(threads) as pool:
        futures = [pool.submit(agreement_cell, row, Path(tmp)) for row in AGREEMENTS]
        return [(row, f.result()) for row, f in zip(AGREEMENTS, futures, strict=True)]


def markdown(rows: list[tuple[Row, dict[str, Cell]]], paths: list[str],
             agreed: list[tuple[Agreement, Cell]] | None = None) -> str:  # fmt: skip
    lines = ["| failure | " + " | ".join(f"`{p}`" for p in paths) + " |", "|---" * (len(paths) + 1) + "|"]
    for row, cells in rows:
        lines.append(f"| {row.name} | " + " | ".join(str(cells[p].code) for p in paths) + " |")
    lines += ["", "First line of the message (the same on every path; `OUT`: the trace folder, `--out` or, for "
              "`compare`, `--out`/traces):", ""]
    for row, cells in rows:
        seen = sorted({c.line for c in cells.values()})
        lines.append(f"- {row.name}: " + " / ".join(f"`` {x} ``" if "`" in x else f"`{x}`" for x in seen))
    compare = [f"{row.name} {cells['compare'].command_code}" for row, cells in rows if "compare" in cells]
    if compare:
        lines += ["", "`compare`'s own exit code: " + ", ".join(compare) + "."]
    plugin = [f"{row.name} {cells['pytest'].kind}" for row, cells in rows if "pytest" in cells]
    if plugin:
        own = sorted({f"{cells['pytest'].command_code}" for _, cells in rows if "pytest" in cells})
        lines += ["", "pytest's report of the item: " + ", ".join(plugin) + "; pytest's own exit code: "
                  f"{', '.join(own)} (0 for the expected failure, else 1)."]  # fmt: skip
    if agreed:
        lines += ["", f"`compare`'s agreement outcomes (a box landing on {AGREEMENT_BACKENDS}, every assertion "
                  "passes):", "", "| outcome | `compare` |", "|---|---|"]  # fmt: skip
        lines += [f"| {row.name} | {cell.code} |" for row, cell in agreed]
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ray", action="store_true", help="include the Ray column (starts a local cluster)")
    parser.add_argument("--markdown", type=Path, help="also write the table here")
    args = parser.parse_args(argv)
    paths = [p for p in PATHS if args.ray or p != "ray"]
    if args.ray:
        with ray_cluster() as address:
            rows = table(paths, ray=address)
    else:
        rows = table(paths)
    agreed = agreements()
    text = markdown(rows, paths, agreed)
    sys.stdout.write(text)
    if args.markdown:
        args.markdown.write_text(text)
    bad = [(r.name, p, c.code) for r, cells in rows for p, c in cells.items() if c.code != r.code]
    bad += [(r.name, "compare", c.code) for r, c in agreed if c.code != r.code]
    lines = [(r.name, sorted({c.line for c in cells.values()})) for r, cells in rows]
    for name, p, code in bad:
        sys.stderr.write(f"{name} on {p}: exit {code}\n")
    for name, seen in lines:
        if len(seen) != 1:
            sys.stderr.write(f"{name}: {len(seen)} different first lines\n")
    return 1 if bad or any(len(s) != 1 for _, s in lines) else 0


if __name__ == "__main__":
    sys.exit(main())
