"""The backend registry: names -> adapter classes, imported lazily, with install hints.

Two sources: the built-in table below and the entry points of the group ``physics_scenarios.backends``
(engines installed from outside this repository, ``backends.entry_points``), the built-in ones first.

``list_backends()`` never imports an engine; ``get_backend(name)`` imports the adapter on first use and
turns a missing engine into :class:`BackendNotInstalled` with the pip command that fixes it;
``check_options(name, raw)`` checks a ``backend_options`` block without the engine. Engine names are written
here and in the adapters only (tests/architecture checks the runner, tests/perf the benchmarks).
"""

from __future__ import annotations

import importlib
import importlib.util
from collections.abc import Iterator, Mapping
from typing import Any

from ._kit.options import BackendOptions
from .base import Backend
from .entry import BackendEntry
from .entry_points import BrokenBackend, registered
from .errors import BackendNotInstalled, UnknownBackend, UnsupportedFeature
from .types import Capability, CompiledWorld, Precision
from .versions import version_or_absent

# Kept sorted by name.
_KNOWN: dict[str, BackendEntry] = {
    "crash": BackendEntry("crash", "backends.crash:CrashBackend", "numpy", "numpy", "",
                          "test-only: kills its own process mid-run (SIGKILL/SIGSEGV) to test isolation", hidden=True,
                          options="backends.crash:CrashOptions"),
    "dart": BackendEntry(
        "dart",
        "backends.dart:DartBackend",
        "dartpy",
        "dartpy",
        "dart",
        "DART (dartpy), ODE collision detector by default",
        options="backends.dart._options:DartOptions",
    ),
    "drake": BackendEntry(
        "drake",
        "backends.drake:DrakeBackend",
        "pydrake",
        "drake",
        "drake",
        "Drake (pydrake MultibodyPlant + SceneGraph), hydroelastic contact (point contact as fallback) and the SAP "
        "solver by default",
        options="backends.drake._options:DrakeOptions",
    ),
    "fake": BackendEntry(
        "fake",
        "backends.fake:FakeBackend",
        "numpy",
        "numpy",
        "",
        "pure-Python point masses, for tests of the runner's logic",
        hidden=True,
    ),
    "mujoco": BackendEntry(
        "mujoco", "backends.mujoco:MujocoBackend", "mujoco", "mujoco", "mujoco", "MuJoCo, built through MjSpec",
        options="backends.mujoco._options:MujocoOptions",
    ),
    "mujoco_warp": BackendEntry(
        "mujoco_warp", "backends.mujoco_warp:MujocoWarpBackend", "mujoco_warp", "mujoco-warp", "mujoco_warp",
        "MuJoCo Warp (MJWarp): the MuJoCo backend's model stepped on a Warp device (CPU by default)",
        options="backends.mujoco_warp._options:MujocoWarpOptions", precision=Precision.FLOAT32,
        # one world on Warp's CPU device: the conformance suite takes 1103 s (mujoco: 9 s), a 2 s case 12.5 s
        # against 2.8 s (docs/backends/mujoco_warp.md); it runs where named
        opt_in=True,
    ),
    "newton": BackendEntry(
        "newton",
        "backends.newton:NewtonBackend",
        "newton",
        "newton",
        "newton",
        "NVIDIA Newton on Warp (CPU or CUDA), the XPBD solver by default (featherstone by option)",
        options="backends.newton._options:NewtonOptions",
        precision=Precision.FLOAT32,
        # installed by `[all]` (CI runs its contract suite: about 2.5 min of CPU with a cold kernel cache), but
        # one world on Warp's CPU device costs many times the others (its conformance column took 362-997 s on two busy
        # cores; docs/backends/newton.md): it runs where named
        opt_in=True,
    ),
    "ode": BackendEntry(
        "ode",
        "backends.ode:OdeBackend",
        "panda3d",
        "panda3d",
        "ode",
        "the Open Dynamics Engine through panda3d.ode: the reference",
        options="backends.ode._options:OdeOptions",
        precision=Precision.FLOAT32,
    ),
    "pybullet": BackendEntry(
        "pybullet",
        "backends.pybullet:PyBulletBackend",
        "pybullet",
        "pybullet",
        "",
        "PyBullet in DIRECT mode (the default backend)",
        options="backends.pybullet._options:PyBulletOptions",
    ),
}
if list(_KNOWN) != sorted(_KNOWN):  # pragma: no cover - a guard for whoever edits the table
    raise RuntimeError("backends.registry._KNOWN must stay sorted")



def _table() -> dict[str, BackendEntry]:
    """The built-in table, then the engines registered through entry points (read once per process)."""
    return {**_KNOWN, **registered(frozenset(_KNOWN)).entries}


def broken_backends() -> dict[str, str]:
    """Engines registered through an entry point that cannot describe themselves: name -> the reason."""
    return dict(registered(frozenset(_KNOWN)).broken)


class _Known(Mapping[str, BackendEntry]):
    """Every registered backend by name (read-only), entry points included."""

    def __getitem__(self, name: str) -> BackendEntry:
        return _table()[name]

    def __iter__(self) -> Iterator[str]:
        return iter(_table())

    def __len__(self) -> int:
        return len(_table())


KNOWN_BACKENDS: Mapping[str, BackendEntry] = _Known()
DEFAULT_BACKEND = "pybullet"
#: The backend every other one is compared with where no analytic truth exists: real ODE.
REFERENCE_BACKEND = "ode"


