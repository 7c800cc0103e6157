"""Issue 15's loader reproductions, through the command as a user runs it: each ends in exit 2 with a located
message (file:line:column, or the command-line argument), no traceback, and nothing written.

1 an interval cycle through two (and three) intervals; 2 a NUL byte anywhere; 3 `--set` values YAML cannot
build; 4 parameter substitution that would multiply memory (refused before it is built: time and peak memory
measured); 5 over-long names (on every path that writes traces); 7 FIFOs, devices and sockets (refused
without being opened); 13 an error that had no line and column.
"""

from __future__ import annotations

import os
import re
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.paths import ROOT
from tests.reliability.memory import MEASURED

SMALL = """\
schema_version: 1
scenario: t
world: {dt: 0.04, duration: 1}
bodies:
  box: {box: [0.3, 0.3, 0.3], density: 500, pos: [0, 0, 1]}
"""
LOCATED = re.compile(r"^error: (?P<file>.+?):(?P<line>[1-9]\d*):(?P<col>[1-9]\d*): \S")
COMMAND_LINE = re.compile(r"^error: <command line>: --(set|param) \S")


#: `scenario ARGS`, then the process's own peak RSS on stderr



def scenario(*args: object, cwd: Path, timeout: float = 60) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "runner", *map(str, args)], capture_output=True, text=True,
                          cwd=cwd, timeout=timeout)  # fmt: skip


def refused(done: subprocess.CompletedProcess[str], pattern: str, where: re.Pattern[str] = LOCATED) -> None:
    assert done.returncode == 2, (done.returncode, done.stdout, done.stderr)
    assert "Traceback" not in done.stderr, done.stderr
    errors = [line for line in done.stderr.splitlines() if line.startswith("error:")]
    assert errors and all(where.match(line) for line in errors), done.stderr
    assert any(re.search(pattern, line) for line in errors), (pattern, done.stderr)


def nothing_written(folder: Path) -> None:
    assert not folder.exists() or not any(folder.iterdir()), list(folder.iterdir())


@pytest.mark.parametrize("intervals,cycle", [
    ("  ia: {parallel: [{interval: ib}]}\n  ib: {sequence: [{interval: ia}]}\n", "`ia` -> `ib` -> `ia`"),
    ("  a: {sequence: [{interval: b}]}\n  b: {sequence: [{wait: 1}, {interval: c}]}\n"
     "  c: {parallel: [{sequence: [{interval: a}]}]}\n", "`a` -> `b` -> `c` -> `a`"),
])  # fmt: skip
@pytest.mark.parametrize("command", ["validate", "run"])
def test_1_interval_cycles_through_any_number_of_intervals(tmp_path: Path, command: str, intervals: str,
                                                           cycle: str) -> None:  # fmt: skip
    path = tmp_path / "cycle.yaml"
    path.write_text(SMALL + "intervals:\n" + intervals)
    done = scenario(command, path, "--backend", "fake", *(["--out", tmp_path / "out"] if command == "run" else []),
                    cwd=tmp_path)  # fmt: skip
    refused(done, re.escape(f"intervals {cycle} form a cycle"))
    nothing_written(tmp_path / "out")


NUL_PLACES = {
    "sound path": SMALL + 'sounds: {s: "sounds/thud.wav\\0"}\n',
    "key": SMALL + '"state\\0": {a: 1}\n',
    "body name": SMALL.replace("  box:", '  "bo\\0x":'),
    "expression": SMALL + 'assertions: [{name: a, at: end, check: "box.pos.z > 0\\0"}]\n',
    "raw byte in the file": SMALL + "description: a\x00b\n",
}


@pytest.mark.parametrize("place", list(NUL_PLACES))
def test_2_a_nul_byte_anywhere(tmp_path: Path, place: str) -> None:
    path = tmp_path / "nul.yaml"
    path.write_bytes(NUL_PLACES[place].encode())
    for command in ("validate", "run"):
        refused(scenario(command, path, "--backend", "fake", "--no-trace", cwd=tmp_path) if command == "run"
                else scenario(command, path, cwd=tmp_path), r"NUL character|#x0000")  # fmt: skip


@pytest.mark.parametrize("value", [
    "world.dt=!!float abc", "params.count=" + "9" * 5000, "description=!!binary aGVsbG8=", "description=!!set {a}",
    "description=!!timestamp 2001-12-14", "description=!!python/name:os.system", 'description="a\\0b"',
])  # fmt: skip
def test_3_set_values_yaml_cannot_build_name_the_argument(tmp_path: Path, value: str) -> None:
    pile = ROOT / "scenarios" / "box_pile.yaml"
    for command in ("validate", "run"):
        done = scenario(command, pile, "--set", value, *(["--no-trace"] if command == "run" else []), cwd=tmp_path)
        refused(done, re.escape(f"--set {value[:40]}"), COMMAND_LINE)


