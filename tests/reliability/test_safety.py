"""Safe by construction: nothing in a scenario runs code, builds objects or reads outside its folder.

* the expression grammar refuses attribute escapes, calls outside the whitelist and dunder names, also
  in the spellings tests/language/test_expressions.py does not try (unicode look-alikes, starred and
  generator arguments, names passed to the runner's own functions);
* no ``eval``/``exec``/``compile``/``__import__``/pickle/unsafe YAML anywhere in the package (an AST
  scan), and a scenario that tries to run ``touch`` through YAML tags, expressions or ``--set`` leaves
  no file behind;
* YAML tags other than plain data are refused, and alias bombs (nested and through merge keys) are
  refused quickly;
* a sound path escaping the scenario's folder is refused: ``..``, absolute, a symlinked file and a
  symlinked folder.
"""

from __future__ import annotations

import ast
import struct
import subprocess
import sys
import time
import wave
from pathlib import Path

import pytest

from runner.errors import ScenarioValidationError
from runner.language.expressions import ExpressionError, compile_expression
from runner.language.load import load_scenario

from .hostile import ROOT

SMALL = """\
schema_version: 1
scenario: t
world: {dt: 0.04, duration: 0.2}
bodies:
  box: {box: [0.3, 0.3, 0.3], density: 500, pos: [0, 0, 1]}
  door: {box: [2, 2, 0.1], density: 1000, pos: [0, 0, 0]}
"""


def write(folder: Path, text: str, name: str = "t.yaml") -> Path:
    path = folder / name
    path.write_text(text)
    return path


def refusal(path: Path) -> list[str]:
    with pytest.raises(ScenarioValidationError) as info:
        load_scenario(path, None)
    return [str(issue) for issue in info.value.issues]


# ---- the expression grammar -------------------------------------------------------------------------


@pytest.mark.parametrize(
    "text,message",
    [
        ("\uff45\uff56\uff41\uff4c('1')", "unknown function `eval`"),  # fullwidth letters: NFKC makes `eval`
        ("\uff3f_import__('os')", "syntax error"),  # a fullwidth low line cannot start a name
        ("box.\uff3f_class__", "syntax error"),
        ("\u0435val('1')", "unknown function `\u0435val`"),  # Cyrillic e: a different name, unknown
        ("__builtins__", "underscore"),
        ("state.__dict__", "underscore"),
        ("param.__class__.__mro__", "underscore"),
        ("abs(*x)", "`Starred` is not allowed"),
        ("sum(v for v in x)", "`GeneratorExp` is not allowed"),
        ("max(x, key=abs)", "only plain calls"),
        ("(lambda: 1)()", "only plain calls"),
        ("abs.__self__", "underscore"),
        ("'%s'.format(1)", "only plain calls"),
        ("b'\\x00'", "not allowed"),
        ("...", "not allowed"),
        ("{1, 2}", "`Set` is not allowed"),
        ("x if True else (y := 2)", "`NamedExpr` is not allowed"),
        ("(" * 5000 + "1" + ")" * 5000, "longer than"),
        ("-" * 1990 + "1", "expression too long"),
    ],
)
def test_grammar_refuses_escapes(text: str, message: str) -> None:
    with pytest.raises(ExpressionError) as info:
        compile_expression(text)
    assert message in str(info.value)


@pytest.mark.parametrize("text", ["contact(__import__, os)", "playing(__class__)", "count(_private)"])
def test_runner_function_arguments_follow_the_name_rules(text: str) -> None:
    """The runner's functions take names as literals; the underscore rule holds for them too."""
    with pytest.raises(ExpressionError, match="underscore"):
        compile_expression(text)


# ---- nothing runs user text -------------------------------------------------------------------------

FORBIDDEN_CALLS = {"eval", "exec", "compile", "__import__", "breakpoint", "input", "execfile"}
FORBIDDEN_ATTRS = {
    ("yaml", "load"), ("yaml", "unsafe_load"), ("yaml", "full_load"), ("yaml", "load_all"), ("yaml", "Loader"),
    ("yaml", "UnsafeLoader"), ("yaml", "FullLoader"), ("pickle", "loads"), ("pickle", "load"),
    ("marshal", "loads"), ("os", "system"), ("os", "popen"), ("os", "execv"), ("os", "execvp"),
}  # fmt: skip
SUBPROCESS = {"run", "Popen", "call", "check_call", "check_output", "getoutput", "getstatusoutput"}
#: The only dynamic imports: command modules found in runner/commands and the backend table's targets.
ALLOWED_IMPORT_MODULE = {"runner/cli/main.py", "backends/registry.py"}


def _own_python_module(call: ast.Call, lists: dict[str, ast.List]) -> bool:
    """``subprocess.X([sys.executable, "-m", "runner...", ...])`` without a shell: the tool starting itself.
    ``lists``: the file's ``name = [...]`` assignments, for an argv built beforehand."""
    first = call.args[0] if call.args else None
    if isinstance(first, ast.Name):
        first = lists.get(first.id)
    if any(k.arg == "shell" for k in call.keywords) or not isinstance(first, ast.List):
        return False
    argv = first.elts
    return (
        len(argv) >= 3
        and ast.unparse(argv[0]) == "sys.executable"
        and isinstance(argv[1], ast.Constant) and argv[1].value == "-m"
        and isinstance(argv[2], ast.Constant) and str(argv[2].value).startswith(("runner.", "backends."))
    )  # fmt: skip


