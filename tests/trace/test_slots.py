"""Serialised templates (runner/trace/slots.py) against google.protobuf's own serialisation and parser."""

from __future__ import annotations

import math

import numpy as np
import pytest
from foxglove_schemas_protobuf.FrameTransforms_pb2 import FrameTransforms

from reports import trace_format as tf
from runner.trace import proto as pb
from runner.trace.encoder import TraceEncoder
from runner.trace.foxglove import transforms_template
from runner.trace.proto.scenario import scenario_messages
from runner.trace.slots import PairTemplates, SlotTemplate, StampedTemplate, TemplateError

# names the language allows (identifiers), of several lengths, some close to protobuf's JSON camel-casing
NAMES = ["a", "box", "crate_17", "aB", "a_b", "Door", "x" * 64, "_hidden"]
W = len(tf.BODY_ROW)


def _tf_expected(names: list[str], rows: np.ndarray, ns: int) -> FrameTransforms:
    msg = FrameTransforms()
    for name, r in zip(names, rows.tolist(), strict=True):
        t = msg.transforms.add(parent_frame_id=tf.WORLD_FRAME, child_frame_id=name)
        t.timestamp.seconds, t.timestamp.nanos = divmod(ns, 10**9)
        t.translation.x, t.translation.y, t.translation.z = r[0:3]
        t.rotation.w, t.rotation.x, t.rotation.y, t.rotation.z = r[3:7]
    return msg


@pytest.mark.parametrize("ns", [0, 1, 40_000_000, 999_999_999, 10**9, 12_345_678_901, 3_600 * 10**9 + 7])
def test_transforms_equal_google_protobuf_s_bytes_at_every_timestamp_length(ns: int) -> None:
    template = transforms_template(NAMES)
    rows = np.random.default_rng(ns % 97).normal(size=(len(NAMES), W))
    data = template.render(rows, ns)
    expected = _tf_expected(NAMES, rows, ns)
    assert data == expected.SerializeToString(deterministic=True)  # no zero value: byte for byte
    assert FrameTransforms.FromString(data) == expected


def test_zeros_nan_and_infinities_decode_to_the_same_message() -> None:
    template = transforms_template(NAMES)
    rows = np.zeros((len(NAMES), W))
    rows[:, 3] = 1.0
    rows[1, 0], rows[2, 1], rows[3, 2] = math.nan, math.inf, -math.inf
    rows[4, 4] = -0.0
    decoded = FrameTransforms.FromString(template.render(rows, 5))
    expected = _tf_expected(NAMES, rows, 5)
    got = [(t.translation.x, t.translation.y, t.translation.z, t.rotation.w) for t in decoded.transforms]
    want = [(t.translation.x, t.translation.y, t.translation.z, t.rotation.w) for t in expected.transforms]
    np.testing.assert_array_equal(got, want)  # NaN == NaN here
    assert [t.child_frame_id for t in decoded.transforms] == NAMES


def test_bodies_joints_and_contacts_decode_to_what_google_protobuf_builds() -> None:
    enc = TraceEncoder(NAMES, ["slider", "hinge_2"])
    rng = np.random.default_rng(11)
    rows = rng.normal(size=(len(NAMES), W))
    _, bodies = enc.transforms_and_bodies(7, rows)
    assert enc.body_topics == ["/bodies"] and len(bodies) == 1
    msg = enc.messages.bodies[0].FromString(bodies[0])
    q = np.rint(rows * 1e9) / 1e9
    for i, name in enumerate(NAMES):
        b = getattr(msg, name)
        assert [b.vel.x, b.vel.y, b.vel.z, b.angvel.x, b.angvel.y, b.angvel.z] == q[i, 7:].tolist()
    (data,) = enc.joints_messages(np.array([1.5, 0]), np.array([2, 0.0]), np.array([math.nan, 3e9]))
    joints = enc.messages.joints[0].FromString(data)
    assert (joints.slider.position, joints.slider.velocity) == (1.5, 2.0) and math.isnan(joints.slider.motor_force)
    assert joints.hinge_2.motor_force == 3e9
    contacts = [(0, 2, 4, 0.001, 12.5), (3, 1, 1, 0.0, math.nan), (0, 2, 2, 1e-10, 0.0)]
    decoded = pb.Contacts.FromString(enc.contacts_message(contacts))
    assert decoded.count == 3
    got = [(p.a, p.b, p.points, p.depth) for p in decoded.pairs]
    assert got == [("a", "crate_17", 4, 0.001), ("aB", "box", 1, 0.0), ("a", "crate_17", 2, 0.0)]  # 1e-10 -> 1e-9 grid
    assert decoded.pairs[0].normal_force == 12.5 and math.isnan(decoded.pairs[1].normal_force)
    assert pb.Contacts.FromString(enc.contacts_message([])) == pb.Contacts()


def test_pair_templates_equal_google_protobuf_s_bytes() -> None:
    names = ["ground", "ball"]

    def one(a: int, b: int, points: int, depth: float, force: float) -> pb.Contacts:
        return pb.Contacts(pairs=[pb.ContactPair(a=names[a], b=names[b], points=points, depth=depth,
                                                 normal_force=force)])  # fmt: skip

    templates = PairTemplates(2, lambda n: pb.Contacts(count=n), one)
    rows = np.array([[0, 1, 3, 0.25, 9.5], [1, 0, 1, 0.5, 1.5], [0, 1, 7, 0.125, 2.0]])
    expected = pb.Contacts(count=3)
    for a, b, k, d, f in rows.tolist():
        expected.pairs.add(a=names[int(a)], b=names[int(b)], points=int(k), depth=d, normal_force=f)
    assert templates.render(rows) == expected.SerializeToString(deterministic=True)


def test_a_template_that_does_not_reproduce_protobuf_is_refused() -> None:
    """fill() must build the message from the values it is given: one that ignores them cannot be a template."""
    messages = scenario_messages(["box"], [])

    def constant(values: np.ndarray) -> object:
        msg = messages.bodies[0]()
        msg.box.vel.x = 1.25  # not from values
        return msg

    def unstable(values: np.ndarray) -> object:
        msg = messages.bodies[0]()
        msg.box.vel.x = float(values[0])
        msg.box.vel.y = 1.0 if values[0] < 1.5 else 2.0  # depends on a value, not a slot
        return msg

    SlotTemplate(constant, 3)  # no slot at all: fine, it renders the constant
    with pytest.raises(TemplateError):
        for seed_shift in range(8):  # one of the sentinel pairs straddles 1.5
            SlotTemplate(lambda v, s=seed_shift: unstable(v + s * 0.125), 1)

    stamps = StampedTemplate(lambda v, stamp: FrameTransforms(), 1, 3)  # the timestamp is missing
    with pytest.raises(TemplateError, match="occurs 0 times"):
        stamps.render(np.zeros(1), 12345)


def test_scenario_messages_refuse_names_protobuf_cannot_hold() -> None:
    with pytest.raises(ValueError, match="cannot build"):
        scenario_messages(["box", "box"], [])