@pytest.mark.parametrize("reference", ["partial", "whole"])
def test_4_parameter_substitution_is_bounded_before_it_is_built(tmp_path: Path, reference: str) -> None:
    """An 810 KB file: a 10,000-character parameter used 200,000 times (2e9 characters once substituted).
    Before the bound it reached 3.96 GB in 5 s; now it is refused at once."""
    path = tmp_path / "bomb.yaml"
    uses = 200_000
    if reference == "partial":
        body = 'description: "' + "${p}" * uses + '"\n'
    else:
        body = "x: [" + ", ".join(['"${p}"'] * (uses // 2)) + "]\n"  # whole-value uses, each its own value
    path.write_text(SMALL + "params: {p: " + "y" * 10_000 + "}\n" + body)
    assert path.stat().st_size < 1_000_000
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-c", MEASURED, "validate", str(path)], capture_output=True, text=True,
                          cwd=tmp_path, timeout=20)  # fmt: skip
    took = time.perf_counter() - start
    peak_kib = int(done.stderr.rsplit("peak-rss-kib ", 1)[1])
    done.stderr = done.stderr.rsplit("peak-rss-kib ", 1)[0]
    refused(done, r"parameter substitution makes the document hold more than 4000000 characters of text; refused")
    assert took < 20
    assert peak_kib < 500 * 1024, f"peak RSS {peak_kib / 1024:.0f} MB"


@pytest.mark.parametrize("way", [[], ["-j", "2"], ["--isolate"], ["compare"]])
def test_5_over_long_names_are_refused_up_front_with_the_limit(tmp_path: Path, way: list[str]) -> None:
    path = tmp_path / "long.yaml"
    variant = "v" * 300
    path.write_text(SMALL + f"variants:\n  {variant}: {{}}\n")
    out = tmp_path / "out"
    if way == ["compare"]:
        done = scenario("compare", path, "--backend", "fake", "--out", out, cwd=tmp_path)
    else:
        done = scenario("run", path, "--backend", "fake", "--out", out, *way, cwd=tmp_path)
    refused(done, r"expected at most 64 characters \(the name is part of trace file names\); found 300")
    nothing_written(out)


def _fifo(folder: Path) -> Path:
    path = folder / "pipe.yaml"
    os.mkfifo(path)
    return path


SPECIAL = {
    "a FIFO as the scenario": lambda d: (_fifo(d), "expected a scenario file, found a FIFO"),
    "a device as the scenario": lambda d: (Path("/dev/zero"), "expected a scenario file, found a character device"),
    "a folder as the scenario": lambda d: (d / "empty", "found none"),
}


@pytest.mark.parametrize("kind", list(SPECIAL))
def test_7_special_files_are_refused_without_being_opened(tmp_path: Path, kind: str) -> None:
    (tmp_path / "empty").mkdir()
    path, message = SPECIAL[kind](tmp_path)
    for command in ("validate", "run"):
        start = time.perf_counter()
        done = scenario(command, path, *(["--no-trace"] if command == "run" else []), cwd=tmp_path, timeout=20)
        assert time.perf_counter() - start < 20
        assert done.returncode == 2 and "Traceback" not in done.stderr and message in done.stderr, done.stderr


@pytest.mark.parametrize("kind", ["fifo", "socket"])
def test_7_a_special_file_as_a_sound_is_refused_without_being_opened(tmp_path: Path, kind: str) -> None:
    target = tmp_path / "s.wav"
    if kind == "fifo":
        os.mkfifo(target)
    else:
        server = socket.socket(socket.AF_UNIX)
        server.bind(str(target))
    path = tmp_path / "t.yaml"
    path.write_text(SMALL + "sounds: {s: s.wav}\n")
    for command in ("validate", "run"):
        done = scenario(command, path, *(["--no-trace"] if command == "run" else []), cwd=tmp_path, timeout=20)
        found = "a FIFO (named pipe)" if kind == "fifo" else "a socket"
        refused(done, re.escape(f"expected a WAV file at 's.wav': expected a regular file, found {found}"))


def test_13_a_variant_setting_into_a_list_is_located(tmp_path: Path) -> None:
    path = tmp_path / "t.yaml"
    path.write_text(SMALL.replace("world: {dt: 0.04, duration: 1}", "world: [1, 0, 0]")
                    + "variants:\n  v: {set: {world.dt: 0.01}}\n")  # fmt: skip
    done = scenario("run", path, "--variant", "v", "--backend", "fake", "--out", tmp_path / "out", cwd=tmp_path)
    refused(done, re.escape(f"{path}:7:13: variants.v.set.world.dt: cannot set `world.dt`: `world` is a list, "
                            "not a mapping"))  # fmt: skip
    nothing_written(tmp_path / "out")
