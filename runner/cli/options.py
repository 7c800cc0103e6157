"""The command line's shared arguments, defined once so that every command spells them the same way.

* scenario files: files or folders; a folder stands for every scenario file under it, recursively, chosen as
  the pytest plugin chooses them (``*.yaml``/``*.yml`` with a top-level ``schema_version:`` or ``scenario:``
  key; hidden folders and pytest's default ``norecursedirs`` skipped), in path order;
* ``--backend NAMES`` (``-b``): one name, a comma-separated list, repeatable; ``all`` is every installed engine;
* ``--variant NAME`` / ``--all-variants``;
* ``--set KEY=VALUE`` wherever a scenario is loaded;
* ``--baseline DIR``: the folder of golden files, for ``baseline`` and ``check`` alike;
* ``--reference NAME``, ``--max-divergence VALUE``, ``--require-agreement``: how ``compare`` and ``report``
  judge the engines (docs/report-schema.md).
"""

from __future__ import annotations

import argparse
from collections.abc import Iterator
from pathlib import Path

from runner.language.files import scenario_files

__all__ = [
    "ALL",
    "add_backend",
    "add_baseline_dir",
    "add_judgement",
    "add_overrides",
    "add_scenario_files",
    "add_variant_choice",
    "asks_every_engine",
    "backend_names",
    "scenario_files",
]

#: `--backend all`: every installed engine (test-only backends excluded).
ALL = "all"
DEFAULT_BASELINE_DIR = Path("baselines")


def add_scenario_files(parser: argparse.ArgumentParser, what: str = "scenario files") -> None:
    parser.add_argument(
        "files", nargs="+", type=Path, metavar="FILE|FOLDER",
        help=f"{what}, or folders: every scenario file under a folder, recursively (as `pytest FOLDER` collects)",
    )  # fmt: skip


def add_backend(parser: argparse.ArgumentParser, default: str) -> None:
    """``--backend``/``-b``; ``default`` is a name or ``all``."""
    shown = "every installed engine" if default == ALL else default
    parser.add_argument(
        "--backend", "-b", action="append", metavar="NAMES",
        help=f"engine(s): a name or a comma-separated list, repeatable; `all` = every installed engine "
        f"(default: {shown})",
    )  # fmt: skip
    # the names this option had before it was one flag everywhere: still read, not shown
    parser.add_argument("--backends", action="append", dest="backend", help=argparse.SUPPRESS)
    parser.set_defaults(backend_default=default)


def add_variant_choice(parser: argparse.ArgumentParser, default_text: str = "the file's first variant") -> None:
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--variant", metavar="NAME", help=f"this variant only (default: {default_text})")
    group.add_argument("--all-variants", action="store_true", help="every variant")


def add_overrides(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--set", action="append", default=[], metavar="KEY=VALUE",
        help="replace a value by its dotted path, e.g. world.dt=0.01 or params.count=50 (repeatable); only values "
        "the file declares (a misspelt parameter is an error); applied after the variant's own `set:`, so it wins",
    )  # fmt: skip


def add_baseline_dir(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--baseline", type=Path, default=DEFAULT_BASELINE_DIR, metavar="DIR",
        help=f"folder of the golden files (default {DEFAULT_BASELINE_DIR}/)",
    )  # fmt: skip
    parser.add_argument("--dir", type=Path, dest="baseline", help=argparse.SUPPRESS)  # its former name in `baseline`


def add_judgement(parser: argparse.ArgumentParser) -> None:
    """``--reference``, ``--max-divergence`` and ``--require-agreement`` of ``compare`` and ``report``."""
    parser.add_argument(
        "--reference", metavar="NAME",
        help="measure every engine against this backend's run where no truth is known (default: the engines are "
        "compared with each other and the ones that depart from a majority are named)",
    )  # fmt: skip
    parser.add_argument(
        "--max-divergence", type=float, metavar="VALUE",
        help="fail a backend whose positions (m: bodies, sliders, joint drift) stray further than VALUE from their "
        "truth (where none is known: from the engines it is judged with, or from --reference's run); also the "
        "report's position threshold",
    )  # fmt: skip
    parser.add_argument(
        "--require-agreement", action="store_true",
        help="fail (exit 1) when the engines disagree: one misses a known truth or departs from the majority, or "
        "no majority forms (default: agreement is reported, the exit code follows the assertions)",
    )


def _names(values: list[str] | None, default: str) -> Iterator[str]:
    for value in values or [default]:
        yield from (n.strip() for n in value.split(","))


def asks_every_engine(args: argparse.Namespace) -> bool:
    """Whether ``--backend`` (or its default) says ``all``: every installed engine, each for the cases it runs."""
    return any(name in (ALL, "installed") for name in _names(args.backend, args.backend_default))


def backend_names(args: argparse.Namespace) -> list[str]:
    """The backends asked for, in order, each once: checked against the registry (an unknown name is bad input,
    exit 2) and installed (else the install hint, exit 3)."""
    from backends.errors import BackendNotInstalled
    from backends.registry import entry, installed_backends, is_installed
    from runner.errors import UsageError

    names: list[str] = []
    for name in _names(args.backend, args.backend_default):
        if not name:
            continue
        chosen = installed_backends() if name in (ALL, "installed") else [name]
        names += [n for n in chosen if n not in names]
    if not names:
        if args.backend or args.backend_default != ALL:
            raise UsageError("--backend expects engine names, e.g. --backend ode,pybullet or --backend all")
        raise BackendNotInstalled("No backend is installed. Install one with: pip install 'physics-scenarios[ode]'")
    for name in names:
        entry(name)  # unknown -> UnknownBackend (exit 2), with the closest name
        if not is_installed(name):
            raise BackendNotInstalled(f"Backend `{name}` is not installed. Install it with: {entry(name).hint}")
    return names
