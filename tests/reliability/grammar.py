"""A grammar-aware mutator of valid scenarios: it knows the language's keys and types from its JSON Schema
(runner/schema/scenario.schema.json) and the names a document defines, so its mutants stay close to valid
files and reach the checks behind the syntax.

Each mutant starts from a valid scenario (every file under `scenarios/`) and applies one to three structured
mutations, each of a kind that a class of hostile input comes from:

* `value`: a field gets a value generated for its own schema type, biased to edges (limits, zero, huge,
  negative, times as expressions of params or of the state, a name of another kind, a near miss);
* `key`: an object gets one of its schema's optional keys, generated likewise;
* `ref`: a reference becomes another name the document defines (an interval inlining another makes cycles
  through any number of intervals, a joint's body a static one...);
* `name`: a key of a name map (bodies, variants, intervals, params, sounds, triggers...) is renamed: long (up to
  300 characters, as trace file names are built from names), with a NUL or a control character, unicode;
* `text`: a string gets a NUL or a control character, as a YAML escape (`"\\0"`);
* `params`: a long parameter used many times, as a whole value or inside text (substitution blow-up);
* `variant`: a variant sets a dotted path of the document (or one into a list, a scalar, an undeclared
  parameter) to a generated value;
* `special`: a sound points at a FIFO or a socket in the scenario's folder (a reader would block on it);
* `override`: `--set` items a command line could carry (tags, huge integers, escapes, undeclared paths).

Everything is drawn through hypothesis, so a failure shrinks to a small reproducer.
"""

from __future__ import annotations

import copy
import json
from dataclasses import dataclass
from typing import Any

import yaml
from hypothesis import strategies as st

from runner.language.yaml_source import load_yaml
from tests.paths import ROOT
from tests.reliability.hostile import Seed, Tree, get, walk

SCHEMA: dict[str, Any] = json.loads((ROOT / "runner" / "schema" / "scenario.schema.json").read_text())
#: every valid scenario of the repository, conformance suite included
SEED_TEXTS = {p.name: p.read_text() for p in sorted((ROOT / "scenarios").rglob("*.yaml"))}
SEEDS = [Seed(name, text, load_yaml(text, name)[0]) for name, text in SEED_TEXTS.items()]
NAME_MAPS = ("params", "bodies", "joints", "sounds", "state", "intervals", "triggers", "on", "variants")
SPECIAL_FILES = ("pipe.wav", "socket.wav")  # created by the test in the scenario's folder

# ---- the schema ---------------------------------------------------------------------------------------


def resolve(node: dict[str, Any]) -> dict[str, Any]:
    while "$ref" in node:
        node = SCHEMA["$defs"][node["$ref"].rsplit("/", 1)[1]]
    return node


def options(node: dict[str, Any]) -> list[dict[str, Any]]:
    """The concrete alternatives of a schema (anyOf/oneOf flattened, references followed, null left out)."""
    node = resolve(node)
    alternatives = node.get("anyOf") or node.get("oneOf")
    if alternatives:
        return [o for a in alternatives for o in options(a)]
    return [] if node.get("type") == "null" else [node]


def child(node: dict[str, Any], key: str | int, value: Any) -> list[dict[str, Any]]:
    """The schemas the value at ``key`` of a value of schema ``node`` may follow."""
    out: list[dict[str, Any]] = []
    for alt in options(node):
        if isinstance(key, str) and alt.get("type") == "object":
            if key in alt.get("properties", {}):
                out.append(alt["properties"][key])
            elif alt.get("patternProperties"):
                out.extend(alt["patternProperties"].values())
            elif isinstance(alt.get("additionalProperties"), dict):
                out.append(alt["additionalProperties"])
        elif isinstance(key, int) and alt.get("type") == "array":
            prefix = alt.get("prefixItems")
            if prefix and key < len(prefix):
                out.append(prefix[key])
            elif "items" in alt:
                out.append(alt["items"])
    return out


def schema_at(data: Tree, path: tuple[str | int, ...]) -> list[dict[str, Any]]:
    nodes: list[dict[str, Any]] = [SCHEMA]
    value = data
    for part in path:
        nodes = [c for n in nodes for c in child(n, part, value)]
        if isinstance(value, dict):
            value = value.get(part)
        elif isinstance(value, list) and isinstance(part, int) and part < len(value):
            value = value[part]
        else:
            value = None
    return nodes


# ---- values of a schema type, biased to the edges ----------------------------------------------------

EXPRESSIONS = ["param.{p}*2", "duration", "duration/2", "0.99*duration", "dt*3", "sqrt(2*1/g)", "pi/10",
               "box.pos.z", "time", "state.x", "count('start')", "1/0", "max(0, duration - 2)", "-1",
               "duration + 1", "1e300", "param.nope"]  # fmt: skip
LONG = ["x" * 65, "v" * 129, "n" * 300, "é" * 100]


def names_of(data: Tree) -> dict[str, list[str]]:
    """The names a document defines, by kind."""
    out = {kind: list(data.get(kind, {}) or {}) if isinstance(data.get(kind), dict) else [] for kind in NAME_MAPS}
    return out


