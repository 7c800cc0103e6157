"""Connected components by union-find: bodies joined by joints, skeletons joined by contacts."""

from __future__ import annotations

from collections.abc import Hashable, Iterable
from typing import TypeVar

Node = TypeVar("Node", bound=Hashable)


def components(nodes: Iterable[Node], pairs: Iterable[tuple[Node, Node]]) -> dict[Node, Node]:
    """Each node's representative: nodes that ``pairs`` join (directly or through others) share one. A pair with
    an end outside ``nodes`` joins nothing."""
    parent = {n: n for n in nodes}

    def root(n: Node) -> Node:
        while parent[n] != n:
            parent[n] = parent[parent[n]]
            n = parent[n]
        return n

    for a, b in pairs:
        if a in parent and b in parent:
            parent[root(a)] = root(b)
    return {n: root(n) for n in parent}
