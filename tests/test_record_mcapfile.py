"""The recorder's own MCAP writer (``rcon_core/record/mcapfile.py``): what it leaves out (copies, CRCs,
compressing what is compressed already) and that readers RCON did not write still open its files: the
``mcap`` package's seeking reader and its streaming reader with CRC checks on, and ``rosbags``."""

from __future__ import annotations

import os
import random
from pathlib import Path
from typing import Any

import pytest
from mcap.reader import make_reader
from mcap.records import Chunk, DataEnd, Message
from mcap.stream_reader import StreamReader
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore

from rcon_core.msgs import TypeRegistry
from rcon_core.record.mcapfile import FAST_RATIO, SKIP_AFTER_POOR, McapFile
from rcon_core.record.schema import schema_for
from rcon_core.record.writer import McapSink, _DirectFile

REG2 = TypeRegistry.standard(ros2=True)


class Pieces:
    """A sink that keeps every object it was handed (to see that a message's bytes were not copied)."""

    def __init__(self, path: Path) -> None:
        self.file = _DirectFile(str(path))
        self.handed: list[Any] = []

    def write(self, data: Any) -> int:
        self.handed.append(data)
        return self.file.write(data)

    def writev(self, pieces: Any) -> int:
        self.handed.extend(pieces)
        return self.file.writev(pieces)

    def tell(self) -> int:
        return self.file.tell()


def image(i: int, w: int = 64, h: int = 48, noise: bool = False) -> bytes:
    data = os.urandom(w * h * 3) if noise else bytes((x + i) % 256 for x in range(w * h * 3))
    return REG2.serialize_cdr("sensor_msgs/Image", {
        "header": {"stamp": {"sec": i, "nanosec": 0}, "frame_id": "cam"}, "height": h, "width": w,
        "encoding": "rgb8", "is_bigendian": 0, "step": w * 3, "data": data})


def jpeg(i: int) -> bytes:
    return REG2.serialize_cdr("sensor_msgs/CompressedImage", {
        "header": {"stamp": {"sec": i, "nanosec": 0}, "frame_id": "cam"}, "format": "jpeg",
        "data": os.urandom(4000)})


def channel(f: McapFile, topic: str, type_name: str) -> int:
    s = schema_for(type_name, True, REG2)
    return f.add_channel(topic, s.message_encoding, f.add_schema(s.name, s.encoding, s.data))


def records(path: Path, *, chunks: bool = False) -> list[Any]:
    with open(path, "rb") as fh:
        return list(StreamReader(fh, emit_chunks=chunks, validate_crcs=True, record_size_limit=1 << 30).records)


@pytest.mark.parametrize("compression", ["zstd", "lz4", "none"])
def test_every_reader_opens_the_file_and_no_message_is_copied(tmp_path: Path, compression: str) -> None:
    path = tmp_path / f"w-{compression}.mcap"
    out = Pieces(path)
    f = McapFile(out, compression=compression, chunk_size=40_000)
    f.start("ros2", "rcon")
    f.add_metadata("rcon", {"robot": "boat"})
    cam, comp = channel(f, "/cam", "sensor_msgs/Image"), channel(f, "/cam/compressed", "sensor_msgs/CompressedImage")
    sent = []
    for i in range(60):
        data = image(i) if i % 3 else jpeg(i)
        ch = cam if i % 3 else comp
        f.add_message(ch, 1_000 + i, 2_000 + i, data)
        sent.append((ch, 1_000 + i, 2_000 + i, data))
        if i == 30:
            f.close_chunk()  # as the sink does after a second
    f.finish()
    out.file.close()
    if compression == "none":  # stored as they are: the very bytes objects reached the OS
        assert all(any(p is d for p in out.handed) for *_x, d in sent)

    # the mcap package's seeking reader (summary, chunk and message indexes)
    with open(path, "rb") as fh:
        reader = make_reader(fh)
        summary = reader.get_summary()
        got = [(m.channel_id, m.log_time, m.publish_time, m.data) for _s, _c, m in reader.iter_messages()]
        assert reader.get_header().profile == "ros2"
        assert [md.metadata for md in reader.iter_metadata()] == [{"robot": "boat"}]
    assert got == sent
    assert summary.statistics.message_count == 60 and summary.statistics.chunk_count == len(summary.chunk_indexes)
    assert summary.statistics.channel_message_counts == {cam: 40, comp: 20}
    assert (summary.statistics.message_start_time, summary.statistics.message_end_time) == (1_000, 1_059)
    # its streaming reader with CRC checks on (the summary's CRC is there; the data's are 0: not checked)
    recs = records(path)
    assert [(m.channel_id, m.log_time, m.publish_time, m.data) for m in recs if isinstance(m, Message)] == sent
    assert [r.data_section_crc for r in recs if isinstance(r, DataEnd)] == [0]
    chunks = [r for r in records(path, chunks=True) if isinstance(r, Chunk)]
    assert len(chunks) == summary.statistics.chunk_count and all(c.uncompressed_crc == 0 for c in chunks)
    # rosbags decodes every message from the schemas in the file
    n = 0
    with AnyReader([path], default_typestore=get_typestore(Stores.EMPTY)) as reader:
        for conn, _t, raw in reader.messages():
            msg = reader.deserialize(raw, conn.msgtype)
            n += 1
            assert msg.header.frame_id == "cam"
    assert n == 60


