"""Per-step protobuf messages without building a message per step: serialised templates with value slots.

Setting a field of a Python protobuf message costs about 0.1 us, so /tf and /bodies built field by field
cost 1-2 us per body per step, ten times the budget (docs/trace-format.md, "Cost"). But a ``double`` is
always 8 little-endian bytes on the wire and a ``fixed32`` 4, at a place that does not depend on the value.
So a message is serialised once by google.protobuf with distinct sentinel values, the sentinels are
found in its bytes, and each step copies those bytes and writes its values into the slots with one numpy
assignment. Nothing here writes a tag, a length or a varint: every byte around the slots is
google.protobuf's own. Each template proves itself when built: a second, independent message filled in
through the slots must equal what google.protobuf serialises for it, byte for byte, or the template is
refused (``TemplateError``).

One difference from google.protobuf's own output is deliberate: a value of exactly 0.0 stays in its slot,
where proto3 would leave the field out. Both decode to the same message (the field's default is 0.0).
"""

from __future__ import annotations

import random
from collections.abc import Callable, Sequence
from typing import Any, NamedTuple

import numpy as np
from google.protobuf.timestamp_pb2 import Timestamp

__all__ = ["PairTemplates", "SlotTemplate", "StampedTemplate", "TemplateError", "quantize"]

#: absolute resolution of per-step values (reports.trace_format.VALUE_RESOLUTION as a scale)
_SCALE = 1e9
#: the bits of 1.0 (IEEE 754 double): with a 52-bit mantissa, a double in [1, 2)
_ONE_BITS = np.uint64(0x3FF0000000000000)


class TemplateError(RuntimeError):
    """A template's slots do not reproduce google.protobuf's bytes (a programming error, not bad input)."""


def quantize(values: np.ndarray) -> np.ndarray:
    """``values`` rounded to 1e-9 (NaN and infinities kept): a body at rest writes the same bytes every step,
    which compression then removes, and a reader gets exactly the numbers format 1 gave it."""
    return np.rint(values * _SCALE) / _SCALE


def _sentinels(n: int, seed: int) -> np.ndarray:
    """``n`` doubles in [1, 2) with random mantissas: their bytes occur nowhere else by chance (and if they did,
    or two were equal, the template's check would refuse it). Drawn with the standard library's generator:
    numpy.random is a module more to import in every worker, for a few draws."""
    draw = random.Random(seed).getrandbits
    mantissas = np.fromiter((draw(52) for _ in range(n)), dtype=np.uint64, count=n)
    return (mantissas | _ONE_BITS).view(np.float64)


def _find(data: bytes, patterns: Sequence[bytes]) -> list[int]:
    """The offset of each pattern in ``data``, which must occur exactly once."""
    offsets = []
    for p in patterns:
        at = data.find(p)
        if at < 0 or data.find(p, at + 1) >= 0:
            raise TemplateError("a sentinel value is missing or not unique in the serialised template")
        offsets.append(at)
    return offsets


def _used(data: bytes, values: np.ndarray) -> tuple[list[int], list[int]]:
    """(slot offsets, value indices) of the sentinels found in ``data``, in one vectorised pass over its 8-byte
    windows; a sentinel found twice is an error, one not found is a value the message does not use."""
    raw = np.frombuffer(data, dtype=np.uint8)
    if len(raw) < 8 or not len(values):
        return [], []
    windows = np.lib.stride_tricks.sliding_window_view(raw, 8).copy().view("<u8").ravel()
    keys = np.ascontiguousarray(values, dtype="<f8").view("<u8")
    order = np.argsort(keys)
    sorted_keys = keys[order]
    # membership by binary search (np.isin and np.unique would import numpy.ma in every worker)
    nearest = np.minimum(np.searchsorted(sorted_keys, windows), len(sorted_keys) - 1)
    at = np.flatnonzero(sorted_keys[nearest] == windows)
    which = order[nearest[at]]
    ranked = np.sort(which)
    if (ranked[1:] == ranked[:-1]).any():
        raise TemplateError("a sentinel value occurs twice in the serialised template")
    by_value = np.argsort(which)
    return at[by_value].tolist(), which[by_value].tolist()


def _byte_index(offsets: Sequence[int] | np.ndarray, width: int) -> np.ndarray:
    return (np.asarray(offsets, dtype=np.intp)[:, None] + np.arange(width)).ravel()


