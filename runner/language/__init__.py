"""Stage 1, the scenario language: YAML with locations, pydantic models, loading, references, expressions, schema.

A YAML key becomes a model field here (``model_*.py``); :func:`runner.language.load.load_scenario` turns a
file into a validated :class:`~runner.language.load.LoadedScenario`. Nothing here knows about engines.
"""