def test_payloads_compressed_already_are_stored_and_noise_is_not_compressed_in_vain(tmp_path: Path) -> None:
    path = tmp_path / "mixed.mcap"
    out = Pieces(path)
    f = McapFile(out, compression="zstd", chunk_size=1 << 30)
    f.start("ros2", "rcon")
    cam, comp = channel(f, "/cam", "sensor_msgs/Image"), channel(f, "/cam/compressed", "sensor_msgs/CompressedImage")
    f.add_message(cam, 1, 1, image(1))
    f.close_chunk()  # a raw picture: compressed
    for i in range(3):
        f.add_message(comp, 2 + i, 2 + i, jpeg(i))
    f.close_chunk()  # JPEG: stored as it is
    f.add_message(cam, 10, 10, image(2, noise=True))
    f.close_chunk()  # noise: compressed (in vain: the next chunks are stored)...
    for i in range(SKIP_AFTER_POOR):
        f.add_message(cam, 20 + i, 20 + i, image(i))
        f.close_chunk()
    f.add_message(cam, 40, 40, image(3))
    f.close_chunk()  # ...then compression is tried again
    f.finish()
    out.file.close()
    with open(path, "rb") as fh:
        reader = make_reader(fh)
        kinds = [c.compression for c in reader.get_summary().chunk_indexes]
        assert len(list(reader.iter_messages())) == 3 + 3 + SKIP_AFTER_POOR
    assert kinds == ["zstd", "", "zstd", *[""] * SKIP_AFTER_POOR, "zstd"]
    assert f.stored_chunks == 1 + SKIP_AFTER_POOR


def noisy_image(i: int, w: int = 160, h: int = 120) -> bytes:
    """A picture with a real sensor's noise: four flat bands (sky, shore, sea...) plus 0-7 of noise per byte
    (zstd level 3 keeps about 55 % of it, level 1 about 62 %)."""
    rng = random.Random(i)
    n = w * h * 3
    data = bytes(40 + 50 * (4 * x // n) + i + rng.getrandbits(3) for x in range(n))
    return REG2.serialize_cdr("sensor_msgs/Image", {
        "header": {"stamp": {"sec": i, "nanosec": 0}, "frame_id": "cam"}, "height": h, "width": w,
        "encoding": "rgb8", "is_bigendian": 0, "step": w * 3, "data": data})


def test_a_noisy_camera_is_compressed_at_the_fast_level_a_clean_one_is_not(tmp_path: Path) -> None:
    """zstd level 3 cost 6.1 ms a 640x480 frame of a noisy camera for 59 % of its size, level 1 1.1 ms for
    66 %: after a chunk keeps more than FAST_RATIO of its size, the next SKIP_AFTER_POOR chunks use level 1
    (then level 3 is tried again). Every message reads back."""
    sent: list[bytes] = []
    path = tmp_path / "noisy.mcap"
    out = Pieces(path)
    f = McapFile(out, compression="zstd", chunk_size=1 << 30)
    f.start("ros2", "rcon")
    cam = channel(f, "/cam", "sensor_msgs/Image")
    for i in range(1 + SKIP_AFTER_POOR):  # the first at level 3 (moderate), then the fast level
        sent.append(noisy_image(i))
        f.add_message(cam, i + 1, i + 1, sent[-1])
        f.close_chunk()
    assert f.fast_chunks == SKIP_AFTER_POOR and f.stored_chunks == 0
    for i in range(3):  # clean pictures after: level 3 again, and it stays there
        sent.append(image(i))
        f.add_message(cam, 100 + i, 100 + i, sent[-1])
        f.close_chunk()
    assert f.fast_chunks == SKIP_AFTER_POOR
    f.finish()
    out.file.close()
    with open(path, "rb") as fh:
        reader = make_reader(fh)
        summary = reader.get_summary()
        assert all(c.compression == "zstd" for c in summary.chunk_indexes)
        first = summary.chunk_indexes[0]
        assert first.compressed_size > FAST_RATIO * first.uncompressed_size  # noisy: moderately compressible
        assert [m.data for _s, _c, m in reader.iter_messages()] == sent


def test_the_sink_writes_through_it_and_a_file_cut_short_is_recovered(tmp_path: Path) -> None:
    """The recorder's sink (its thread) on this writer; the first chunks of a file whose end is lost are
    read by the recovery path (StreamReader, CRC checks on)."""
    from rcon_core.record.recover import Recovered, read_complete

    path = tmp_path / "cut.mcap"
    sink = McapSink(str(path), "ros2", chunk_size=20_000)
    s = schema_for("sensor_msgs/Image", True, REG2)
    sink.add_channel("/cam", s.name, s.encoding, s.data, s.message_encoding)
    for i in range(40):
        assert sink.write("/cam", i, i, image(i))
    sink.close()
    assert sink.stats.messages == 40 and sink.problem is None
    whole = path.read_bytes()
    cut = tmp_path / "cut-short.mcap"
    cut.write_bytes(whole[: len(whole) * 2 // 3])
    found = Recovered()
    got = list(read_complete(str(cut), found))
    assert found.cut and 10 <= len(got) < 40
    assert [m.log_time for _c, m in got] == list(range(len(got)))
