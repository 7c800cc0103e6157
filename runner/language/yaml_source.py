"""Safe YAML loading that remembers where every value came from.

``load_yaml`` returns plain Python data plus a :class:`Positions` map from a field path (a tuple of keys
and list indices) to its (line, column), so every later error can name file:line:column. Only YAML's
safe types are built (no object tags); duplicate keys, non-string keys and alias bombs are refused.
"""

from __future__ import annotations

import re
from collections.abc import MutableMapping
from dataclasses import dataclass, field
from typing import Any

import yaml

from runner.errors import Issue, ScenarioValidationError

Path = tuple[str | int, ...]

MAX_FILE_BYTES = 1_000_000
MAX_NODES = 200_000  # values built, counting every alias expansion (a "billion laughs" stops here)
MAX_DEPTH = 64
#: Characters of text (keys and values) the loaded document may hold, every alias use and every `${param}`
#: substitution counted: later stages copy and check text per use, so memory follows this, not the file size.
MAX_TEXT = 4_000_000
COMMAND_LINE = "<command line>"


@dataclass
class Positions:
    """Field path -> (line, column), 1-based; keys are located at the key, values at the value."""

    file: str
    values: MutableMapping[Path, tuple[int, int]] = field(default_factory=dict)
    keys: MutableMapping[Path, tuple[int, int]] = field(default_factory=dict)
    #: paths whose value came from the command line (`--set`), with the argument; issues there name it
    overridden: dict[Path, str] = field(default_factory=dict)
    #: characters of text in the document as built (aliases expanded); see MAX_TEXT
    text_size: int = 0

    def locate(self, path: Path, at_key: bool = False) -> tuple[int, int]:
        table = self.keys if at_key else self.values
        probe = tuple(path)
        while probe:
            if probe in table:
                return table[probe]
            if probe in self.values:
                return self.values[probe]
            probe = probe[:-1]
        return self.values.get((), (1, 1))

    def issue(self, path: Path, message: str, at_key: bool = False) -> Issue:
        for i in range(len(path), 0, -1):
            argument = self.overridden.get(tuple(path[:i]))
            if argument is not None:
                field = format_path(path)
                where = "" if i == len(path) else f"{field}: "
                return Issue(COMMAND_LINE, 0, 0, argument, where + message)
        line, col = self.locate(path, at_key)
        return Issue(self.file, line, col, format_path(path), message)

    def remap(self, src: Path, dst: Path, value: Any) -> None:
        """Make the positions under ``src``, where the document holds ``value``, also answer for ``dst``
        (variants merged into the base). Only the paths of ``value`` are visited, so merging a variant costs
        its own size, not the file's."""
        for sub in _subpaths(value):
            for table in (self.values, self.keys):
                pos = table.get(src + sub)
                if pos is not None:
                    table[dst + sub] = pos


def _subpaths(value: Any) -> list[Path]:
    """The paths inside ``value`` (``()`` for itself), depth first."""
    out: list[Path] = [()]
    stack: list[tuple[Path, Any]] = [((), value)]
    while stack:
        prefix, node = stack.pop()
        items = node.items() if isinstance(node, dict) else enumerate(node) if isinstance(node, list) else ()
        for key, child in items:
            out.append(prefix + (key,))
            stack.append((prefix + (key,), child))
    return out


def format_path(path: Path) -> str:
    out = ""
    for part in path:
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else str(part))
    return out


_PLAIN_TAGS = frozenset({"tag:yaml.org,2002:map", "tag:yaml.org,2002:seq"})
_SCALAR_TAGS = frozenset(f"tag:yaml.org,2002:{t}" for t in ("str", "int", "float", "bool", "null"))


class _Builder:
    def __init__(self, file: str, loader: _Loader) -> None:
        self.file = file
        self.loader = loader
        self.positions = Positions(file)
        self.count = 0
        self.text = 0

    def fail(self, node: yaml.Node, path: Path, message: str) -> ScenarioValidationError:
        mark = node.start_mark
        return ScenarioValidationError([Issue(self.file, mark.line + 1, mark.column + 1, format_path(path), message)])

    def build(self, node: yaml.Node, path: Path) -> Any:
        self.count += 1
        if self.count > MAX_NODES:
            raise self.fail(
                node, path, f"the document expands to more than {MAX_NODES} values (an alias bomb?); refused"
            )
        if len(path) > MAX_DEPTH:
            raise self.fail(node, path, f"nesting deeper than {MAX_DEPTH} levels; refused")
        self.positions.values.setdefault(path, (node.start_mark.line + 1, node.start_mark.column + 1))
        if isinstance(node, yaml.MappingNode | yaml.SequenceNode) and node.tag not in _PLAIN_TAGS:
            raise self.fail(node, path, f"unsupported YAML tag {node.tag!r} (only plain data is allowed)")
        if isinstance(node, yaml.MappingNode):
            self.loader.flatten_mapping(node)
            out: dict[str, Any] = {}
            for key_node, value_node in node.value:
                if not isinstance(key_node, yaml.ScalarNode):
                    raise self.fail(key_node, path, "expected a plain key, found a complex key")
                key = self.scalar(key_node, path)
                if not isinstance(key, str):
                    key = str(key) if isinstance(key, int | float | bool) and key_node.style is None else key
                    if not isinstance(key, str):
                        raise self.fail(key_node, path, f"expected a text key, found {key!r}")
                if key in out:
                    raise self.fail(key_node, path + (key,), f"duplicate key `{key}`")
                self.positions.keys[path + (key,)] = (key_node.start_mark.line + 1, key_node.start_mark.column + 1)
                out[key] = self.build(value_node, path + (key,))
            return out
        if isinstance(node, yaml.SequenceNode):
            return [self.build(item, path + (i,)) for i, item in enumerate(node.value)]
        if isinstance(node, yaml.ScalarNode):
            return self.scalar(node, path)
        raise self.fail(node, path, "unsupported YAML node")  # pragma: no cover

    def scalar(self, node: yaml.ScalarNode, path: Path) -> Any:
        if node.tag not in _SCALAR_TAGS:
            raise self.fail(node, path, f"unsupported YAML tag {node.tag!r} (only plain data is allowed)")
        self.text += len(node.value)
        self.positions.text_size = self.text
        if self.text > MAX_TEXT:
            message = f"the document holds more than {MAX_TEXT} characters of text, aliases expanded; refused"
            raise self.fail(node, path, message)
        control = _CONTROL.search(node.value)
        if control is not None:  # an escape in a quoted scalar ("\0", "\a"): the reader saw only its text
            char = ord(control.group())
            name = "a NUL character" if char == 0 else f"the control character #x{char:02x}"
            raise self.fail(node, path, f"{name} in text (written as an escape); control characters are refused")
        try:
            return self.loader.construct_object(node)
        except (yaml.constructor.ConstructorError, ValueError, ArithmeticError, KeyError) as exc:
            # `!!int abc`, `!!bool maybe`, an integer past Python's 4300-digit conversion limit...
            problem = exc.problem if isinstance(exc, yaml.constructor.ConstructorError) else exc
            if "integer string conversion" in str(problem):
                problem = f"an integer of {sum(c.isdigit() for c in node.value)} digits; at most 4300 are read"
            raise self.fail(node, path, f"unsupported YAML value ({problem})") from None


