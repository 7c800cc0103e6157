"""Hostile scenario documents for the fuzzing tests: seeds, tree mutations, text mutations (hypothesis).

A case starts from a seed (every scenario in ``scenarios/`` and the small documents of
tests/language/test_bad_input.py), applies one to four mutations to its data tree (wrong types, missing,
extra and renamed keys, huge, negative and non-finite numbers, deep nesting, unicode, broken
references, YAML hazards), dumps it as YAML and may then damage the text itself; or it is random text
or bytes. Everything is drawn through hypothesis, so a failure shrinks to a small reproducer.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml
from hypothesis import strategies as st

from runner.errors import ScenarioValidationError
from runner.language.yaml_source import load_yaml
from tests.language.test_bad_input import BASE, CASES

ROOT = Path(__file__).resolve().parents[2]
SCENARIOS = sorted((ROOT / "scenarios").glob("*.yaml"))
Tree = Any
Path_ = tuple[str | int, ...]


@dataclass(frozen=True)
class Seed:
    name: str
    text: str
    data: Tree | None  # None when the seed's text is not loadable YAML (it is then mutated as text)


def _seeds() -> list[Seed]:
    texts = [(p.name, p.read_text()) for p in SCENARIOS] + [("base", BASE)] + [(c[0], c[1]) for c in CASES]
    out = []
    for name, text in texts:
        try:
            data = load_yaml(text, name)[0]
        except ScenarioValidationError:
            data = None
        out.append(Seed(name, text, data))
    return out


SEEDS = _seeds()
REPO_SEEDS = [s for s in SEEDS if s.name.endswith(".yaml")]


def get(tree: Tree, path: Path_) -> Tree:
    for part in path:
        tree = tree[part]
    return tree


def walk(tree: Tree, path: Path_ = ()) -> Iterator[Path_]:
    """Every path in ``tree`` (dict keys and list indices), parents before children."""
    yield path
    if isinstance(tree, dict):
        for key, value in tree.items():
            yield from walk(value, path + (key,))
    elif isinstance(tree, list):
        for i, value in enumerate(tree):
            yield from walk(value, path + (i,))


def _words(tree: Tree) -> set[str]:
    out: set[str] = set()
    for path in walk(tree):
        out.update(p for p in path if isinstance(p, str))
        value = get(tree, path)
        if isinstance(value, str) and len(value) < 40:
            out.add(value)
    return out


VOCAB = sorted(set().union(*(_words(s.data) for s in SEEDS if s.data is not None)))


# ---- values ---------------------------------------------------------------------------------------

NUMBERS = [
    0, 1, -1, 2, 3, 7, 0.5, -0.0, -1e-9, 1e-300, 5e-324, 1e308, -1e308, 1.7976931348623157e308, math.nan,
    math.inf, -math.inf, 2**31, 2**53 + 1, 2**63, -(2**63) - 1, 10**30, 10**400, 10_000, 10_001, 100_000,
    1e7, 1e12,
]  # fmt: skip
STRINGS = [
    "", " ", "end", "environment", "start", "time", "inf", "nan", "-inf", "${count}", "${nope}", "${count",
    "$", "{}", "[]", "~", "null", "yes", "on", "1e999", "0x1F", "1_000",
    "__import__('os').system('true')", "().__class__.__bases__[0].__subclasses__()", "box.__class__",
    "9**9**9", "open('/etc/passwd')", "lambda: 1", "box.pos.z > 0", "contact(box, door)", "playing('x')",
    "max(crate.pos.z)", "state.door_open", "param.count * 2", "1/0", "sqrt(-1)", "a" * 2001, "x" * 65,
    "../../etc/passwd", "/etc/passwd", "sounds/thud.wav", "sounds", ".", "sounds/../sounds/close.wav",
    "\u202egnp.txt", "\u00e9v\u00e9nement", "\u540d\u524d", "\U0001f642", "a\u0301", "\ufeffkey", "tab\there",
    "line\nbreak", "nul\x00byte", "bell\x07", "\u2028", "\ufffe", "%fn-into-%in", "*-again-*", "box-into-door",
]  # fmt: skip
KEYS = [
    "box", "sphere", "mass", "density", "pos", "hpr", "quat", "scale", "vel", "angvel", "motion", "array",
    "count", "dt", "duration", "substeps", "gravity", "bounce", "mu", "type", "bodies", "axis", "motor",
    "fmax", "limits", "at", "event", "every", "repeat", "name", "value", "near", "tol", "always", "during",
    "lerp", "sequence", "parallel", "func", "wait", "sound", "start", "loop", "set", "calc", "if", "then",
    "else", "inputs", "assertions", "variants", "params", "state", "on", "intervals", "collisions",
    "sounds", "joints", "surfaces", "backend_options", "pybullet", "solver_iterations", "schema_version",
    "<<", "__class__", "_private", "\u00e9", "",
]  # fmt: skip

texts = st.text(st.characters(blacklist_categories=("Cs",)), max_size=24)
scalars = st.one_of(
    st.sampled_from(NUMBERS),
    st.sampled_from(STRINGS),
    st.sampled_from(VOCAB),
    st.none(),
    st.booleans(),
    st.integers(),
    st.floats(),
    texts,
)
keys = st.one_of(st.sampled_from(KEYS), st.sampled_from(VOCAB), texts)
structures = st.recursive(
    scalars, lambda inner: st.lists(inner, max_size=4) | st.dictionaries(keys, inner, max_size=4), max_leaves=12
)


@st.composite
def misspelt(draw: st.DrawFn, word: str) -> str:
    """One edit away from ``word`` (dropped, doubled, swapped or replaced letter)."""
    if not word:
        return draw(texts)
    i = draw(st.integers(0, len(word) - 1))
    kind = draw(st.sampled_from(["drop", "double", "swap", "replace", "case"]))
    if kind == "drop":
        return word[:i] + word[i + 1 :]
    if kind == "double":
        return word[:i] + word[i] + word[i:]
    if kind == "swap" and i + 1 < len(word):
        return word[:i] + word[i + 1] + word[i] + word[i + 2 :]
    if kind == "case":
        return word.swapcase()
    return word[:i] + draw(st.characters(blacklist_categories=("Cs",))) + word[i + 1 :]


@st.composite
def nested(draw: st.DrawFn) -> Tree:
    """Lists or mappings nested 1 to 400 deep (the loader's limit is 64)."""
    depth = draw(st.integers(1, 400))
    value: Tree = draw(scalars)
    as_map = draw(st.booleans())
    for _ in range(depth):
        value = {"a": value} if as_map else [value]
    return value


@st.composite
def hostile_value(draw: st.DrawFn, old: Tree) -> Tree:
    """A replacement for ``old``: of the wrong type, out of range, broken, or a near miss."""
    kind = draw(st.sampled_from(["scalar", "structure", "nested", "near", "wrap", "unwrap", "number", "ref"]))
    if kind == "scalar":
        return draw(scalars)
    if kind == "structure":
        return draw(structures)
    if kind == "nested":
        return draw(nested())
    if kind == "wrap":
        return [old] if draw(st.booleans()) else {draw(keys): old}
    if kind == "unwrap" and isinstance(old, list | dict) and old:
        return list(old.values())[0] if isinstance(old, dict) else old[0]
    if kind == "near" and isinstance(old, str):
        return draw(misspelt(old))
    if kind == "number" and isinstance(old, int | float) and not isinstance(old, bool):
        factor = draw(st.sampled_from([-1, 0, 1e-300, 1e300, 10, 1e6, math.inf, math.nan]))
        try:
            return old * factor
        except OverflowError:
            return math.inf
    if kind == "ref":
        return draw(st.sampled_from(VOCAB))
    return draw(scalars)


# ---- tree mutations -------------------------------------------------------------------------------


def _set(tree: Tree, path: Path_, value: Tree) -> Tree:
    if not path:
        return value
    get(tree, path[:-1])[path[-1]] = value
    return tree


def _is_number(value: Tree) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


numbers = st.one_of(
    st.sampled_from(NUMBERS),
    st.floats(),
    st.floats(min_value=-1e6, max_value=1e6),
    st.integers(-(10**6), 10**6),
)


@st.composite
def mutate_number(draw: st.DrawFn, old: float) -> float:
    """A number in place of ``old``: out of range, non-finite, huge, tiny, or ``old`` scaled."""
    if draw(st.booleans()):
        return draw(numbers)
    factor = draw(st.sampled_from([-1, 0, 1e-300, 1e-9, 1e-3, 10, 1e3, 1e9, 1e300, math.inf, math.nan]))
    try:
        return old * factor
    except OverflowError:
        return math.inf


@st.composite
def mutate_tree(draw: st.DrawFn, tree: Tree) -> Tree:
    """One mutation at a random place of ``tree`` (changed in place where possible; returned).

    Half the mutations change numbers only (one number, or every number of a vector), so that many
    cases stay well-formed and reach the compiler with extreme values.
    """
    paths = list(walk(tree))
    numeric = [p for p in paths if _is_number(get(tree, p))]
    if numeric and draw(st.booleans()):
        path = draw(st.sampled_from(numeric))
        parent = get(tree, path[:-1])
        if isinstance(parent, list) and all(_is_number(v) for v in parent) and draw(st.booleans()):
            for i, value in enumerate(parent):  # a whole vector: pos, quat, axis, size...
                parent[i] = draw(mutate_number(value))
            return tree
        return _set(tree, path, draw(mutate_number(get(tree, path))))
    path = draw(st.sampled_from(paths))
    node = get(tree, path)
    op = draw(st.sampled_from(["replace", "delete", "add", "rename", "copy", "replace", "duplicate-key"]))
    if op == "delete" and path:
        parent = get(tree, path[:-1])
        del parent[path[-1]]
        return tree
    if op in ("add", "duplicate-key") and isinstance(node, dict):
        key = draw(keys) if op == "add" else draw(misspelt(draw(st.sampled_from(sorted(node) or ["x"]))))
        node[key] = draw(hostile_value(None))
        return tree
    if op == "rename" and path and isinstance(path[-1], str):
        parent = get(tree, path[:-1])
        new = draw(st.one_of(misspelt(path[-1]), keys))
        parent[new] = parent.pop(path[-1])
        return tree
    if op == "copy":
        source = get(tree, draw(st.sampled_from(paths)))
        return _set(tree, path, copy.deepcopy(source))
    return _set(tree, path, draw(hostile_value(node)))


# ---- text -----------------------------------------------------------------------------------------

YAML_HAZARDS = [
    "!!python/object/apply:os.system ['true']", "!!python/name:os.system", "!!binary aGVsbG8=",
    "!!set {a, b}", "!!omap [a: 1]", "!custom 1", "!!float 'nan'", "!!int '0x1F'", "!!timestamp 2001-12-14",
    "&a [1, 2]", "*a", "*missing", "<<: *a", "<<: 5", "---", "...", "%YAML 1.1", "%TAG ! tag:x:", "? [a, b]",
    "\t", "\r\n", "\r", "\ufeff", "\x00", "\x01", "\x1b[31m", "\u0085", "\ufffe", "'", '"', "\\", "{", "}", "[",
    "]", ":", ": ", "- ", " " + "9" * 4301, "#", "|", ">", "@", "`", ",", "=", "~", " " * 40, "\n" * 3,
    "x: " + "[" * 300,
    "a: &a [1,1,1,1,1,1,1,1,1,1]\nb: &b [*a,*a,*a,*a,*a,*a,*a,*a,*a,*a]\nc: &c [*b,*b,*b,*b,*b,*b,*b,*b,*b,*b]\n"
    "d: &d [*c,*c,*c,*c,*c,*c,*c,*c,*c,*c]\ne: [*d,*d,*d,*d,*d,*d,*d,*d,*d,*d]\n",
]  # fmt: skip


@st.composite
def mutate_text(draw: st.DrawFn, text: str) -> str:
    """Damage the YAML text: insert a hazard or random text, delete, duplicate or swap lines, truncate."""
    op = draw(st.sampled_from(["insert", "insert", "delete", "dup-line", "swap-lines", "truncate", "replace"]))
    pos = draw(st.integers(0, len(text)))
    if op == "insert":
        snippet = draw(st.one_of(st.sampled_from(YAML_HAZARDS), texts))
        return text[:pos] + snippet + text[pos:]
    if op == "delete":
        return text[:pos] + text[pos + draw(st.integers(1, 40)) :]
    if op == "truncate":
        return text[:pos]
    if op == "replace" and text:
        i = min(pos, len(text) - 1)
        return text[:i] + draw(st.characters(blacklist_categories=("Cs",))) + text[i + 1 :]
    lines = text.splitlines(keepends=True)
    if not lines:
        return text
    i, j = draw(st.integers(0, len(lines) - 1)), draw(st.integers(0, len(lines) - 1))
    if op == "dup-line":
        lines.insert(j, lines[i])
    else:
        lines[i], lines[j] = lines[j], lines[i]
    return "".join(lines)


def dump(tree: Tree, flow: bool | None, unicode: bool) -> str:
    return yaml.safe_dump(tree, default_flow_style=flow, allow_unicode=unicode, sort_keys=False, width=100)


@dataclass(frozen=True)
class Case:
    """One generated document: its bytes, the seed it came from and what was done to it."""

    seed: str
    data: bytes
    how: str
    variants: tuple[str, ...] = ()  # the seed's variant names (the mutated file may have lost them)


@st.composite
def documents(draw: st.DrawFn, repo_weight: float = 0.5) -> Case:
    """A hostile scenario document (as bytes), mostly derived from a seed."""
    origin = draw(st.sampled_from(["seed"] * 8 + ["text", "bytes"]))
    if origin == "text":
        return Case("-", draw(st.text(max_size=400)).encode("utf-8", "surrogatepass"), "random text")
    if origin == "bytes":
        return Case("-", draw(st.binary(max_size=400)), "random bytes")
    from_repo = draw(st.floats(0, 1)) < repo_weight
    seed = draw(st.sampled_from(REPO_SEEDS if from_repo else SEEDS))
    steps: list[str] = []
    if seed.data is not None and draw(st.integers(0, 9)) > 0:
        tree = copy.deepcopy(seed.data)
        for _ in range(draw(st.integers(1, 4))):
            tree = draw(mutate_tree(tree))
        flow, unicode = draw(st.sampled_from([None, True, False])), draw(st.booleans())
        try:
            text = dump(tree, flow, unicode)
        except (yaml.YAMLError, UnicodeError, RecursionError):
            text = seed.text
        steps.append("tree")
    else:
        text = seed.text
    for _ in range(draw(st.sampled_from([0, 0, 0, 1, 1, 2, 3]))):
        text = draw(mutate_text(text))
        steps.append("text")
    encoding = draw(st.sampled_from(["utf-8"] * 8 + ["utf-16", "latin-1"]))
    data = text.encode(encoding, "surrogatepass") if encoding != "latin-1" else text.encode("latin-1", "replace")
    variants = seed.data.get("variants") if isinstance(seed.data, dict) else None
    names = tuple(variants) if isinstance(variants, dict) else ()
    return Case(seed.name, data, "+".join(steps) + f" ({encoding})", names)
