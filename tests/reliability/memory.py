"""Peak memory of one piece of work, on Linux, without what the process held before it.

``ru_maxrss`` is the wrong figure here: it is the whole process's high-water mark since it started, and
Linux carries it across ``fork`` and ``exec`` (a child of a 900 MB pytest process reports 900 MB at
once). ``VmHWM`` in ``/proc/self/status`` belongs to the current address space (``exec`` starts a new
one), and writing ``5`` to ``/proc/self/clear_refs`` lowers it to the current resident size, so that
the next reading is the peak since then.
"""

from __future__ import annotations

import re
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

#: a program that runs the command line and prints the peak of its worker processes on stderr
#: (``RUSAGE_CHILDREN``: finished children that were waited for, and theirs; the forkserver, whose children
#: the workers are when the command cannot fork itself, is stopped and waited for first)
WITH_WORKERS = (
    "import resource, sys\n"
    "from multiprocessing import forkserver\n"
    "from runner.cli.main import main\n"
    "code = main(sys.argv[1:])\n"
    "forkserver._forkserver._stop()\n"
    "print('workers-peak-kib', resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss, file=sys.stderr)\n"
    "sys.exit(code)\n"
)


def workers_peak_mib(stderr: str) -> tuple[float, str]:
    """The peak :data:`WITH_WORKERS` printed (MiB), and ``stderr`` without it."""
    rest, _, kib = stderr.rpartition("workers-peak-kib ")
    return int(kib) / 1024, rest


def _read() -> dict[str, float]:
    return {name: int(kib) / 1024 for name, kib in _FIELD.findall(STATUS.read_text())}


def start_window() -> float:
    """Start measuring: the peak is reset to the resident size now, which is returned (MB)."""
    Path("/proc/self/clear_refs").write_text("5")
    return _read()["VmRSS"]


def peak_since(start: float) -> float:
    """The most memory (MB) the process held since :func:`start_window` above what it held then."""
    return _read()["VmHWM"] - start