def entry(name: str) -> BackendEntry:
    if name in _KNOWN:  # a built-in name: no need to read the entry points
        return _KNOWN[name]
    table = _table()
    try:
        return table[name]
    except KeyError:
        broken = broken_backends()
        if name in broken:
            raise BrokenBackend(broken[name]) from None
        import difflib  # here: only an unknown name needs it

        close = difflib.get_close_matches(name, [n for n, e in table.items() if not e.hidden], n=1)
        hint = f" Did you mean `{close[0]}`?" if close else ""
        listed = ", ".join(n for n, e in table.items() if not e.hidden)
        raise UnknownBackend(f"Unknown backend `{name}`.{hint} Known backends: {listed}.") from None


def is_installed(name: str) -> bool:
    return importlib.util.find_spec(entry(name).module) is not None


def engine_version(name: str) -> str:
    return version_or_absent(entry(name).distribution)


def distribution_installed(name: str) -> bool:
    """Whether the engine's distribution is installed (its adapter may still fail to import: a bug, not a skip)."""
    return engine_version(name) != "not installed"


def list_backends(include_hidden: bool = False) -> list[BackendEntry]:
    return [e for e in _table().values() if include_hidden or not e.hidden]


def engine_modules() -> frozenset[str]:
    """The import names of every engine (to tell whether one is loaded in this process)."""
    return frozenset(e.module for e in _table().values() if e.extra or e.package or e.name == DEFAULT_BACKEND)


def installed_backends(include_opt_in: bool = False) -> list[str]:
    """The installed engines that ``all`` selects; an opt-in engine (``BackendEntry.opt_in``) only when asked."""
    return [e.name for e in list_backends() if is_installed(e.name) and (include_opt_in or not e.opt_in)]


def get_backend(name: str) -> type[Backend]:
    """The adapter class for ``name``, imported now."""
    item = entry(name)
    if not is_installed(name):
        raise BackendNotInstalled(
            f"Backend `{name}` needs the `{item.module}` package, which is not installed. Install it with: {item.hint}"
        )
    module_name, _, class_name = item.target.partition(":")
    try:
        module = importlib.import_module(module_name)
    except ImportError as exc:
        raise BackendNotInstalled(
            f"Backend `{name}` could not import its engine ({exc}). Install it with: {item.hint}"
        ) from exc
    cls: type[Backend] = getattr(module, class_name)
    return cls


def import_adapter(name: str) -> None:
    """Import backend ``name``'s adapter module, letting its ImportError through as it is (the shipped suite:
    an adapter that cannot be imported fails its tests with the reason; get_backend turns it into a hint)."""
    importlib.import_module(entry(name).target.partition(":")[0])


def options_of(name: str) -> type[BackendOptions]:
    """The class of backend ``name``'s ``backend_options`` block, imported without the engine."""
    module_name, _, class_name = entry(name).options.partition(":")
    cls: type[BackendOptions] = getattr(importlib.import_module(module_name), class_name)
    return cls


def check_options(name: str, raw: Mapping[str, Any]) -> BackendOptions:
    """A scenario's ``backend_options.<name>`` block checked as ``run`` checks it, without the engine (for
    ``validate``): UnsupportedFeature names the key, what was expected and what was received."""
    return options_of(name).parse(raw, name)


def check_capabilities(cls: type[Backend], world: CompiledWorld) -> None:
    """Refuse a world that needs what the backend cannot do, options it does not take, or beyond the engine's
    limits (``Backend.check_world``), before anything is built (UnsupportedFeature, exit 2)."""
    lacking = world.required_capabilities() - cls.capabilities
    missing = sorted(c.value for c in lacking)
    if missing:
        sites = [f"robot `{m.robot}`: {site}" for m in world.models for c, site in m.need_sites if c in lacking]
        where = f" ({'; '.join(sites)})" if sites else ""
        refusal = UnsupportedFeature(
            f"Scenario `{world.name}` needs {', '.join(missing)}{where}, which backend `{cls.name}` does not "
            f"support. Supported: {', '.join(sorted(c.value for c in cls.capabilities))}."
            f"{_alternatives(cls, lacking)}"
        )
        refusal.missing = frozenset(lacking)
        raise refusal
    options = cls.Options.parse(world.options_for(cls.name), cls.name)  # unknown keys and bad values
    cls.check_world(cls.engine_world(world), options)  # the engine's limits (Backend.check_world)


def _alternatives(refusing: type[Backend], lacking: frozenset[Capability] | set[Capability]) -> str:
    """The hint of a refusal: the other installed backends that declare everything ``lacking``, else the
    install commands of those that would (a backend that cannot be imported is judged by nothing)."""
    installed, hints = [], []
    for name, known in KNOWN_BACKENDS.items():
        if known.hidden or name == refusing.name:
            continue
        try:
            other = get_backend(name)
        except BackendNotInstalled:
            hints.append(known.hint)
            continue
        if lacking <= other.capabilities:
            installed.append(name)
    if installed:
        return f" Backends that support it: {', '.join(installed)} (--backend {installed[0]})."
    return f" Install another backend: {'; '.join(hints)}." if hints else ""


def create_backend(name: str, world: CompiledWorld) -> Backend:
    cls = get_backend(name)
    check_capabilities(cls, world)
    return cls(world)
