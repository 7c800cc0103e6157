"""One registered backend described without importing its engine (``backends.registry``'s table and the
entry points of engines outside this repository, ``backends.entry_points``)."""

from __future__ import annotations

from dataclasses import dataclass

from .types import Precision


@dataclass(frozen=True)
class BackendEntry:
    """One engine in the registry: its name, adapter class, import name and distribution (backends.registry)."""

    name: str
    target: str  # "module:Class"
    module: str  # the engine's import name, checked without importing it
    distribution: str  # the engine's distribution, for its version
    extra: str  # the extra of physics-scenarios that installs it ("" for none)
    description: str
    hidden: bool = False  # test-only backends are not listed by `scenario backends`
    options: str = "backends._kit.options:BackendOptions"  # "module:Class" of its backend_options, engine-free
    #: the format of the engine's state, as its adapter declares it (Backend.precision), engine-free
    precision: Precision = Precision.FLOAT64
    #: the distribution that registered it through an entry point ("" for the built-in table)
    package: str = ""
    #: run only where named (``--backend NAME``): listed by `scenario backends` but left out of the installed set
    #: (``--backend all``, `scenario conformance`'s default, the pytest plugin's ``installed``, the engine lists
    #: of the tests beyond the contract suite), for an engine whose one-world CPU run costs many times the others'
    opt_in: bool = False

    def __post_init__(self) -> None:
        if not isinstance(self.precision, Precision):  # a mapping from an entry point spells it "float32"
            object.__setattr__(self, "precision", Precision(self.precision))

    @property
    def hint(self) -> str:
        if self.extra:
            return f"pip install 'physics-scenarios[{self.extra}]'"
        if self.package:
            return f"pip install {self.distribution}"
        return "it ships with the runner"
