"""A body's own inertia (`inertia:` on a body): principal moments, moments along turned axes, or the full
tensor, about the centre of mass in the body frame; checked to be a physical inertia."""

from __future__ import annotations

from typing import Any

import numpy as np
from pydantic import Field, field_validator, model_validator

from runner.language.hpr import hpr_to_quat
from runner.language.model_base import FiniteFloat, PositiveFloat, Quat, Strict, Vec3, finite_vec

__all__ = ["Inertia", "inertia_problem", "moments_list_schema", "principal_inertia"]

#: rounding allowed in the triangle inequality (a thin plate's I_z = I_x + I_y exactly, written in decimals)
_TRIANGLE_SLACK = 1e-9


class Inertia(Strict):
    """Principal moments along turned axes (`moments` with `quat` or `hpr`), or the full tensor (`ixx` ...
    `iyz`, URDF's `<inertia>`), about the centre of mass in the body frame, kg m^2."""

    moments: tuple[PositiveFloat, PositiveFloat, PositiveFloat] | None = Field(
        None, description="Principal moments of inertia, kg m^2, along the axes `quat`/`hpr` turn the body's to."
    )
    quat: Quat | None = Field(None, description="The principal axes: the body frame turned by this (w, x, y, z).")
    hpr: Vec3 | None = Field(None, description="The principal axes: the body frame turned by this (degrees).")
    ixx: FiniteFloat | None = Field(None, description="Full tensor, kg m^2, body frame (URDF's <inertia>).")
    iyy: FiniteFloat | None = None
    izz: FiniteFloat | None = None
    ixy: FiniteFloat = 0.0
    ixz: FiniteFloat = 0.0
    iyz: FiniteFloat = 0.0

    _v = field_validator("quat", "hpr", mode="before")(finite_vec)

    @model_validator(mode="before")
    @classmethod
    def _list(cls, value: Any) -> Any:
        """`[Ixx, Iyy, Izz]`: principal moments along the body's own axes."""
        return {"moments": value} if isinstance(value, list | tuple) else value

    @model_validator(mode="after")
    def _one_form(self) -> Inertia:
        full = [k for k in ("ixx", "iyy", "izz") if getattr(self, k) is not None]
        off = any(getattr(self, k) != 0.0 for k in ("ixy", "ixz", "iyz"))
        if self.moments is not None:
            if full or off:
                raise ValueError(
                    "expected either `moments` (with `quat` or `hpr`) or the tensor `ixx` ... `iyz`, found both"
                )
            if self.quat is not None and self.hpr is not None:
                raise ValueError("expected either quat or hpr, found both")
            if self.quat is not None and sum(c * c for c in self.quat) < 1e-12:
                raise ValueError("expected a non-zero quaternion, found (0, 0, 0, 0)")
        else:
            if len(full) != 3:
                raise ValueError("expected `moments: [I1, I2, I3]` or the tensor's `ixx`, `iyy`, `izz` (and `ixy`, "
                                 f"`ixz`, `iyz`, default 0), found {', '.join(full) or 'neither'}")  # fmt: skip
            if self.quat is not None or self.hpr is not None:
                raise ValueError("`quat`/`hpr` turn `moments`; a full tensor is already in the body frame")
        problem = inertia_problem(self.tensor())
        if problem:
            raise ValueError(problem)
        return self

    def tensor(self) -> np.ndarray:
        """The 3x3 tensor in the body frame."""
        if self.moments is not None:
            r = _rotation(self.axes_quat())
            return np.asarray(r @ np.diag(self.moments) @ r.T, dtype=np.float64)
        if self.ixx is None or self.iyy is None or self.izz is None:
            raise ValueError("no tensor")  # the validator refused this form
        return np.array(
            [[self.ixx, self.ixy, self.ixz], [self.ixy, self.iyy, self.iyz], [self.ixz, self.iyz, self.izz]]
        )

    def axes_quat(self) -> tuple[float, float, float, float]:
        if self.quat is not None:
            q = np.asarray(self.quat, float)
            w, x, y, z = (q / np.linalg.norm(q)).tolist()
            return (w, x, y, z)
        return hpr_to_quat(self.hpr) if self.hpr is not None else (1.0, 0.0, 0.0, 0.0)


