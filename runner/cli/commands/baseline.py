"""`scenario baseline`: record golden files (every variant of every file, on each backend asked for)."""

from __future__ import annotations

import argparse
from pathlib import Path

from rich.console import Console

from backends.registry import DEFAULT_BACKEND

NAME = "baseline"
HELP = "record golden files for `scenario check` (per scenario x variant x backend)"
DEFAULT_DIR = Path("baselines")


def add_case_options(parser: argparse.ArgumentParser) -> None:
    """Options shared with `scenario check`."""
    parser.add_argument("files", nargs="+", type=Path, metavar="FILE")
    parser.add_argument(
        "--backend",
        "-b",
        action="append",
        metavar="NAME",
        help=f"engine(s), repeatable or comma-separated; `installed` = every installed one (default {DEFAULT_BACKEND})",
    )
    parser.add_argument("--variant", help="only this variant (default: every variant)")


def configure(parser: argparse.ArgumentParser) -> None:
    add_case_options(parser)
    parser.add_argument("--dir", type=Path, default=DEFAULT_DIR, help="folder of the golden files (default baselines/)")
    parser.add_argument(
        "--period",
        type=float,
        metavar="SECONDS",
        help="time between recorded states, rounded to whole steps; 0 = every step "
        "(default: the existing file's, else 0.1 s)",
    )
    parser.add_argument("--out", type=Path, help="keep the recorded runs' traces in this folder (default: not kept)")


def backends_from(values: list[str] | None) -> list[str]:
    """Backend names from repeated/comma-separated options, checked and installed (else bad input / exit 3)."""
    from backends.errors import BackendNotInstalled
    from backends.registry import entry, installed_backends, is_installed

    names: list[str] = []
    for value in values or [DEFAULT_BACKEND]:
        for name in (n.strip() for n in value.split(",")):
            chosen = installed_backends() if name == "installed" else [name] if name else []
            names += [n for n in chosen if n not in names]
    for name in names:
        entry(name)  # unknown -> UnknownBackend (exit 2)
        if not is_installed(name):
            raise BackendNotInstalled(f"Backend `{name}` is not installed. Install it with: {entry(name).hint}")
    return names


def load_cases(files: list[Path], variant: str | None) -> list:  # noqa: ANN401 - LoadedScenario, imported late
    from runner.errors import ScenarioValidationError
    from runner.language.load import load_all

    cases, problems = [], []
    for path in files:
        try:
            cases.extend(load_all(path, variant, variant is None, ()))
        except ScenarioValidationError as exc:
            problems.extend(exc.issues)
    if problems:
        raise ScenarioValidationError(problems)
    return cases


def execute(args: argparse.Namespace, out: Console, err: Console) -> int:
    from runner.ci.regression import record_case
    from runner.errors import ExitCode, UsageError

    if args.period is not None and not args.period >= 0:
        raise UsageError(f"--period {args.period}: expected seconds >= 0")
    backends = backends_from(args.backend)
    cases = load_cases(args.files, args.variant)
    failed = 0
    for backend in backends:
        for case in cases:
            result, path, rec = record_case(case, backend, args.dir, args.out, args.period)
            every = int(rec.header["every"])
            note = "" if result.passed else f" [yellow](recorded with status {result.status})[/]"
            out.print(
                f"recorded {case.model.scenario} · {case.variant} · {backend} -> {path} "
                f"({len(rec.steps)} states every {every} step{'s' if every != 1 else ''}, {len(rec.events)} events, "
                f"{len(rec.verdicts)} verdicts){note}"
            )
            failed += not result.passed
    out.print(f"{len(cases) * len(backends)} baseline(s) written to {args.dir}")
    if failed:
        err.print(f"[yellow]warning:[/] {failed} run(s) did not pass; their goldens record that status")
    return ExitCode.OK
