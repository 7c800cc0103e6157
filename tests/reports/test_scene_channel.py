"""The scene channel is read by its well-known schema name in the encoding it declares: JSON (today's traces)
and protobuf (Foxglove's precompiled SceneUpdate, decoded from the FileDescriptorSet the channel carries)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from mcap.writer import Writer

from reports.scene3d.model import _updates
from reports.scene3d.scene_channel import read_scene_updates

ENTITY = {
    "frame_id": "box", "id": "body/box", "metadata": [],
    "cubes": [{"pose": {"position": {"x": 0, "y": 0, "z": 0.1}, "orientation": {"x": 0, "y": 0, "z": 0, "w": 1}},
               "size": {"x": 0.3, "y": 0.4, "z": 0.5}, "color": {"r": 1, "g": 0.5, "b": 0, "a": 1}}],
}  # fmt: skip


def _write(path: Path, schema: tuple[str, str, bytes], encoding: str, messages: list[tuple[int, bytes]]) -> None:
    with open(path, "wb") as f:
        w = Writer(f)
        w.start()
        sid = w.register_schema(*schema)
        cid = w.register_channel("/scene", encoding, sid)
        for ns, data in messages:
            w.add_message(cid, ns, data, ns)
        w.finish()


def test_json_scene_updates_are_read_in_time_order(tmp_path: Path) -> None:
    bigger = json.loads(json.dumps(ENTITY))
    bigger["cubes"][0]["size"] = {"x": 0.9, "y": 1.2, "z": 1.5}
    msgs = [(2_000_000_000, {"deletions": [], "entities": [bigger]}), (0, {"deletions": [], "entities": [ENTITY]})]
    path = tmp_path / "t.mcap"
    _write(path, ("foxglove.SceneUpdate", "jsonschema", b"{}"), "json",
           [(ns, json.dumps(m).encode()) for ns, m in msgs])  # fmt: skip
    found = read_scene_updates(path)
    assert [t for t, _ in found] == [0.0, 2.0]
    updates = _updates(found)
    assert updates[0][1]["body/box"].primitives[0].size == (0.3, 0.4, 0.5)  # type: ignore[union-attr]
    assert updates[1][1]["body/box"].primitives[0].size == (0.9, 1.2, 1.5)  # type: ignore[union-attr]


def test_protobuf_scene_updates_decode_with_the_schema_the_channel_carries(tmp_path: Path) -> None:
    pb = pytest.importorskip("foxglove_schemas_protobuf.SceneUpdate_pb2",
                             reason="tool not installed: foxglove-schemas-protobuf (the dev extra)")  # fmt: skip
    from google.protobuf import descriptor_pb2, json_format

    message = json_format.ParseDict({"deletions": [], "entities": [ENTITY]}, pb.SceneUpdate())
    files = descriptor_pb2.FileDescriptorSet()
    seen: set[str] = set()

    def add(fd: object) -> None:  # dependencies first, each file once
        for dep in fd.dependencies:  # type: ignore[attr-defined]
            add(dep)
        if fd.name not in seen:  # type: ignore[attr-defined]
            seen.add(fd.name)  # type: ignore[attr-defined]
            fd.CopyToProto(files.file.add())  # type: ignore[attr-defined]

    add(pb.SceneUpdate.DESCRIPTOR.file)
    path = tmp_path / "t.mcap"
    _write(path, ("foxglove.SceneUpdate", "protobuf", files.SerializeToString()), "protobuf",
           [(500_000_000, message.SerializeToString())])  # fmt: skip
    found = read_scene_updates(path)
    assert len(found) == 1 and found[0][0] == 0.5
    entity = _updates(found)[0][1]["body/box"]
    assert entity is not None and entity.body == "box"
    cube = entity.primitives[0]
    assert cube.kind == "cube" and cube.size == pytest.approx((0.3, 0.4, 0.5))
    assert cube.position == pytest.approx((0, 0, 0.1))
    assert cube.quat == (1.0, 0.0, 0.0, 0.0) and cube.rgba == pytest.approx((1.0, 0.5, 0.0, 1.0))


def test_a_trace_without_a_readable_scene_channel_gives_nothing(tmp_path: Path) -> None:
    path = tmp_path / "cut.mcap"
    path.write_bytes(b"\x89MCAP0\r\n" + b"\x01" * 40)  # a cut-off file
    assert read_scene_updates(path) == []
    _write(tmp_path / "other.mcap", ("foxglove.Log", "jsonschema", b"{}"), "json", [(0, b"{}")])
    assert read_scene_updates(tmp_path / "other.mcap") == []
