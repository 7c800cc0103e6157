"""The entry point's target: the backend described without importing the engine (``scenario backends`` lists
backends this way). Hidden: a test engine without contacts is not offered to users or to `scenario conformance`."""

ENTRY = {
    "name": "outside",
    "target": "outside_engine.engine:OutsideBackend",
    "module": "outside_engine.engine",  # the engine itself (the package is imported to read this entry)
    "distribution": "scenario-outside-engine",
    "extra": "",
    "description": "test-only: a pure-numpy rigid-body engine registered from outside the repository (no contacts)",
    "hidden": True,
    "precision": "float64",
}