@st.composite
def value_for(draw: st.DrawFn, nodes: list[dict[str, Any]], data: Tree, depth: int = 0) -> Any:
    """A value for one of ``nodes`` (schemas), mostly of the right kind, often at an edge."""
    alternatives = [o for n in nodes for o in options(n)]
    if not alternatives:
        return draw(st.sampled_from([0, "x", None, [], {}]))
    node = draw(st.sampled_from(alternatives))
    names = names_of(data)
    params = names["params"] or ["p"]
    kind = node.get("type")
    if "const" in node or "enum" in node:
        choices = [node["const"]] if "const" in node else list(node["enum"])
        return draw(st.sampled_from(choices + [str(choices[0]) + "x", str(choices[0]).upper()]))
    if kind in ("number", "integer"):
        lo, hi = node.get("minimum", node.get("exclusiveMinimum")), node.get("maximum")
        edges = [0, 1, -1, 0.5, 1e-300, 1e9, 1e9 + 1, 10**12]
        edges += [lo, lo - 1e-9 if isinstance(lo, float | int) else 0] if lo is not None else []
        edges += [hi, hi * 1.000001] if hi is not None else []
        value = draw(st.sampled_from([e for e in edges if e is not None]))
        return int(value) if kind == "integer" and abs(value) < 1e18 else value
    if kind == "boolean":
        return draw(st.booleans())
    if kind == "string":
        pattern = node.get("pattern", "")
        if pattern.startswith("\\$\\{"):  # a parameter
            return "${" + draw(st.sampled_from(params + ["nope"])) + "}"
        if "expression" in node.get("description", "") or node.get("minLength") == 1 and not pattern:
            return draw(st.sampled_from(EXPRESSIONS)).replace("{p}", draw(st.sampled_from(params)))
        pool = [n for kind_names in names.values() for n in kind_names] + LONG + ["start", "end", "environment"]
        return draw(st.sampled_from(pool))
    if kind == "array":
        prefix = node.get("prefixItems")
        if prefix:
            count = draw(st.sampled_from([len(prefix), len(prefix) - 1, len(prefix) + 1]))
            items = [prefix[min(i, len(prefix) - 1)] for i in range(max(count, 0))]
            return [draw(value_for([s], data, depth + 1)) for s in items]
        if depth > 2:
            return []
        return draw(st.lists(value_for([node.get("items", {})], data, depth + 1), max_size=2))
    if kind == "object" and depth <= 2:
        properties = node.get("properties", {})
        required = node.get("required", [])
        optional = [k for k in properties if k not in required]
        keys = required + draw(st.lists(st.sampled_from(optional), max_size=2, unique=True)) if optional else required
        return {k: draw(value_for([properties[k]], data, depth + 1)) for k in keys}
    return {}


# ---- mutations -----------------------------------------------------------------------------------------


def _paths(data: Tree) -> list[tuple[str | int, ...]]:
    return [p for p in walk(data) if p]


@st.composite
def mutate_value(draw: st.DrawFn, data: Tree) -> str:
    path = draw(st.sampled_from(_paths(data)))
    nodes = schema_at(data, path)
    get(data, path[:-1])[path[-1]] = draw(value_for(nodes, data))
    return f"value {'.'.join(map(str, path))}"


@st.composite
def add_key(draw: st.DrawFn, data: Tree) -> str:
    objects = [p for p in walk(data) if isinstance(get(data, p), dict)]
    path = draw(st.sampled_from(objects))
    keys = sorted({k for n in schema_at(data, path) for o in options(n) for k in o.get("properties", {})})
    missing = [k for k in keys if k not in get(data, path)]
    if not missing:
        return "key (none missing)"
    key = draw(st.sampled_from(missing))
    get(data, path)[key] = draw(value_for(schema_at(data, (*path, key)), data))
    return f"key {'.'.join(map(str, (*path, key)))}"


@st.composite
def cross_ref(draw: st.DrawFn, data: Tree) -> str:
    """A reference becomes another defined name (an `interval:` step, a lerp's body, a joint's bodies...)."""
    names = names_of(data)
    refs = [p for p in walk(data) if p and isinstance(get(data, p), str) and p[-1] in ("interval", "body", "start",
            "pause", "resume", "finish", "loop", "sound", "play_sound", "reset", "send", "event", "joint")]  # fmt: skip
    intervals = names["intervals"]
    if intervals and draw(st.booleans()):  # intervals inlining each other in a ring: cycles through 1 to 3
        size = draw(st.integers(min(2, len(intervals)), min(3, len(intervals))))  # 1: a self-reference
        ring = draw(st.lists(st.sampled_from(intervals), min_size=size, max_size=size, unique=True))
        for source, target in zip(ring, ring[1:] + ring[:1], strict=True):
            step = data["intervals"][source]
            kind = next((k for k in ("sequence", "parallel") if isinstance(step, dict)
                         and isinstance(step.get(k), list)), None)  # fmt: skip
            if kind is not None:
                step[kind].append({"interval": target})
            else:
                data["intervals"][source] = {"sequence": [step, {"interval": target}]}
        return f"ref interval ring {' -> '.join(ring)}"
    if not refs:
        return "ref (none)"
    path = draw(st.sampled_from(refs))
    pool = [n for kind_names in names.values() for n in kind_names] or ["x"]
    get(data, path[:-1])[path[-1]] = draw(st.sampled_from(pool))
    return f"ref {'.'.join(map(str, path))}"