def moments_list_schema(schema: dict[str, Any]) -> None:
    """The editor schema of a body's `inertia`: also a list of three principal moments (read as `moments`)."""
    moments = {"type": "array", "items": {"type": "number", "exclusiveMinimum": 0}, "minItems": 3, "maxItems": 3}
    schema["anyOf"] = [moments, *schema.get("anyOf", [])]


def inertia_problem(tensor: np.ndarray) -> str | None:
    """Why ``tensor`` is no rigid body's inertia about its centre of mass (None if it is one): it must be
    positive definite and its principal moments must satisfy the triangle inequality I1 <= I2 + I3 (each
    moment is a sum of two of the mass's second moments: I1 = B + C, I2 = A + C, I3 = A + B with A, B, C >= 0)."""
    moments = np.linalg.eigvalsh(tensor)
    shown = ", ".join(f"{m:.6g}" for m in moments)
    if moments[0] <= 0.0:
        return f"expected a positive definite inertia (every principal moment > 0), found principal moments {shown}"
    a, b, c = moments
    if c > (a + b) * (1.0 + _TRIANGLE_SLACK):
        return (f"expected principal moments that satisfy the triangle inequality (each at most the sum of the other "
                f"two), found {shown}: {c:.6g} > {a:.6g} + {b:.6g}")  # fmt: skip
    return None


def principal_inertia(inertia: Inertia) -> tuple[tuple[float, float, float], tuple[float, float, float, float]]:
    """(principal moments, the quaternion turning the body frame to the principal axes), as BodySpec holds
    them: a diagonal tensor keeps the body's axes and its moments in order; otherwise the eigenvectors of the
    tensor, made a right-handed frame."""
    if inertia.moments is not None:
        m = inertia.moments
        return (float(m[0]), float(m[1]), float(m[2])), inertia.axes_quat()
    tensor = inertia.tensor()
    if not (inertia.ixy or inertia.ixz or inertia.iyz):
        return (float(tensor[0, 0]), float(tensor[1, 1]), float(tensor[2, 2])), (1.0, 0.0, 0.0, 0.0)
    moments, axes = np.linalg.eigh(tensor)
    if np.linalg.det(axes) < 0:
        axes[:, 2] = -axes[:, 2]
    return (float(moments[0]), float(moments[1]), float(moments[2])), _quat(axes)


def _rotation(q: tuple[float, float, float, float]) -> np.ndarray:
    w, x, y, z = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])  # fmt: skip


def _quat(r: np.ndarray) -> tuple[float, float, float, float]:
    """The unit quaternion (w, x, y, z, w >= 0) of a rotation matrix (Shepperd's method)."""
    t = float(np.trace(r))
    if t > 0:
        s = 2.0 * np.sqrt(t + 1.0)
        q = (0.25 * s, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s)
    elif r[0, 0] > r[1, 1] and r[0, 0] > r[2, 2]:
        s = 2.0 * np.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2])
        q = ((r[2, 1] - r[1, 2]) / s, 0.25 * s, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s)
    elif r[1, 1] > r[2, 2]:
        s = 2.0 * np.sqrt(1.0 + r[1, 1] - r[0, 0] - r[2, 2])
        q = ((r[0, 2] - r[2, 0]) / s, (r[0, 1] + r[1, 0]) / s, 0.25 * s, (r[1, 2] + r[2, 1]) / s)
    else:
        s = 2.0 * np.sqrt(1.0 + r[2, 2] - r[0, 0] - r[1, 1])
        q = ((r[1, 0] - r[0, 1]) / s, (r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, 0.25 * s)
    v = np.asarray(q, float)
    v = v / np.linalg.norm(v) * (1.0 if v[0] >= 0 else -1.0)
    return (float(v[0]), float(v[1]), float(v[2]), float(v[3]))