#: C0 control characters other than tab, line feed and carriage return (what YAML's reader refuses as text)
_CONTROL = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\x7f]")


class _Loader(yaml.SafeLoader):
    """SafeLoader with YAML 1.2 booleans: only true/false, so `on:` (the handlers key) stays a string."""


_Loader.yaml_implicit_resolvers = {
    first: [(tag, regexp) for tag, regexp in resolvers if tag != "tag:yaml.org,2002:bool"]
    for first, resolvers in yaml.SafeLoader.yaml_implicit_resolvers.items()
}
_Loader.add_implicit_resolver(
    "tag:yaml.org,2002:bool", re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$"), list("tTfF")
)


_BREAK = re.compile("\r\n|[\r\n\x85\u2028\u2029]")  # YAML's line breaks


def line_col(text: str, index: int) -> tuple[int, int]:
    """1-based line and column of character ``index`` of ``text``, counting lines as YAML does."""
    line, start = 1, 0
    for match in _BREAK.finditer(text, 0, index):
        line, start = line + 1, match.end()
    return line, index - start + 1


def load_yaml(text: str, file: str) -> tuple[Any, Positions]:
    """Parse ``text`` safely; raise :class:`ScenarioValidationError` with a location on any problem."""
    size = len(text.encode("utf-8", "surrogatepass"))
    if size > MAX_FILE_BYTES:
        line, col = line_col(
            text, len(text.encode("utf-8", "surrogatepass")[:MAX_FILE_BYTES].decode("utf-8", "ignore"))
        )
        message = f"file larger than {MAX_FILE_BYTES} bytes ({size} bytes; the limit is crossed here); refused"
        raise ScenarioValidationError([Issue(file, line, col, "", message)])
    try:
        loader = _Loader(text)
    except yaml.reader.ReaderError as exc:  # a control character: PyYAML checks the whole text up front
        line, col = line_col(text, exc.position)
        message = f"invalid YAML: character #x{exc.character:04x} is not allowed (control characters are refused)"
        raise ScenarioValidationError([Issue(file, line, col, "", message)]) from None
    try:
        node = loader.get_single_node()
        if node is None:
            raise ScenarioValidationError([Issue(file, 1, 1, "", "expected a scenario mapping, found an empty file")])
        builder = _Builder(file, loader)
        data = builder.build(node, ())
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        line, col = (mark.line + 1, mark.column + 1) if mark else (0, 0)
        problem = exc.problem or exc.context or "invalid YAML"
        raise ScenarioValidationError([Issue(file, line, col, "", f"invalid YAML: {problem}")]) from None
    except yaml.YAMLError as exc:
        raise ScenarioValidationError([Issue(file, 0, 0, "", f"invalid YAML: {exc}")]) from None
    except RecursionError:
        mark = loader.get_mark()
        message = f"nesting deeper than {MAX_DEPTH} levels; refused"
        raise ScenarioValidationError([Issue(file, mark.line + 1, mark.column + 1, "", message)]) from None
    finally:
        loader.dispose()
    return data, builder.positions


def load_value(text: str) -> Any:
    """A command-line value (`--set key=value`): a YAML scalar or flow collection, plain data only, with the
    document's limits. Text that is not valid YAML stays text; anything refused raises :class:`ValueError`
    with the reason (the caller names the argument)."""
    if len(text) > MAX_FILE_BYTES:
        raise ValueError(f"a value longer than {MAX_FILE_BYTES} characters; refused")
    if not text.strip():
        return ""
    try:
        loader = _Loader(text)
    except yaml.reader.ReaderError as exc:
        raise ValueError(f"character #x{exc.character:04x} is not allowed (control characters are refused)") from None
    try:
        node = loader.get_single_node()
        return "" if node is None else _Builder(COMMAND_LINE, loader).build(node, ())
    except ScenarioValidationError as exc:
        raise ValueError(exc.issues[0].message) from None
    except yaml.YAMLError:
        return text  # not YAML (`a: b: c`, `x[`): the text itself
    except RecursionError:
        raise ValueError(f"nesting deeper than {MAX_DEPTH} levels; refused") from None
    finally:
        loader.dispose()