@st.composite
def rename(draw: st.DrawFn, data: Tree) -> str:
    maps = [k for k in NAME_MAPS if isinstance(data.get(k), dict) and data[k]]
    if not maps:
        return "name (no map)"
    kind = draw(st.sampled_from(maps))
    old = draw(st.sampled_from(list(data[kind])))
    new = draw(st.sampled_from([*LONG, old + "\x00", old + "\x07", "_" + old, old + "-" + "ü" * 3, old * 5]))
    data[kind] = {(new if k == old else k): v for k, v in data[kind].items()}
    return f"name {kind}.{old}"


@st.composite
def control_text(draw: st.DrawFn, data: Tree) -> str:
    strings = [p for p in walk(data) if p and isinstance(get(data, p), str)]
    if not strings:
        return "text (none)"
    path = draw(st.sampled_from(strings))
    value = get(data, path)
    char = draw(st.sampled_from(["\x00", "\x07", "\x1b", "\x7f", "\x0b"]))
    at = draw(st.integers(0, len(value)))
    get(data, path[:-1])[path[-1]] = value[:at] + char + value[at:]
    return f"text {'.'.join(map(str, path))}"


@st.composite
def param_bomb(draw: st.DrawFn, data: Tree) -> str:
    size = draw(st.sampled_from([10, 1_000, 10_000, 100_000]))
    uses = draw(st.sampled_from([1, 100, 5_000, 50_000]))
    data.setdefault("params", {})
    if not isinstance(data["params"], dict):
        data["params"] = {}
    data["params"]["big"] = "y" * size
    if draw(st.booleans()):
        data["description"] = "${big}" * uses
    else:
        data["notes"] = ["${big}"] * uses
    return f"params {size} x {uses}"


@st.composite
def variant_set(draw: st.DrawFn, data: Tree) -> str:
    paths = [p for p in walk(data) if p and p[0] not in ("variants",) and all(isinstance(x, str | int) for x in p)]
    dotted = [".".join(map(str, p)) for p in paths] + ["params.nope", "world.dt.x", "bodies.nope.pos",
                                                        "inputs.99.at", "assertions.0.name.x"]  # fmt: skip
    key = draw(st.sampled_from(dotted))
    value = draw(value_for(schema_at(data, tuple(int(k) if k.isdigit() else k for k in key.split("."))), data))
    variants = data.setdefault("variants", {})
    if not isinstance(variants, dict):
        data["variants"] = variants = {}
    variants["fuzz"] = {"set": {key: value}}
    return f"variant set {key}"


@st.composite
def special_sound(draw: st.DrawFn, data: Tree) -> str:
    data["sounds"] = dict(data.get("sounds") or {}) if isinstance(data.get("sounds"), dict) else {}
    data["sounds"]["special"] = draw(st.sampled_from(SPECIAL_FILES))
    return "special sound"


MUTATIONS = {
    "value": mutate_value, "key": add_key, "ref": cross_ref, "name": rename, "text": control_text,
    "params": param_bomb, "variant": variant_set, "special": special_sound,
}  # fmt: skip
OVERRIDES = [
    "world.dt=!!float abc", "params.count=" + "9" * 5000, "description=!!binary aGVsbG8=", "description=!!set {a}",
    "description=!!timestamp 2001-12-14", 'description="a\\0b"', "params.nope=1", "world.dtt=0.1",
    "world=[1, 0, 0]", "bodies.nope.pos=[0, 0, 1]", "inputs.0.at=1e9", "world.duration=0.01",
    "assertions.0.at=duration*2", "variants.x.set={}", "description=" + "x" * 2000,
]  # fmt: skip


@dataclass(frozen=True)
class Mutant:
    seed: str
    data: bytes
    how: str
    overrides: tuple[str, ...]
    variants: tuple[str, ...]


def dump(tree: Tree) -> str:
    return yaml.safe_dump(tree, default_flow_style=None, allow_unicode=False, sort_keys=False, width=100)


@st.composite
def mutants(draw: st.DrawFn) -> Mutant:
    seed = draw(st.sampled_from(SEEDS))
    data = copy.deepcopy(seed.data)
    how = [draw(MUTATIONS[draw(st.sampled_from(sorted(MUTATIONS)))](data)) for _ in range(draw(st.integers(1, 3)))]
    overrides = tuple(draw(st.lists(st.sampled_from(OVERRIDES), max_size=1)))
    variants = data.get("variants")
    names = tuple(variants) if isinstance(variants, dict) else ()
    try:
        text = dump(data)
    except (yaml.YAMLError, RecursionError):
        text = seed.text
    return Mutant(seed.name, text.encode("utf-8", "surrogatepass"), "; ".join(how), overrides, names)