def package_sources() -> list[Path]:
    return sorted(p for top in ("runner", "backends", "reports") for p in (ROOT / top).rglob("*.py"))


def test_no_eval_exec_or_unsafe_loading_anywhere_in_the_package() -> None:
    found = []
    for path in package_sources():
        rel = path.relative_to(ROOT).as_posix()
        tree = ast.parse(path.read_text(), rel)
        lists = {
            n.targets[0].id: n.value
            for n in ast.walk(tree)
            if isinstance(n, ast.Assign) and isinstance(n.targets[0], ast.Name) and isinstance(n.value, ast.List)
        }
        for node in ast.walk(tree):
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in FORBIDDEN_CALLS:
                found.append(f"{rel}:{node.lineno}: {node.func.id}()")
            if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name):
                pair = (node.value.id, node.attr)
                if pair in FORBIDDEN_ATTRS:
                    found.append(f"{rel}:{node.lineno}: {pair[0]}.{pair[1]}")
                if pair == ("importlib", "import_module") and rel not in ALLOWED_IMPORT_MODULE:
                    found.append(f"{rel}:{node.lineno}: importlib.import_module")
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute):
                if ast.unparse(node.func.value) == "subprocess" and node.func.attr in SUBPROCESS:
                    if not _own_python_module(node, lists):
                        found.append(f"{rel}:{node.lineno}: {ast.unparse(node.func)}(...) not of the tool itself")
            if isinstance(node, ast.ImportFrom) and node.module in ("pickle", "marshal", "subprocess"):
                found.append(f"{rel}:{node.lineno}: from {node.module} import ...")
    assert len(package_sources()) > 50  # the scan saw the package
    assert found == []


def test_a_scenario_that_tries_to_run_a_command_runs_nothing(tmp_path: Path) -> None:
    """YAML tags, expressions and a --set value each try to `touch` a file; none may exist afterwards."""
    marker = tmp_path / "pwned"
    attempts = {
        "tag.yaml": SMALL + f"x: !!python/object/apply:os.system ['touch {marker}']\n",
        "name.yaml": SMALL + "y: !!python/name:os.system\n",
        "expr.yaml": SMALL
        + f"assertions:\n  - name: a\n    at: end\n    check: __import__('os').system('touch {marker}')\n",
        "calc.yaml": SMALL + 'state: {s: 0}\non:\n  start: [{calc: {s: "().__class__.__bases__[0]"}}]\n',
    }
    cli = [sys.executable, "-m", "runner"]
    for name, text in attempts.items():
        path = write(tmp_path, text, name)
        done = subprocess.run([*cli, "run", str(path), "--backend", "fake", "--no-trace"], capture_output=True,
                              text=True, cwd=tmp_path, timeout=120)  # fmt: skip
        assert done.returncode == 2 and "Traceback" not in done.stderr, (name, done.stderr)
    ok = write(tmp_path, SMALL + "assertions:\n  - {name: a, at: end, check: time > 0}\n", "ok.yaml")
    override = f"description=!!python/object/apply:os.system ['touch {marker}']"
    done = subprocess.run([*cli, "run", str(ok), "--backend", "fake", "--no-trace", "--set", override],
                          capture_output=True, text=True, cwd=tmp_path, timeout=120)  # fmt: skip
    assert done.returncode == 2, done.stderr  # a tag is refused on the command line as in a file, naming it
    assert "error: <command line>: --set description=!!python/object" in done.stderr
    assert "unsupported YAML tag" in done.stderr and "Traceback" not in done.stderr
    assert not marker.exists()


# ---- YAML -------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "snippet",
    [
        "x: !!python/object/apply:os.system ['true']",
        "x: !!python/object/new:dict {}",
        "x: !!python/name:os.system",
        "x: !!python/module:os",
        "x: !!set {a, b}",
        "x: !!omap [a: 1]",
        "x: !custom {a: 1}",
        "x: !custom 1",
        "x: !!binary aGVsbG8=",
        "x: !!timestamp 2001-12-140",
        "x: !!float abc",
        "x: !!bool maybe",
    ],
)
def test_yaml_tags_beyond_plain_data_are_refused_with_a_location(tmp_path: Path, snippet: str) -> None:
    issues = refusal(write(tmp_path, SMALL + snippet.replace("x:", "description:") + "\n"))
    assert any(i.startswith(f"{tmp_path / 't.yaml'}:7:") and "YAML" in i for i in issues), issues


