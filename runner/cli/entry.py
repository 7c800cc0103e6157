"""The `scenario` command's entry point: handles SIGINT and SIGTERM before anything heavy is imported.

Importing the command (Rich, pydantic, the scenario language) takes about half a second; a Ctrl-C or a
SIGTERM meanwhile is an interruption like any other (exit 130 / 143, one line, no traceback).
"""

from __future__ import annotations

import contextlib
import os
import sys

from runner import interrupts

__all__ = ["HEADLESS", "main"]

#: Settings the command gives the libraries it loads, unless the user set them (each is ``os.environ.setdefault``,
#: so a variable the user set, even empty, is theirs; the workers inherit them). None changes a result:
#:
#: - ``MUJOCO_GL=disable``: MuJoCo's renderer stays unloaded. The command never draws through an engine (its
#:   pictures and windows are Panda3D's), and MuJoCo's GL context (GLFW, which starts a Python subprocess to ask
#:   the library's version) is about a tenth of a one-step run's start-up.
#: - ``OPENBLAS_THREAD_TIMEOUT=4``: numpy's OpenBLAS threads go to sleep as soon as they have no work, instead of
#:   spinning for about 2**28 cycles (0.1 s) after they start and after each threaded call: in a one-step run that
#:   spin was about 90 ms of CPU time, a sixth of the run, taken from the other core. The number of threads, and
#:   so every result, is unchanged; a large threaded call (none in the runner, whose arrays are small) waits a
#:   few microseconds for the threads to wake.
#: - ``PYDANTIC_DISABLE_PLUGINS=__all__``: pydantic does not look for plugins (the entry points of the group
#:   ``pydantic``: every installed distribution's list, read when the first validator is built, about 4 ms). The
#:   scenario language's models are the tool's own: a pydantic plugin installed in the same environment (tracing
#:   or logging validations) would only see the tool's internals, and does not run on them; set the variable (to
#:   an empty string, for instance) to have pydantic load its plugins.
HEADLESS = {"MUJOCO_GL": "disable", "OPENBLAS_THREAD_TIMEOUT": "4", "PYDANTIC_DISABLE_PLUGINS": "__all__"}


def main() -> int:
    for name, value in HEADLESS.items():
        os.environ.setdefault(name, value)
    interrupts.install()  # kept: runner.cli.main.main installs them again and restores these at its end
    try:
        from runner.cli.main import main as command
    except BaseException as exc:
        interruption = interrupts.behind(exc)  # a class being built may have wrapped it in RuntimeError
        if interruption is None:
            raise
        code = 128 + interrupts.signal_of(interruption)
        sys.stderr.write(f"{'terminated (SIGTERM)' if code == 143 else 'interrupted (Ctrl-C)'} while starting\n")
        sys.stderr.flush()
        # at once: an import that saw the KeyboardInterrupt pass through C code may have marked it unhandled,
        # and the interpreter would then end by SIGINT instead of this exit code; nothing is written yet
        os._exit(code)
    code = command()
    if code in (130, 143):  # interrupted: its exit code, whatever an import that saw the signal may have marked
        with contextlib.suppress(OSError):
            sys.stdout.flush()
            sys.stderr.flush()
        os._exit(code)
    return code
