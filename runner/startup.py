"""Start-up imports without the cyclic garbage collector.

Importing the command (pydantic's models, Rich, the runner) and, in a worker, the engine allocates hundreds of
thousands of objects that live as long as the process; the collector, triggered by the count of allocations,
would walk them again and again meanwhile (about a tenth of a one-step ``scenario run``'s CPU time) and find
nothing to free. :func:`imports_uncollected` pauses it for such an import; at the end the objects made so far
are moved out of its reach (``gc.freeze``: later collections, in this process and in the workers forked from
it, do not walk them, and a worker does not touch, hence copy, their pages). Both are done once per process
at most, and only where the collector was on.
"""

from __future__ import annotations

import gc
from collections.abc import Iterator
from contextlib import contextmanager

__all__ = ["imports_uncollected"]

_frozen = False


@contextmanager
def imports_uncollected() -> Iterator[None]:
    """The block runs with the collector paused; what exists at its end is frozen (the first time only)."""
    global _frozen
    if _frozen or not gc.isenabled():
        yield
        return
    gc.disable()
    try:
        yield
    finally:
        gc.freeze()
        _frozen = True
        gc.enable()
