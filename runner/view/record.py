"""``--record NAME``: what was played, written into the scenario file as a new variant.

The file is changed by insertion only: the new variant's lines go in after the last line of the
``variants:`` block (or a new block at the end), so every other byte, comments and layout included,
stays as it was. ruamel.yaml (a round-trip YAML library) reads where that block ends and writes the new
variant's YAML; the result is checked before it replaces the file (atomically): the old lines are all
still there in order, every other variant loads to the same model as before, and the new variant's
inputs fall on exactly the steps they were played at (the loader's rule: an input at ``t`` is due at the
first step whose time is at or after ``t``, runner.compile.program). A variant copies the ``set``,
inputs and assertions of the variant that was played, adds the played inputs and says in comments
where it comes from and what the verdicts of the live run were.
"""

from __future__ import annotations

import copy
import difflib
import hashlib
import io
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from runner.compile.program import STEP_EPS, build_program
from runner.errors import InternalError, UsageError
from runner.language.load import BASE_CASE, LoadedScenario, load_scenario
from runner.sim.assertions import Verdict

__all__ = ["Played", "RecordPlan", "due_step", "input_time", "plan_record", "write_record"]


@dataclass(frozen=True)
class Played:
    """One input made in the window: delivered at the start of step ``step`` (time step * dt)."""

    step: int
    event: str


def due_step(t: float, dt: float) -> int:
    """The step a timed input at ``t`` is delivered at (the loader's rule, runner.compile.program)."""
    return max(0, math.ceil(t / dt - STEP_EPS))


def input_time(step: int, dt: float) -> float:
    """The time of step ``step`` (``step * dt``, when the input was delivered) as the shortest decimal that
    is that time to a nanosecond (the trace's resolution) and that the loader maps back to ``step``: 1.2,
    not 1.2000000000000002 (and never 1.5 for step 38 of 0.04 s, which the loader would also map there)."""
    exact = step * dt
    for digits in range(1, 18):
        t = round(exact, digits)
        if abs(t - exact) < 0.5e-9 and due_step(t, dt) == step:
            return t
    return exact  # pragma: no cover - k*dt itself always maps to k


def _yaml() -> Any:
    from ruamel.yaml import YAML

    yaml = YAML()  # round trip (typ "rt"): keeps comments, order, styles, quotes; builds no Python objects from tags
    yaml.preserve_quotes = True
    yaml.width = 4096
    yaml.indent(mapping=2, sequence=4, offset=2)
    return yaml


@dataclass(frozen=True)
class RecordPlan:
    """Where a variant called ``name`` goes into ``path`` (checked before the window opens)."""

    path: Path
    name: str
    insert_at: int  # line index the new variant's lines are inserted before
    indent: int  # column of the variants' names
    new_block: bool  # the file has no ``variants:`` yet


def _last_line(lines: Sequence[str], start: int, stop: int) -> int:
    """The last line in [start, stop) that belongs to an indented block (not blank, not a column-0 comment)."""
    last = start
    for i in range(start, stop):
        text = lines[i]
        if text.strip() and not text.startswith("#"):
            last = i
    return last


def plan_record(loaded: LoadedScenario, name: str) -> RecordPlan:
    """Check that a variant ``name`` can be added to ``loaded``'s file; say where (UsageError if not)."""
    path = loaded.path
    data = _yaml().load(loaded.text)
    variants = data.get("variants")
    if "variants" in data and not (hasattr(variants, "lc") and variants and not variants.fa.flow_style()):
        raise UsageError(
            f"{path}: cannot add a variant to `variants:` written in flow style or empty; write it as a block "
            "mapping (one variant per key) first"
        )
    if variants is not None and name in variants:
        line, col = variants.lc.key(name)
        raise UsageError(f"{path}:{line + 1}:{col + 1}: variant `{name}` already exists; choose another name")
    if name == BASE_CASE:
        raise UsageError(f"`{BASE_CASE}` names the file's base case; choose another variant name")
    lines = loaded.text.splitlines()
    if variants is None:
        return RecordPlan(path, name, len(lines), 2, True)
    keys = list(data.keys())
    after = keys.index("variants") + 1
    stop = data.lc.key(keys[after])[0] if after < len(keys) else len(lines)
    start = data.lc.key("variants")[0]
    first = next(iter(variants))
    return RecordPlan(path, name, _last_line(lines, start, stop) + 1, variants.lc.key(first)[1], False)


def _verdict_lines(verdicts: Sequence[Verdict]) -> list[str]:
    passed = sum(v.passed for v in verdicts)
    out = [f"Verdicts of that run: {passed} passed, {len(verdicts) - passed} failed"]
    for v in verdicts:
        mark = "pass" if v.passed else "FAIL"
        detail = "" if v.passed else f": measured {v.measured}, expected {v.expected}"
        out.append(f"  {mark} {v.name}{detail}")
    return out


