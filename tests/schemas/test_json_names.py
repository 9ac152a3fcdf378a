"""Our schemas load in Rerun's and Foxglove's importers: protobuf JSON names are unique.

Rerun (0.41) refuses a whole MCAP file when two fields of one message share a JSON name up to
case (``x`` and ``X`` did in GroundTruthObject); logs written before the rename still replay.
"""

from __future__ import annotations

import importlib
from pathlib import Path

import pytest
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
from google.protobuf.timestamp_pb2 import Timestamp
from mcap.writer import Writer

from trackreplay.replay.log.groundtruth import read_groundtruth
from trackreplay.replay.log.reader import LogReader
from trackreplay.schemas import records as r
from trackreplay.schemas.generate import GEN_DIR


def _our_messages():
    for path in sorted(GEN_DIR.glob("*_pb2.py")):
        module = importlib.import_module(f"trackreplay.schemas._gen.{path.stem}")
        for desc in module.DESCRIPTOR.message_types_by_name.values():
            yield from _nested(desc)


def _nested(desc):
    yield desc
    for inner in desc.nested_types:
        yield from _nested(inner)


MESSAGES = list(_our_messages())


def test_every_proto_file_is_compiled() -> None:
    protos = {p.stem for p in (GEN_DIR.parent / "proto" / "trackreplay").glob("*.proto")}
    assert protos == {p.stem.removesuffix("_pb2") for p in GEN_DIR.glob("*_pb2.py")}
    assert "GroundPlane" in protos and len(MESSAGES) >= 8


@pytest.mark.parametrize("desc", MESSAGES, ids=lambda d: d.full_name)
def test_json_names_unique_ignoring_case(desc) -> None:
    names = [f.json_name.lower() for f in desc.fields] + [f.name.lower() for f in desc.fields]
    by_field = {}
    for f in desc.fields:
        for key in {f.json_name.lower(), f.name.lower()}:
            assert by_field.setdefault(key, f.name) == f.name, (
                f"{desc.full_name}: fields {by_field[key]!r} and {f.name!r} share the JSON name {key!r}")
    assert len(names) == 2 * len(desc.fields)


def _old_ground_truth_classes():
    """GroundTruthFrame as written before the rename: fields 6-8 named X, Y, Z."""
    from trackreplay.schemas._gen import GroundTruth_pb2

    fdp = descriptor_pb2.FileDescriptorProto()
    GroundTruth_pb2.DESCRIPTOR.CopyToProto(fdp)
    fdp.name = "trackreplay/GroundTruthOld.proto"
    for msg in fdp.message_type:
        if msg.name == "GroundTruthObject":
            for field in msg.field:
                if field.name.startswith("world_"):
                    field.name = field.name[-1].upper()
                    field.json_name = field.name
    pool = descriptor_pool.DescriptorPool()
    ts = descriptor_pb2.FileDescriptorProto()
    Timestamp.DESCRIPTOR.file.CopyToProto(ts)
    pool.Add(ts)
    pool.Add(fdp)
    frame_desc = pool.FindMessageTypeByName("trackreplay.GroundTruthFrame")
    return fdp, ts, message_factory.GetMessageClass(frame_desc)


def test_log_with_old_field_names_still_reads(tmp_path: Path) -> None:
    fdp, ts, OldFrame = _old_ground_truth_classes()
    msg = OldFrame(frame=0, t_ns=5)
    obj = msg.objects.add(id=1, x=10.0)
    obj.X, obj.Y, obj.Z = 1.5, -2.0, 3.25
    fds = descriptor_pb2.FileDescriptorSet(file=[ts, fdp])
    path = tmp_path / "old.mcap"
    with open(path, "wb") as fh:
        w = Writer(fh)
        w.start(profile="", library="test")
        sid = w.register_schema("trackreplay.GroundTruthFrame", "protobuf", fds.SerializeToString())
        cid = w.register_channel("/groundtruth/objects", "protobuf", sid)
        w.add_message(cid, 5, msg.SerializeToString(), 5)
        w.finish()
    table = read_groundtruth(LogReader(path))
    row = table.row(0, named=True)
    assert (row["x"], row["X"], row["Y"], row["Z"]) == (10.0, 1.5, -2.0, 3.25)
    assert row["y"] is None


def test_new_names_round_trip() -> None:
    obj = r.GroundTruthObject(3, x=1.0, X=2.0, Y=None, Z=-4.0)
    pb = obj.to_pb()
    assert pb.world_x == 2.0 and pb.HasField("world_z") and not pb.HasField("world_y")
    assert r.GroundTruthObject.from_pb(pb) == obj
