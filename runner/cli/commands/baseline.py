"""`scenario baseline`: record golden files (every variant of every file, on each backend asked for)."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.markup import escape

from backends.registry import DEFAULT_BACKEND
from runner.cli import options

NAME = "baseline"
HELP = "record golden files for `scenario check` (per scenario x variant x backend)"
DEFAULT_DIR = options.DEFAULT_BASELINE_DIR


def add_case_options(parser: argparse.ArgumentParser) -> None:
    """Options shared with `scenario check`."""
    options.add_scenario_files(parser)
    options.add_backend(parser, DEFAULT_BACKEND)
    parser.add_argument("--variant", metavar="NAME", help="only this variant (default: every variant)")
    options.add_overrides(parser)
    options.add_baseline_dir(parser)


def configure(parser: argparse.ArgumentParser) -> None:
    add_case_options(parser)
    parser.add_argument(
        "--period",
        type=float,
        metavar="SECONDS",
        help="time between recorded states, rounded to whole steps; 0 = every step "
        "(default: the existing file's, else 0.1 s)",
    )
    parser.add_argument("--out", type=Path, help="keep the recorded runs' traces in this folder (default: not kept)")


def load_cases(files: list[Path], variant: str | None, sets: list[str] | None = None) -> list:  # noqa: ANN401
    """Every variant (or one) of every scenario file (folders expanded), with `--set` applied."""
    from runner.errors import ScenarioValidationError
    from runner.language.load import load_all, parse_overrides

    overrides = parse_overrides(sets or [])
    cases, problems = [], []
    for path in options.scenario_files(files):
        try:
            cases.extend(load_all(path, variant, variant is None, overrides))
        except ScenarioValidationError as exc:
            problems.extend(exc.issues)
    if problems:
        raise ScenarioValidationError(problems)
    return cases


def sit_out_refused(pairs: list, out: Console, what: str, keep: Callable[[Any, str], bool] | None = None) -> list:
    """With ``--backend all``: the (case, engine) pairs whose engine refuses the case up front (what `scenario
    validate --backend` checks: a capability it lacks, a limit it states) sit out, each named with the reason, as
    in `scenario compare`; ``keep(case, engine)`` keeps one anyway. A named engine that refuses a case is an
    error, as in `scenario run`."""
    from backends.errors import UnsupportedFeature
    from backends.registry import check_capabilities, get_backend
    from runner.compile.program import build_program

    kept = []
    worlds: dict[int, Any] = {}
    for case, backend in pairs:
        world = worlds.setdefault(id(case), build_program(case).world)
        try:
            check_capabilities(get_backend(backend), world)
        except UnsupportedFeature as refusal:
            if keep is None or not keep(case, backend):
                needs = ", ".join(sorted(str(getattr(c, "value", c)) for c in refusal.missing)) or str(refusal)
                out.print(f"not {what}: {case.model.scenario} · {case.variant} on {backend}, which refuses it up front "
                          f"({needs}; name the engines with --backend to see the refusal as an error)",
                          markup=False, highlight=False)  # fmt: skip
                continue
        kept.append((case, backend))
    return kept


def execute(args: argparse.Namespace, out: Console, err: Console) -> int:
    """Each case runs through runner.exec as `scenario run` runs it; one that does not complete records
    nothing and the command exits as `run` would (the most severe code)."""
    from runner.ci.regression import record_cases
    from runner.cli.outcomes import print_problem
    from runner.errors import ExitCode, UsageError
    from runner.exec.exits import most_severe

    if args.period is not None and not args.period >= 0:
        raise UsageError(f"--period {args.period}: expected seconds >= 0")
    backends = options.backend_names(args)
    cases = load_cases(args.files, args.variant, args.set)
    pairs = [(case, backend) for backend in backends for case in cases]
    if options.asks_every_engine(args):  # an engine that refuses a case has no baseline for it
        pairs = sit_out_refused(pairs, out, "recorded")
    recorded = record_cases(pairs, args.baseline, args.out, args.period)
    failed, written, codes = 0, 0, []
    for (case, backend), (res, path, rec) in zip(pairs, recorded, strict=True):
        if rec is None:
            print_problem(err, res)
            codes.append(res.exit.code)
            continue
        written += 1
        every = int(rec.header["every"])
        status = res.result.status if res.result is not None else res.status
        note = "" if res.passed else f" [yellow](recorded with status {status})[/]"
        out.print(
            f"recorded {escape(case.model.scenario)} · {escape(case.variant)} · {backend} -> {escape(str(path))} "
            f"({len(rec.steps)} states every {every} step{'s' if every != 1 else ''}, {len(rec.events)} events, "
            f"{len(rec.verdicts)} verdicts){note}"
        )
        failed += not res.passed
    out.print(f"{written} baseline(s) written to {args.baseline}", markup=False)
    if failed:
        err.print(f"[yellow]warning:[/] {failed} run(s) did not pass; their goldens record that status")
    return most_severe(codes) if codes else ExitCode.OK
