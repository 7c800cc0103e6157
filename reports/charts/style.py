"""How a backend looks in every chart: a colour from a colour-blind-safe palette, a dash and a marker.

The colours are Okabe and Ito's (2008, "Color Universal Design"), distinguishable under the common
colour-vision deficiencies, in an order that keeps the first four far apart; yellow is left out (it
vanishes on white). Dash patterns and marker shapes differ too, so lines that lie on top of each
other (two engines that agree) stay readable and a greyscale print still tells them apart.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

__all__ = ["COLORS", "DASHES", "MARKERS", "Look", "look", "looks"]

COLORS = ("#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000")
#: stroke-dasharray per backend (the first solid)
DASHES: tuple[tuple[int, ...], ...] = ((1, 0), (7, 3), (2, 2), (9, 3, 2, 3), (4, 4), (12, 4), (1, 3))
#: Vega point shapes
MARKERS = ("circle", "square", "triangle-up", "diamond", "cross", "triangle-down", "wedge")


@dataclass(frozen=True)
class Look:
    color: str
    dash: tuple[int, ...]
    marker: str


def look(index: int) -> Look:
    """The look of the ``index``-th backend in report order (the reference first)."""
    k = index % len(COLORS)
    return Look(COLORS[k], DASHES[k], MARKERS[k])


def looks(names: Sequence[str]) -> dict[str, Look]:
    return {n: look(i) for i, n in enumerate(names)}