class _Layout:
    """One serialised template and where each output byte comes from.

    ``buffer`` = template bytes, then the step's values (8 bytes each), then the step's extra bytes (a
    timestamp); ``gather`` picks the output from it, so a step is one copy in and one ``take`` out.
    """

    def __init__(self, data: bytes, n: int, slots: Sequence[int], used: Sequence[int], extra_at: Sequence[int],
                 extra_len: int) -> None:  # fmt: skip
        size = len(data)
        self.values_at = size
        self.extra_at = size + 8 * n
        self.buffer = np.zeros(self.extra_at + extra_len, dtype=np.uint8)
        self.buffer[:size] = np.frombuffer(data, dtype=np.uint8)
        gather = np.arange(size, dtype=np.intp)
        gather[_byte_index(slots, 8)] = _byte_index(self.values_at + 8 * np.asarray(used, dtype=np.intp), 8)
        if extra_len:
            gather[_byte_index(extra_at, extra_len)] = np.tile(self.extra_at + np.arange(extra_len), len(extra_at))
        self.gather = gather

    def render(self, values: np.ndarray, extra: bytes = b"") -> bytes:
        buf = self.buffer
        buf[self.values_at : self.extra_at] = np.ascontiguousarray(values, dtype="<f8").reshape(-1).view(np.uint8)
        if extra:
            buf[self.extra_at :] = np.frombuffer(extra, dtype=np.uint8)
        return buf.take(self.gather).tobytes()


class SlotTemplate:
    """A message whose double fields take their values from a float64 vector of length ``n`` per step.

    ``fill(values)`` must return the message built through google.protobuf from ``values``; it may use
    any of them, in any order and place. It is called twice, when the template is built.
    """

    def __init__(self, fill: Callable[[np.ndarray], Any], n: int) -> None:
        self.n = n
        first = _sentinels(n, 1)
        data = fill(first).SerializeToString(deterministic=True)
        slots, used = _used(data, first)
        self._layout = _Layout(data, n, slots, used, (), 0)
        check = _sentinels(n, 2)
        if self.render(check) != fill(check).SerializeToString(deterministic=True):
            raise TemplateError("the template's slots do not reproduce google.protobuf's serialisation")

    def render(self, values: np.ndarray) -> bytes:
        """The serialised message for ``values`` (float64, ``n`` of them in any shape)."""
        return self._layout.render(values)


class StampedTemplate:
    """A :class:`SlotTemplate` whose message also holds ``stamps`` copies of one ``google.protobuf.Timestamp``.

    A Timestamp is varints, whose length depends on the time, so there is one template per serialised
    length (a run meets a handful): built with the step's own timestamp, which must then occur exactly
    ``stamps`` times; each later step of that length writes its timestamp's bytes over those copies.
    ``fill(values, stamp)`` builds the message through google.protobuf.
    """

    def __init__(self, fill: Callable[[np.ndarray, Timestamp], Any], n: int, stamps: int) -> None:
        self.n = n
        self.stamps = stamps
        self._fill = fill
        self._by_length: dict[int, _Layout] = {}

    @staticmethod
    def timestamp(ns: int) -> Timestamp:
        sec, nsec = divmod(int(ns), 1_000_000_000)
        return Timestamp(seconds=sec, nanos=nsec)

    def _build(self, stamp: Timestamp, stamp_bytes: bytes) -> _Layout:
        first = _sentinels(self.n, 1)
        data = self._fill(first, stamp).SerializeToString(deterministic=True)
        slots, used = _used(data, first)
        stamp_at: list[int] = []
        if stamp_bytes:
            at = data.find(stamp_bytes)
            while at >= 0:
                stamp_at.append(at)
                at = data.find(stamp_bytes, at + len(stamp_bytes))
        if len(stamp_at) != (self.stamps if stamp_bytes else 0):
            raise TemplateError(f"the timestamp occurs {len(stamp_at)} times in the template, not {self.stamps}")
        layout = _Layout(data, self.n, slots, used, stamp_at, len(stamp_bytes))
        check = _sentinels(self.n, 2)
        if layout.render(check, stamp_bytes) != self._fill(check, stamp).SerializeToString(deterministic=True):
            raise TemplateError("the template's slots do not reproduce google.protobuf's serialisation")
        return layout

    def render(self, values: np.ndarray, ns: int) -> bytes:
        """The serialised message for ``values`` at simulated time ``ns`` (integer nanoseconds)."""
        stamp = self.timestamp(ns)
        stamp_bytes = stamp.SerializeToString(deterministic=True)
        layout = self._by_length.get(len(stamp_bytes))
        if layout is None:
            layout = self._by_length[len(stamp_bytes)] = self._build(stamp, stamp_bytes)
        return layout.render(values, stamp_bytes)


