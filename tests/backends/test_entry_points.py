"""Engines registered from outside this repository (backends/entry_points.py): an installed distribution's
entry point in the group ``physics_scenarios.backends`` adds a backend beside the built-in ones, without
importing its engine; a broken one is named with its reason, never silently dropped."""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from backends import registry
from backends.entry_points import GROUP, BrokenBackend, registered
from backends.errors import UnknownBackend
from backends.testing.fixtures import available

_MODULE = """
ENTRY = {"name": "tiny", "target": "tiny_adapter:TinyBackend", "module": "numpy", "distribution": "numpy",
         "extra": "", "description": "a test engine", "precision": "float32"}
def make():
    return dict(ENTRY, name="tinycall")
WRONG_NAME = dict(ENTRY, name="someone-else")
BUILTIN = dict(ENTRY, name="fake")
NOT_AN_ENTRY = 42
BAD_TARGET = dict(ENTRY, name="badtarget", target="tiny_adapter.TinyBackend")
ABSENT = dict(ENTRY, name="absent", module="tiny_absent_engine", distribution="tiny-absent-engine")
"""
_POINTS = {
    "tiny": "tiny_registration:ENTRY",
    "tinycall": "tiny_registration:make",
    "missing": "no_such_module_anywhere:ENTRY",
    "other": "tiny_registration:WRONG_NAME",
    "fake": "tiny_registration:BUILTIN",
    "number": "tiny_registration:NOT_AN_ENTRY",
    "badtarget": "tiny_registration:BAD_TARGET",
    "absent": "tiny_registration:ABSENT",
}


@pytest.fixture
def installed(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    """A distribution `tiny-engine` on sys.path: a dist-info with the entry points, and its module."""
    (tmp_path / "tiny_registration.py").write_text(_MODULE)
    info = tmp_path / "tiny_engine-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: tiny-engine\nVersion: 0.1\n")
    lines = "".join(f"{name} = {value}\n" for name, value in _POINTS.items())
    (info / "entry_points.txt").write_text(f"[{GROUP}]\n{lines}")
    monkeypatch.syspath_prepend(str(tmp_path))
    registered.cache_clear()
    yield tmp_path
    registered.cache_clear()


def test_an_entry_point_adds_a_backend_beside_the_built_in_ones(installed: Path) -> None:
    names = [e.name for e in registry.list_backends()]
    assert names[: len(names) - 3] == [e.name for e in registry.list_backends() if not e.package]
    assert names[-3:] == ["absent", "tiny", "tinycall"]  # after the built-in table, sorted
    tiny = registry.entry("tiny")
    assert tiny.package == "tiny-engine" and tiny.precision.value == "float32"
    assert tiny.hint == "pip install numpy"  # the engine's distribution, not an extra of ours
    assert "tiny" in registry.KNOWN_BACKENDS and registry.entry("tinycall").description == "a test engine"
    assert "tiny_adapter" not in sys.modules  # described, not imported


@pytest.mark.parametrize(
    ("name", "reason"),
    [
        ("missing", r"cannot be loaded \(ModuleNotFoundError: No module named 'no_such_module_anywhere'\)"),
        ("other", r"it describes backend `someone-else`, not `other`"),
        ("fake", r"`fake` is the name of a built-in backend"),
        ("number", r"it gives a int, not a BackendEntry"),
        ("badtarget", r"target `tiny_adapter.TinyBackend` is not `module:Class`"),
    ],
)
def test_a_broken_entry_point_is_named_with_its_reason(installed: Path, name: str, reason: str) -> None:
    if name == "fake":  # the built-in stays itself; the clash is reported, not applied
        assert registry.entry("fake").target == "backends.fake:FakeBackend"
        assert reason.replace("\\", "") in registry.broken_backends()["fake"].replace("\\", "")
        return
    with pytest.raises(BrokenBackend, match=reason) as info:
        registry.entry(name)
    assert f"entry point `{name} = {_POINTS[name]}` (group {GROUP}, from tiny-engine)" in str(info.value)
    assert name not in [e.name for e in registry.list_backends(include_hidden=True)]


def test_an_unknown_name_is_still_unknown(installed: Path) -> None:
    with pytest.raises(UnknownBackend, match="Known backends: .*tiny"):
        registry.entry("tinny")


def test_scenario_backends_lists_both_and_the_broken_one(installed: Path) -> None:
    env_path = f"{installed}:{Path(__file__).resolve().parents[2]}"
    done = subprocess.run(
        [sys.executable, "-m", "runner", "backends"], capture_output=True, text=True, timeout=120,
        env={"PYTHONPATH": env_path, "PATH": "/usr/bin:/bin", "COLUMNS": "400"},
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert "tiny" in done.stdout and "a test engine" in done.stdout
    assert "registered but broken" in done.stdout and "no_such_module_anywhere" in done.stdout


def test_the_suite_fails_an_engine_whose_adapter_cannot_be_imported(installed: Path) -> None:
    """`tiny`'s engine (numpy) is installed but its adapter module `tiny_adapter` does not exist: the suite's
    fixture raises that import error (a failed test), where a missing engine distribution skips."""
    with pytest.raises(ModuleNotFoundError, match="tiny_adapter"):
        available("tiny")
    with pytest.raises(pytest.skip.Exception, match="engine not installed: pip install tiny-absent-engine"):
        available("absent")
    with pytest.raises(BrokenBackend, match="no_such_module_anywhere"):
        available("missing")
