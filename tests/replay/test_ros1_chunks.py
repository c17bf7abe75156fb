"""ROS1 chunks finished on a worker thread: the bytes of rosbags' own writer."""

from __future__ import annotations

import random
from pathlib import Path

import pytest
from rosbags.rosbag1 import Reader, Writer
from rosbags.typesys import Stores, get_typestore

from replay.formats.ros1.chunks import ThreadedRos1Writer

TYPESTORE = get_typestore(Stores.ROS1_NOETIC)


def write_sample(writer: Writer, compression: Writer.CompressionFormat | None) -> None:
    """Two connections (the second added between messages), log times that sometimes go
    back, a chunk completed early, random sizes over many chunks."""
    rng = random.Random(3)
    if compression is not None:
        writer.set_compression(compression)
    writer.open()
    first = writer.add_connection("/a", "std_msgs/msg/String", typestore=TYPESTORE)
    second = None
    stamp = 1_700_000_000_999_000_000
    for index in range(1500):
        if index == 400:
            second = writer.add_connection("/b", "std_msgs/msg/Int8", typestore=TYPESTORE)
        connection = first if second is None or rng.random() < 0.5 else second
        stamp += rng.randint(-3, 40_000_000)
        writer.write(connection, stamp, rng.randbytes(rng.randint(0, 3000)))
        if index == 700:
            writer.write_chunk(writer.chunks[-1])
    writer.close()


@pytest.mark.slow
@pytest.mark.parametrize("compression", [Writer.CompressionFormat.LZ4,
                                         Writer.CompressionFormat.BZ2, None])
def test_same_bytes_as_rosbags_writer(compression: Writer.CompressionFormat | None,
                                      tmp_path: Path) -> None:
    theirs, ours = tmp_path / "theirs.bag", tmp_path / "ours.bag"
    write_sample(Writer(theirs), compression)
    writer = ThreadedRos1Writer(ours)
    writer.chunk_threshold = 64 * 1024  # many chunks, each finished by the worker
    write_sample(writer, compression)
    reference = Writer(tmp_path / "reference.bag")
    reference.chunk_threshold = 64 * 1024
    write_sample(reference, compression)
    assert ours.read_bytes() == (tmp_path / "reference.bag").read_bytes()
    with Reader(ours) as reader, Reader(theirs) as original:
        assert len(reader.chunk_infos) > 30
        assert [(c.topic, t, bytes(d)) for c, t, d in reader.messages()] == \
            [(c.topic, t, bytes(d)) for c, t, d in original.messages()]
