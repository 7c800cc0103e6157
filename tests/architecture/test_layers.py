"""The house rules of docs/architecture.md, checked on the source: no import cycles, data flowing one way
(language -> compile -> sim -> trace; reports read traces only; backends know nothing of the runner), and
only an engine's own adapter importing that engine."""

from __future__ import annotations

from pathlib import Path

import pytest

from backends.registry import KNOWN_BACKENDS
from tests.architecture.imports import cycles, external_imports, graph, modules

GRAPH = graph()

#: For each stage of the runner, the stages it must never import (directly or lazily).
FORBIDDEN = {
    "runner.language": ("runner.compile", "runner.sim", "runner.trace", "runner.exec", "runner.ci", "runner.cli",
                        "runner.conformance", "reports"),
    "runner.compile": ("runner.sim", "runner.trace", "runner.exec", "runner.ci", "runner.cli", "runner.conformance",
                       "reports"),
    "runner.sim": ("runner.exec", "runner.ci", "runner.cli", "runner.conformance"),
    "runner.trace": ("runner.language", "runner.compile", "runner.sim", "runner.exec", "runner.ci", "runner.cli",
                     "runner.conformance"),
    "runner.exec": ("runner.ci", "runner.cli"),
    "runner.ci": ("runner.cli", "runner.conformance"),  # it runs cases through runner.exec, as every command does
    "backends": ("runner", "reports"),
    "reports": ("runner",),
    "runner.view": ("runner.exec", "runner.ci", "runner.conformance", "runner.cli"),
}  # fmt: skip

#: Engine modules, imported only inside their own adapter package.
#: engine import -> the adapter packages that may import it (MuJoCo Warp's adapter builds MuJoCo's model; Warp is
#: the device layer of both MuJoCo Warp and Newton)
ENGINES = {"pybullet": ("backends.pybullet",), "pybullet_data": ("backends.pybullet",),
           "mujoco": ("backends.mujoco", "backends.mujoco_warp"), "mujoco_warp": ("backends.mujoco_warp",),
           "warp": ("backends.mujoco_warp", "backends.newton"), "newton": ("backends.newton",),
           "dartpy": ("backends.dart",), "panda3d": ("backends.ode",), "direct": ("backends.ode",)}  # fmt: skip


def test_there_is_no_import_cycle() -> None:
    found = cycles(GRAPH)
    assert not found, "import cycles (each list imports itself through the others): " + "; ".join(map(str, found))


def test_the_graph_sees_lazy_imports() -> None:
    """A function-level import counts as an edge too (a cycle hidden in a function is still a cycle)."""
    assert "runner.trace.writer" in GRAPH["runner.sim.run"]  # imported inside run_loaded


def _in(module: str, package: str) -> bool:
    return module == package or module.startswith(package + ".")


@pytest.mark.parametrize("stage", sorted(FORBIDDEN))
def test_stages_import_only_what_comes_before_them(stage: str) -> None:
    wrong = sorted(
        f"{a} -> {b}"
        for a, targets in GRAPH.items()
        if _in(a, stage)
        for b in targets
        for banned in FORBIDDEN[stage]
        if _in(b, banned)
    )
    assert not wrong, f"{stage} imports a later stage: " + ", ".join(wrong)


#: Panda3D is also the renderer of the report's pictures and of `scenario view`'s window: reports.scene3d and
#: runner.view may import its rendering and display modules (panda3d.core, direct.showbase, direct.gui), never its
#: physics (panda3d.ode).
RENDERERS = {"panda3d": ("reports.scene3d", "runner.view"), "direct": ("runner.view",)}
#: MuJoCo's compiler is also the MJCF reader of the language (runner.language.mjcf: MJCF's semantics are
#: MuJoCo's; docs/robots.md): that module may import mujoco to *parse*, never to simulate (no mj_step).
PARSERS = {"mujoco": ("runner.language.mjcf",)}


def _full_imports(path: object) -> set[str]:
    import ast
    from pathlib import Path

    tree = ast.parse(Path(str(path)).read_text(encoding="utf-8"))
    out: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom) and not node.level and node.module:
            out.add(node.module)
    return out


def test_only_an_engines_adapter_imports_the_engine() -> None:
    wrong = []
    for name, path in modules().items():
        for engine in external_imports(name, path) & set(ENGINES):
            if any(_in(name, adapter) for adapter in ENGINES[engine]):
                continue
            if any(_in(name, p) for p in PARSERS.get(engine, ())) and "mj_step" not in Path(str(path)).read_text():
                continue
            renderers = RENDERERS.get(engine, ())
            if any(_in(name, r) for r in renderers) and not any(
                m.startswith("panda3d.ode") for m in _full_imports(path)
            ):
                continue
            wrong.append(f"{name} imports {engine}")
    assert not wrong, ", ".join(wrong)


def test_no_stage_of_a_run_imports_the_viewer() -> None:
    """runner.view drives runs; the stages it drives (and reports) never import it."""
    wrong = sorted(
        f"{a} -> {b}"
        for a, targets in GRAPH.items()
        if not _in(a, "runner.view") and not _in(a, "runner.cli")
        for b in targets
        if _in(b, "runner.view")
    )
    assert not wrong, ", ".join(wrong)


def test_engine_names_are_written_only_in_the_registry() -> None:
    """Outside backends/ (the adapters, the registry) no module of the runner spells an engine's registry name
    as a string literal: the registry is the one place that knows them."""
    import ast

    names = {n for n, e in KNOWN_BACKENDS.items() if not e.hidden}
    wrong = []
    parsers = {m for ms in PARSERS.values() for m in ms}  # there `mujoco` is MJCF's root element, not a backend
    for name, path in modules().items():
        if name.startswith("backends") or name in parsers:
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value in names:
                wrong.append(f"{name}:{node.lineno} {node.value!r}")
    assert not wrong, "engine names outside the registry: " + ", ".join(wrong)
