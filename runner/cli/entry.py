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

#: Settings of the engines that keep their renderers from loading, unless the user set them: the command never
#: draws through an engine (its pictures and windows are Panda3D's), and MuJoCo's GL context (GLFW, which starts
#: a Python subprocess to ask the library's version) is about a tenth of a one-step run's start-up.
HEADLESS = {"MUJOCO_GL": "disable"}


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