class PairTemplates:
    """A repeated field of small messages (one per contact pair), each with one ``fixed32`` and two double
    slots, keyed by an integer pair (a, b) of at most ``n`` values each.

    Protobuf defines concatenated serialisations of a message as their merge, with repeated fields
    appended; so a step's message is a header (``head(count)``, serialised by google.protobuf) followed
    by one serialised single-element message per pair, each from a template cached per (a, b); a step
    gathers them from one array of every template's bytes, then fills the slots (numpy throughout). The
    gathered templates and slot positions are kept for the next step, which reuses them when its pairs are
    the same ones in the same order (most steps of a run), and the header is kept per pair count.
    ``one(a, b, points, x, y)`` must build the single-element message through google.protobuf.
    """

    def __init__(self, n: int, head: Callable[[int], Any], one: Callable[[int, int, int, float, float], Any]) -> None:
        self._n = max(1, n)
        self._head = head
        self._one = one
        self._keys = np.empty(0, dtype=np.int64)  # sorted pair keys a * n + b
        self._ids = np.empty(0, dtype=np.intp)  # template index of each key
        self._data = np.empty(0, dtype=np.uint8)  # every template's bytes, one after the other
        self._start: list[int] = []
        self._length: list[int] = []
        self._slots: list[tuple[int, int, int]] = []  # byte offsets of points, x, y in each template
        self._arrays: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        self._heads: dict[int, bytes] = {}  # the header by pair count
        self._last: _PairLayout | None = None

    def _add(self, a: int, b: int) -> None:
        points, x, y = 0x5AC3_9E71, *_sentinels(2, 3)
        data = self._one(a, b, points, x, y).SerializeToString(deterministic=True)
        fixed = np.array([points], dtype="<u4").tobytes()
        slots = _find(data, [fixed, np.array([x], "<f8").tobytes(), np.array([y], "<f8").tobytes()])
        points2, x2, y2 = 0x1234_5678, *_sentinels(2, 4)
        patched = bytearray(data)
        patched[slots[0] : slots[0] + 4] = np.array([points2], dtype="<u4").tobytes()
        patched[slots[1] : slots[1] + 8] = np.array([x2], "<f8").tobytes()
        patched[slots[2] : slots[2] + 8] = np.array([y2], "<f8").tobytes()
        if bytes(patched) != self._one(a, b, points2, x2, y2).SerializeToString(deterministic=True):
            raise TemplateError("the pair template's slots do not reproduce google.protobuf's serialisation")
        key = a * self._n + b
        at = int(np.searchsorted(self._keys, key))
        self._keys = np.insert(self._keys, at, key)
        self._ids = np.insert(self._ids, at, len(self._start))
        self._start.append(len(self._data))
        self._length.append(len(data))
        self._slots.append((slots[0], slots[1], slots[2]))
        self._data = np.concatenate([self._data, np.frombuffer(data, dtype=np.uint8)])
        self._arrays = None

    def _lookup(self, keys: np.ndarray) -> np.ndarray:
        at = np.minimum(np.searchsorted(self._keys, keys), max(len(self._keys) - 1, 0))
        found = (at < len(self._keys)) & (self._keys[at] == keys) if len(self._keys) else np.zeros(len(keys), bool)
        return np.where(found, self._ids[at] if len(self._ids) else 0, -1)

    def render(self, pairs: np.ndarray) -> bytes:
        """``pairs``: (P, 5) rows of a, b, points, x, y (the backends' ``Contact`` rows)."""
        head = self._heads.get(len(pairs))
        if head is None:
            head = self._heads[len(pairs)] = bytes(self._head(len(pairs)).SerializeToString(deterministic=True))
        if not len(pairs):
            return head
        keys = pairs[:, 0].astype(np.int64) * self._n + pairs[:, 1].astype(np.int64)
        last = self._last
        if last is None or len(last.keys) != len(keys) or not np.array_equal(last.keys, keys):
            last = self._last = self._layout(keys)
        body = last.body.copy()
        body[last.points_at] = pairs[:, 2].astype("<u4").view(np.uint8)
        body[last.doubles_at] = np.ascontiguousarray(pairs[:, 3:5], dtype="<f8").view(np.uint8).ravel()
        return head + body.tobytes()

    def _layout(self, keys: np.ndarray) -> _PairLayout:
        """The templates of these pairs one after the other, and where their slots are."""
        ids = self._lookup(keys)
        if (ids < 0).any():
            for k in np.unique(keys[ids < 0]).tolist():
                self._add(k // self._n, k % self._n)
            ids = self._lookup(keys)
        if self._arrays is None:
            self._arrays = (np.asarray(self._start), np.asarray(self._length), np.asarray(self._slots))
        start, length, slots = self._arrays
        lengths = length[ids]
        out_start = np.cumsum(lengths) - lengths
        total = int(lengths.sum())
        gather = np.arange(total) + np.repeat(start[ids] - out_start, lengths)  # each template's bytes in turn
        at = slots[ids] + out_start[:, None]
        return _PairLayout(keys.copy(), self._data.take(gather), _byte_index(at[:, 0], 4),
                           _byte_index(at[:, 1:].ravel(), 8))  # fmt: skip


class _PairLayout(NamedTuple):
    """One step's pairs (their keys, in order): the templates' bytes and the byte indices of the slots. A run
    whose pairs stay the same from step to step (a pile at rest) reuses it."""

    keys: np.ndarray
    body: np.ndarray  # uint8: every pair's template, in order
    points_at: np.ndarray  # 4 bytes per pair
    doubles_at: np.ndarray  # 16 bytes per pair: x, then y
