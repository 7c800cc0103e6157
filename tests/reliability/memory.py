"""Peak memory of one piece of work, on Linux, without what the process held before it.

``ru_maxrss`` is the wrong figure here: it is the whole process's high-water mark since it started, and
Linux carries it across ``fork`` and ``exec`` (a child of a 900 MB pytest process reports 900 MB at
once). ``VmHWM`` in ``/proc/self/status`` belongs to the current address space (``exec`` starts a new
one), and writing ``5`` to ``/proc/self/clear_refs`` lowers it to the current resident size, so that
the next reading is the peak since then.
"""

from __future__ import annotations

import re
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

STATUS = Path("/proc/self/status")
_FIELD = re.compile(r"^(VmHWM|VmRSS):\s+(\d+) kB$", re.M)

#: a program that runs the command line and prints its own peak (VmHWM) on stderr, for a subprocess
MEASURED = (
    "import re, sys\n"
    "from runner.cli.main import main\n"
    "code = main(sys.argv[1:])\n"
    "hwm = re.search(r'VmHWM:\\s+(\\d+)', open('/proc/self/status').read()).group(1)\n"
    "print('peak-rss-kib', hwm, file=sys.stderr)\n"
    "sys.exit(code)\n"
)

#: a program that runs the command line and prints on stderr its own peak (VmHWM) and that of its worker
#: processes (``RUSAGE_CHILDREN``: finished children that were waited for, and theirs; the forkserver, whose
#: children the workers are when the command cannot fork itself, is stopped and waited for first)
WITH_WORKERS = (
    "import re, resource, sys\n"
    "from multiprocessing import forkserver\n"
    "from runner.cli.main import main\n"
    "code = main(sys.argv[1:])\n"
    "forkserver._forkserver._stop()\n"
    "hwm = re.search(r'VmHWM:\\s+(\\d+)', open('/proc/self/status').read()).group(1)\n"
    "workers = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss\n"
    "print('peak-kib', hwm, workers, file=sys.stderr)\n"
    "sys.exit(code)\n"
)


@dataclass(frozen=True)
class Measured:
    code: int
    stdout: str
    stderr: str  # without the peaks line
    seconds: float
    command_mib: float  # the command's own peak resident memory
    workers_mib: float  # the largest peak of its worker processes (0: none ran)


def run_measured(args: list[str], env: dict[str, str], timeout: float, cwd: Path | None = None) -> Measured:
    """``scenario ARGS`` through :data:`WITH_WORKERS`: exit code, output, wall time and peaks."""
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-c", WITH_WORKERS, *args], capture_output=True, text=True,
                          timeout=timeout, env=env, cwd=cwd)  # fmt: skip
    seconds = time.perf_counter() - start
    rest, _, line = done.stderr.rpartition("peak-kib ")
    if not line.strip():  # the command ended before printing (a traceback): no figures
        return Measured(done.returncode, done.stdout, done.stderr, seconds, 0.0, 0.0)
    hwm, workers = (int(x) / 1024 for x in line.split()[:2])
    return Measured(done.returncode, done.stdout, rest, seconds, hwm, workers)


def _read() -> dict[str, float]:
    return {name: int(kib) / 1024 for name, kib in _FIELD.findall(STATUS.read_text())}


def start_window() -> float:
    """Start measuring: the peak is reset to the resident size now, which is returned (MB)."""
    Path("/proc/self/clear_refs").write_text("5")
    return _read()["VmRSS"]


def peak_since(start: float) -> float:
    """The most memory (MB) the process held since :func:`start_window` above what it held then."""
    return _read()["VmHWM"] - start
