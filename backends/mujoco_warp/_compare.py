"""Which MuJoCo models can be the worlds of one MJWarp model, and in which fields they differ (docs/batch.md).

MJWarp holds one model for all its worlds. A ``mujoco_warp.Model`` field whose array spec starts with ``"*"`` has
a leading world dimension that may be larger than one (``put_model(batch_sizes=...)``; a kernel reads
``field[worldid % len(field)]``): those fields may differ between the worlds of a batch. Everything else (sizes,
topology, types, options, the other arrays) must be equal, since the batch runs world 0's. A few batched fields
also decide, in ``put_model``, which code paths the whole model runs (``has_tendon_stiffness``, the actuators'
kinds...): they are kept out, so that every world runs the code paths it would run alone.
"""

from __future__ import annotations

import dataclasses
import inspect
import re
from collections.abc import Sequence
from typing import Any

import mujoco
import numpy as np

#: Batched ``Model`` fields that ``put_model`` also reads to choose code paths for all worlds (mujoco_warp
#: 4.0.0 io.py: tendon stiffness/damping flags, actuator kinds, equality addresses) or whose per-world form
#: needs more than the field (``geom_dataid``: per-world meshes need their derived sizes too).
_DECIDES_CODE_PATHS = frozenset({
    "eq_data", "tendon_stiffness", "tendon_stiffnesspoly", "tendon_damping", "tendon_dampingpoly",
    "actuator_gainprm", "actuator_biasprm", "actuator_damping", "actuator_dampingpoly", "actuator_gear",
    "geom_dataid",
})  # fmt: skip


#: The sizes a user recognises, compared (and named) before MuJoCo's derived ones.
_FIRST_SIZES = ("nbody", "njnt", "ngeom", "nq", "nv", "nu", "ntendon", "npair", "nexclude", "nmesh")

_FIRST_ARRAYS = ("geom_type", "jnt_type", "body_parentid", "geom_size")


def batched_model_fields() -> frozenset[str]:
    """The ``mujoco_warp.Model`` fields that may differ per world (see the module docstring)."""
    from mujoco_warp._src import types

    names = set()
    for f in dataclasses.fields(types.Model):
        shape = getattr(f.type, "shape", ())
        if shape and shape[0] == "*":
            names.add(f.name)
    return frozenset(names - _DECIDES_CODE_PATHS)


def device_read_fields() -> frozenset[str]:
    """The MjModel fields that reach the device: ``mujoco_warp.Model``'s own, and those ``put_model`` reads to
    derive others (found in its source, so that a newer MJWarp is judged by what it reads). The rest (``dof_M0``,
    the names...) only the host reads, each view from its own world's model."""
    from mujoco_warp._src import io, types

    names = {f.name for f in dataclasses.fields(types.Model)}
    return frozenset(names | set(re.findall(r"\bmjm\.(\w+)", inspect.getsource(io))))


def _model_attributes(m: mujoco.MjModel) -> list[str]:
    """MjModel's arrays and numbers (its sizes, its per-element arrays), by name."""
    names = []
    for name in dir(m):
        if name.startswith("_"):
            continue
        value = getattr(m, name)
        if isinstance(value, np.ndarray | int | float) and not isinstance(value, bool):
            names.append(name)
    return names


def _option_attributes(m: mujoco.MjModel) -> list[str]:
    return [n for n in dir(m.opt) if not n.startswith("_") and isinstance(getattr(m.opt, n), np.ndarray | int | float)]


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, np.ndarray):
        return isinstance(b, np.ndarray) and a.shape == b.shape and bool(np.array_equal(a, b, equal_nan=True))
    return bool(a == b)


def _bytes(a: np.ndarray) -> tuple[tuple[int, ...], bytes]:
    """An array's shape and bits: equal bits are equal values (a NaN included), compared at memcmp speed."""
    return a.shape, a.tobytes()


def _shown(value: Any) -> str:
    if isinstance(value, np.ndarray):
        flat = value.reshape(-1)
        text = np.array2string(flat[:6], precision=6, separator=", ")
        return f"{text[:-1]}, ...]" if flat.size > 6 else text
    return repr(value)


def model_differences(models: Sequence[mujoco.MjModel]) -> tuple[str | None, set[str]]:
    """(None, the batched fields that differ) when the models can be one MJWarp model; otherwise (the reason,
    naming the field and the two variants, set())."""
    batched, device = batched_model_fields(), device_read_fields()
    first = models[0]
    sizes = [n for n in _model_attributes(first) if not isinstance(getattr(first, n), np.ndarray)]
    sizes.sort(key=lambda n: (_FIRST_SIZES.index(n) if n in _FIRST_SIZES else len(_FIRST_SIZES), n))
    arrays = [n for n in _model_attributes(first) if isinstance(getattr(first, n), np.ndarray) and n in device]
    arrays.sort(key=lambda n: (_FIRST_ARRAYS.index(n) if n in _FIRST_ARRAYS else len(_FIRST_ARRAYS), n))
    reference = {n: _bytes(getattr(first, n)) for n in arrays}  # the host's own fields (dof_M0...) may differ
    options = _option_attributes(first)
    differ: set[str] = set()
    for k, m in enumerate(models[1:], start=1):
        for name in sizes:  # nbody, ngeom, ...: the topology first, so that the reason names it
            a, b = getattr(m, name), getattr(first, name)
            if a != b:
                return f"the MuJoCo model's `{name}` is {a!r} in variant {k} and {b!r} in variant 0 (the worlds of " \
                       "one MJWarp model share their sizes)", set()  # fmt: skip
        for name in options:
            a, b = getattr(m.opt, name), getattr(first.opt, name)
            if not _same(a, b):
                return f"the MuJoCo option `opt.{name}` is {_shown(a)} in variant {k} and {_shown(b)} in variant 0 " \
                       "(MJWarp runs one set of options for all worlds)", set()  # fmt: skip
        for name in arrays:
            if name in differ:
                continue
            a = getattr(m, name)
            if _bytes(a) == reference[name]:
                continue
            if name not in batched:
                b = getattr(first, name)
                return f"the MuJoCo model's `{name}` is {_shown(a)} in variant {k} and {_shown(b)} in variant 0 " \
                       "(MJWarp holds it once for all worlds)", set()  # fmt: skip
            differ.add(name)
    return None, differ
