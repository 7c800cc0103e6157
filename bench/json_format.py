"""Trace format 1's per-step encoding (JSON), kept here only to measure the protobuf encoding against it.

This is the code runner/trace/ used until trace format 2 (physics-scenarios 0.1.0): /tf, /bodies, /joints
and /contacts formatted through JSON templates whose numbers are integers of nanounits, written to MCAP
with LZ4 chunks. bench/encoding.py runs it and format 2 on the same recorded steps, in one process.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np

WORLD_FRAME = "world"
JOINT_FIELDS = ("position", "velocity", "motor_force")
_EXP = 9
_SCALE = 10.0**_EXP
_LIMIT = 1e9  # |value| below this fits an int64 once scaled by 1e9
#: the /bodies row (pos, quat w x y z, ...) -> /tf translation, rotation x y z w
TF_COLUMNS = [0, 1, 2, 4, 5, 6, 3]


def json_number(x: float) -> str:
    return repr(float(x)) if math.isfinite(x) else "null"


class StepTemplate:
    """A JSON message whose numbers are filled in per step; the skeleton is serialised once."""

    _MARK = "\x01"  # a value slot
    STAMP = "\x02"  # the step's timestamp

    def __init__(self, skeleton: Any, n_values: int) -> None:
        text = json.dumps(skeleton, separators=(",", ":")).replace("%", "%%")
        parts = text.split(json.dumps(self._MARK))
        if len(parts) != n_values + 1:
            raise ValueError("names must not contain control characters")
        self._stamp = json.dumps(self.STAMP)
        self._fast = f"%de-{_EXP}".join(parts)
        self._slow = "%s".join(parts)

    def render(self, values: np.ndarray, stamp: str = "") -> str:
        if values.size and np.isfinite(values).all() and np.abs(values).max() < _LIMIT:
            fast = self._fast.replace(self._stamp, stamp) if stamp else self._fast
            return fast % tuple(np.rint(values * _SCALE).astype(np.int64).tolist())
        slow = self._slow.replace(self._stamp, stamp) if stamp else self._slow
        return slow % tuple(json_number(v) for v in values.tolist())

    @classmethod
    def slots(cls, keys: Iterable[str]) -> dict[str, str]:
        return {k: cls._MARK for k in keys}


_PAIR_FAST = f'{{"a":%s,"b":%s,"points":%d,"depth":%de-{_EXP},"normal_force":%de-{_EXP}}}'
_PAIR_SLOW = '{"a":%s,"b":%s,"points":%d,"depth":%s,"normal_force":%s}'


def contacts_message(pairs: Sequence[tuple[int, int, int, float, float]], quoted: Sequence[str]) -> str:
    if not pairs:
        return '{"count":0,"pairs":[]}'
    a, b, points, depth, force = zip(*pairs, strict=True)
    values = np.array((depth, force), dtype=np.float64)
    if np.isfinite(values).all() and np.abs(values).max() < _LIMIT:
        depth_i, force_i = np.rint(values * _SCALE).astype(np.int64).tolist()
        rows = zip([quoted[i] for i in a], [quoted[i] for i in b], points, depth_i, force_i, strict=True)
        text = ",".join([_PAIR_FAST % row for row in rows])
    else:
        rows = zip(a, b, points, depth, force, strict=True)
        text = ",".join(
            [_PAIR_SLOW % (quoted[i], quoted[j], k, json_number(d), json_number(f)) for i, j, k, d, f in rows]
        )
    return f'{{"count":{len(pairs)},"pairs":[{text}]}}'


def step_templates(bodies: Sequence[str], joints: Sequence[str]) -> tuple[StepTemplate, StepTemplate, StepTemplate]:
    xyz, slot = "xyz", StepTemplate.slots
    frames = [
        {"timestamp": StepTemplate.STAMP, "parent_frame_id": WORLD_FRAME, "child_frame_id": b,
         "translation": slot(xyz), "rotation": slot("xyzw")}
        for b in bodies
    ]  # fmt: skip
    states = {b: {"pos": slot(xyz), "quat": slot("wxyz"), "vel": slot(xyz), "angvel": slot(xyz)} for b in bodies}
    return (
        StepTemplate({"transforms": frames}, 7 * len(bodies)),
        StepTemplate(states, 13 * len(bodies)),
        StepTemplate({j: slot(JOINT_FIELDS) for j in joints}, 3 * len(joints)),
    )


def stamp(ns: int) -> str:
    sec, nsec = divmod(ns, 1_000_000_000)
    return f'{{"sec":{sec},"nsec":{nsec}}}'