def variant_text(plan: RecordPlan, loaded: LoadedScenario, played: Sequence[Played], dt: float,
                 verdicts: Sequence[Verdict], backend: str, engine: str) -> str:  # fmt: skip
    """The new variant's lines (comments, then the YAML), indented for the file."""
    from ruamel.yaml.comments import CommentedMap, CommentedSeq

    editor = _yaml()
    data = editor.load(loaded.text)
    source = (data.get("variants") or {}).get(loaded.variant) if loaded.variant != BASE_CASE else None
    source = source if isinstance(source, dict) else {}
    body = CommentedMap()
    listed = ", ".join(f"{p.event} at {input_time(p.step, dt):g} s" for p in played) or "no input"
    body["description"] = (
        f"Played in `scenario view` on {backend} from {loaded.variant!r}: {listed}."
        if loaded.variant != BASE_CASE
        else f"Played in `scenario view` on {backend}: {listed}."
    )
    settings = CommentedMap(copy.deepcopy(source.get("set") or {}))
    for key, value in loaded.overrides:  # `--set` on the command line: the variant replays what was played
        if key.split(".")[0] != "variants":
            settings[key] = copy.deepcopy(value)
    if settings:
        body["set"] = settings
    inputs = CommentedSeq()
    for item in (source["inputs"] if "inputs" in source else data.get("inputs")) or []:
        inputs.append(copy.deepcopy(item))  # the inputs the played variant had (its own, else the file's)
    for p in played:
        entry = CommentedMap()
        entry["at"] = input_time(p.step, dt)
        entry["event"] = p.event
        entry.fa.set_flow_style()
        inputs.append(entry)
    body["inputs"] = inputs
    if source.get("assertions"):
        body["assertions"] = copy.deepcopy(source["assertions"])
    out = io.StringIO()
    editor.dump({plan.name: body}, out)
    header = [f"Recorded by `scenario view` on {backend} ({engine}); the played inputs are at the step"]
    header.append("boundaries they were delivered at (the times are multiples of dt).")
    header += _verdict_lines(verdicts)
    pad = " " * plan.indent
    body_lines = [(pad + line).rstrip() for line in out.getvalue().rstrip().splitlines()]
    lines = [f"{pad}# {h}".rstrip() for h in header] + body_lines
    return "\n".join(lines) + "\n"


def new_file_text(plan: RecordPlan, text: str, variant: str) -> str:
    lines = text.splitlines(keepends=True)
    if lines and not lines[-1].endswith("\n"):
        lines[-1] += "\n"
    block = ("variants:\n" + variant) if plan.new_block else variant
    return "".join(lines[: plan.insert_at]) + block + "".join(lines[plan.insert_at :])


def _check(plan: RecordPlan, loaded: LoadedScenario, old: str, new: str, tmp: Path,
           expected: list[tuple[int, str]]) -> None:  # fmt: skip
    ops = difflib.SequenceMatcher(a=old.splitlines(), b=new.splitlines(), autojunk=False).get_opcodes()
    if any(tag not in ("equal", "insert") for tag, *_ in ops):
        raise InternalError(f"recording `{plan.name}` would change existing lines of {plan.path}; nothing written")
    from runner.language.load import variant_names

    for name in variant_names(plan.path):
        before = load_scenario(plan.path, None if name == BASE_CASE else name).model.model_dump()
        after = load_scenario(tmp, None if name == BASE_CASE else name).model.model_dump()
        after.get("variants", {}).pop(plan.name, None)  # the model lists every variant: all but the new one
        if not after.get("variants") and not before.get("variants"):
            after["variants"] = before.get("variants")
        if before != after:
            raise InternalError(f"recording `{plan.name}` would change variant `{name}`; nothing written")
    recorded = build_program(load_scenario(tmp, plan.name))
    got = [(i.step, i.event) for i in recorded.inputs]
    if got != expected:
        raise InternalError(f"the recorded inputs load as {got}, not {expected}; nothing written")


def write_record(plan: RecordPlan, loaded: LoadedScenario, played: Sequence[Played], dt: float,
                 verdicts: Sequence[Verdict], backend: str, engine: str) -> str:  # fmt: skip
    """Write the variant into the file (checked, atomically); returns the text added."""
    current = plan.path.read_bytes()
    if hashlib.sha256(current).hexdigest() != loaded.sha256:
        raise UsageError(f"{plan.path} changed while the window was open; the variant was not written")
    variant = variant_text(plan, loaded, played, dt, verdicts, backend, engine)
    new = new_file_text(plan, loaded.text, variant)
    tmp = plan.path.with_name(f".{plan.path.name}.{os.getpid()}.view.yaml")
    try:
        tmp.write_text(new, encoding="utf-8")
        base = build_program(loaded).inputs
        expected = sorted([(i.step, i.event) for i in base] + [(p.step, p.event) for p in played],
                          key=lambda x: x[0])  # fmt: skip
        _check(plan, loaded, loaded.text, new, tmp, expected)
        os.replace(tmp, plan.path)
    finally:
        tmp.unlink(missing_ok=True)
    return variant