BOMB = "a0: &a0 [x, x, x, x, x, x, x, x, x, x]\n" + "".join(
    f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 10) + "]\n" for i in range(1, 9)
)  # 10**9 values once expanded
MERGE_BOMB = "m0: &m0 {k0: 1, k1: 1, k2: 1, k3: 1, k4: 1, k5: 1, k6: 1, k7: 1, k8: 1, k9: 1}\n" + "".join(
    f"m{i}: &m{i} [" + ", ".join([f"*m{i - 1}"] * 10) + "]\n" for i in range(1, 8)
)


@pytest.mark.parametrize("bomb", [BOMB, MERGE_BOMB], ids=["nested aliases", "aliases of mappings"])
def test_alias_bombs_are_refused_quickly(tmp_path: Path, bomb: str) -> None:
    path = write(tmp_path, SMALL + bomb)
    start = time.perf_counter()
    issues = refusal(path)
    assert time.perf_counter() - start < 5.0
    assert any("alias bomb" in i for i in issues), issues


# ---- files referenced by a scenario -------------------------------------------------------------


def wav(path: Path, seconds: float = 0.1, rate: int = 8000) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    with wave.open(str(path), "wb") as w:
        w.setnchannels(1)
        w.setsampwidth(1)
        w.setframerate(rate)
        w.writeframes(b"\x80" * int(seconds * rate))
    return path


def sound_scenario(folder: Path, ref: str) -> Path:
    return write(folder, SMALL + f"sounds:\n  bang: {ref!r}\non:\n  start: [{{play_sound: bang}}]\n")


@pytest.fixture
def layout(tmp_path: Path) -> tuple[Path, Path]:
    """``tmp/scenario/`` (the scenario's folder, with sounds/ok.wav) and ``tmp/outside/secret.wav``."""
    folder = tmp_path / "scenario"
    wav(folder / "sounds" / "ok.wav")
    secret = wav(tmp_path / "outside" / "secret.wav")
    return folder, secret


def test_a_sound_inside_the_folder_is_accepted(layout: tuple[Path, Path]) -> None:
    folder, _ = layout
    loaded = load_scenario(sound_scenario(folder, "sounds/ok.wav"), None)
    assert loaded.model.sounds == {"bang": "sounds/ok.wav"}


@pytest.mark.parametrize("kind", ["dot-dot", "absolute", "symlinked file", "symlinked folder", "dot-dot inside"])
def test_a_sound_escaping_the_folder_is_refused(layout: tuple[Path, Path], kind: str) -> None:
    folder, secret = layout
    if kind == "dot-dot":
        ref = "../outside/secret.wav"
    elif kind == "absolute":
        ref = str(secret)
    elif kind == "symlinked file":
        (folder / "sounds" / "link.wav").symlink_to(secret)
        ref = "sounds/link.wav"
    elif kind == "symlinked folder":
        (folder / "more").symlink_to(secret.parent, target_is_directory=True)
        ref = "more/secret.wav"
    else:
        ref = "sounds/../../outside/secret.wav"
    issues = refusal(sound_scenario(folder, ref))
    assert any(":8:" in i and "must be inside the scenario's folder" in i for i in issues), issues


def test_the_refusal_does_not_depend_on_the_working_directory(layout: tuple[Path, Path], tmp_path: Path) -> None:
    folder, _ = layout
    path = sound_scenario(folder, "../outside/secret.wav")
    elsewhere = tmp_path / "outside"
    done = subprocess.run([sys.executable, "-m", "runner", "validate", str(path)], capture_output=True, text=True,
                          cwd=elsewhere, timeout=120)  # fmt: skip
    assert done.returncode == 2 and "must be inside the scenario's folder" in done.stderr
    assert "Traceback" not in done.stderr


@pytest.mark.parametrize("kind", ["rate 0", "symlink loop"])
def test_a_sound_that_cannot_be_played_is_refused_located(layout: tuple[Path, Path], kind: str) -> None:
    """A WAV with a sample rate of 0 passed `validate` and made `compare` exit 70 (dividing by the rate); a
    sound that is a symlink loop raised RuntimeError from Path.resolve (exit 70)."""
    folder, _ = layout
    if kind == "rate 0":
        data = bytearray(wav(folder / "sounds" / "zero.wav").read_bytes())
        assert data[12:16] == b"fmt " and struct.unpack_from("<I", data, 24)[0] == 8000  # the fmt chunk's rate
        struct.pack_into("<II", data, 24, 0, 0)  # sample rate and byte rate
        (folder / "sounds" / "zero.wav").write_bytes(bytes(data))
        ref, expected = "sounds/zero.wav", "sample rate of 0 Hz"
    else:
        (folder / "sounds" / "a.wav").symlink_to(folder / "sounds" / "b.wav")
        (folder / "sounds" / "b.wav").symlink_to(folder / "sounds" / "a.wav")
        ref, expected = "sounds/a.wav", "cannot follow its path"
    issues = refusal(sound_scenario(folder, ref))
    assert any(":8:" in i and expected in i for i in issues), issues
    done = subprocess.run([sys.executable, "-m", "runner", "validate", str(folder / "t.yaml")], capture_output=True,
                          text=True, timeout=120)  # fmt: skip
    assert done.returncode == 2 and expected in done.stderr and "Traceback" not in done.stderr, done.stderr
