"""Panda3D CollisionHandlerEvent patterns (%fn-into-%in ...), and the events a scenario can produce."""

from __future__ import annotations

import re
from collections import OrderedDict

from runner.language.model import Scenario, Variant
from runner.language.model_actions import SendAction

#: Tokens supported: from/into node name, from/into solid tangible ('t'; every solid here is tangible),
#: into is a CollisionNode solid ('c') or physics geometry ('g').
_TOKEN = re.compile(r"%(fn|in|fs|is|ig)")
_ANY_TOKEN = re.compile(r"%(\([^)]*\))?[a-z]{1,2}")


def unsupported_token(pattern: str) -> str | None:
    for match in _ANY_TOKEN.finditer(pattern):
        if not _TOKEN.fullmatch(match.group(0)):
            return match.group(0)
    return None


def expand(pattern: str, from_name: str, into_name: str, into_is_geometry: bool = False) -> str:
    values = {"fn": from_name, "in": into_name, "fs": "t", "is": "t", "ig": "g" if into_is_geometry else "c"}
    return _TOKEN.sub(lambda m: values[m.group(1)], pattern)


#: The input events of recently seen `variants` sections (the section object, its events): every variant of
#: a file shares one checked section, so its events are collected once, not once per variant loaded.
_VARIANT_EVENTS: OrderedDict[int, tuple[object, frozenset[str]]] = OrderedDict()


def _variant_events(variants: dict[str, Variant]) -> frozenset[str]:
    hit = _VARIANT_EVENTS.get(id(variants))
    if hit is not None and hit[0] is variants:
        return hit[1]
    events = frozenset(item.event for variant in variants.values() for item in variant.inputs or [])
    _VARIANT_EVENTS[id(variants)] = (variants, events)  # the section is kept, so its id is not reused
    while len(_VARIANT_EVENTS) > 64:
        _VARIANT_EVENTS.popitem(last=False)
    return events


def possible_events(model: Scenario) -> set[str]:
    """Every event name this scenario can ever see (for checking names used in assertions)."""
    from runner.language.model_walk import all_actions
    from runner.language.names import expand_bodies

    events = {"start", *model.triggers, *_variant_events(model.variants)}
    for item in model.inputs:
        events.add(item.event)
    for action, _ in all_actions(model):
        if isinstance(action, SendAction):
            events.add(action.send)
    c = model.collisions
    patterns = [*c.in_, *c.again, *c.out]
    nodes = c.nodes
    for f in c.from_:
        for i in nodes:
            if i != f:
                events.update(expand(p, f, i) for p in patterns)
    names = [b.name for b in expand_bodies(model)]
    for f in c.contacts_from:
        for other in names:
            if other != f:
                events.update(expand(p, f, other, into_is_geometry=True) for p in patterns)
    return events
