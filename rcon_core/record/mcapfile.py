"""``McapFile``: one chunked, indexed MCAP file written with no copy of a message's bytes in the process.

The recorder's hot path (``writer.py``'s thread) writes every message through here. The ``mcap`` package's
own ``Writer`` copies each message's bytes four times (into its chunk buffer, out of it, into the record
buffer, out of that), computes a CRC-32 of every chunk and compresses every chunk, which made recording a
raw camera cost more than twice the CPU of merely receiving it. Here:

* **No copy of the payload.** A chunk is a list of pieces (each message's 31-byte record head, then the
  message's own bytes object); an uncompressed chunk goes to the OS with one ``writev`` of those pieces;
  a compressed one is fed to zstd as a stream (its size pledged: the content size in the frame header),
  or joined once for lz4.
* **No CRC of the data.** The MCAP specification lets a writer leave a chunk's ``uncompressed_crc`` and
  the data end's ``data_section_crc`` at 0 ("not available": readers skip the check; ``mcap``'s reader and
  ``rosbags`` do). The summary's CRC is kept: it is small.
* **No compression of what is compressed already.** A chunk whose bytes are mostly payloads that are
  compressed already (JPEG/PNG ``CompressedImage``, video packets, compressed point clouds: by schema
  name, :data:`COMPRESSED_TYPES`) is stored as it is (compression ``""``, which the format allows per
  chunk). And a chunk that compressed to more than 90 % of its size makes the next
  :data:`SKIP_AFTER_POOR` chunks be stored too (then compression is tried again): noise, or a format not
  in the list, is not compressed in vain. Between the two, a zstd chunk that kept more than
  :data:`FAST_RATIO` of its size makes the next :data:`SKIP_AFTER_POOR` chunks use zstd's fast level
  (:data:`FAST_LEVEL`): a real camera's raw frames (sensor noise) cost 6.1 ms a 640x480 frame at level 3
  for 59 % of the size, 1.1 ms at level 1 for 66 %; the sim's clean pictures stay at level 3 (0.35 ms, 0.5 %).
* **The rest of the format** (header, schemas, channels, metadata, message indexes, chunk indexes,
  statistics, summary offsets, footer) is written with the ``mcap`` package's own record classes: those
  records are few and small.

Layout: the same as the ``mcap`` writer's (schemas and channels inside the chunk that follows their
registration, a message index per channel after each chunk, a summary with schemas, channels,
statistics, chunk and metadata indexes, and summary offsets), so ``mcap``'s seeking and streaming readers,
``rosbags``, Foxglove and the crash recovery (``recover.py``) read it as before. No Qt, no threads: the
caller (``McapSink``'s writer thread) owns it.
"""

from __future__ import annotations

import struct
import zlib
from collections.abc import Callable, Iterator, Sequence
from typing import Any, Protocol

from mcap.data_stream import RecordBuilder
from mcap.opcode import Opcode
from mcap.records import (
    Channel,
    ChunkIndex,
    DataEnd,
    Footer,
    Header,
    McapRecord,
    MessageIndex,
    Metadata,
    MetadataIndex,
    Schema,
    Statistics,
    SummaryOffset,
)

__all__ = ["McapFile", "COMPRESSED_TYPES", "SKIP_AFTER_POOR", "FAST_LEVEL", "FAST_RATIO", "MAGIC"]

MAGIC = b"\x89MCAP0\r\n"
#: schema names (``pkg/Type``, ``pkg/msg/Type``) whose payloads are compressed already: never compressed again
COMPRESSED_TYPES = frozenset({
    "sensor_msgs/CompressedImage",
    "theora_image_transport/Packet",
    "ffmpeg_image_transport_msgs/FFMPEGPacket",
    "foxglove_msgs/CompressedVideo",
    "foxglove_msgs/CompressedImage",
    "point_cloud_interfaces/CompressedPointCloud2",
    "draco_point_cloud_transport/CompressedPointCloud2",
    "zstd_image_transport/ZstdPacket",
})
#: after a chunk compressed poorly (> :data:`POOR_RATIO` of its size), the next chunks stored as they are
SKIP_AFTER_POOR = 8
POOR_RATIO = 0.9
#: after a zstd chunk kept more than this of its size, the next chunks are compressed at FAST_LEVEL
FAST_RATIO = 0.5
#: zstd's level for those chunks (the default level is 3)
FAST_LEVEL = 1

_MESSAGE = struct.Struct("<BQHIQQ")  # opcode, record length, channel id, sequence, log time, publish time
_MESSAGE_FIXED = 2 + 4 + 8 + 8
_CHUNK_HEAD = struct.Struct("<BQQQQI")  # opcode, length, start, end, uncompressed size, uncompressed crc
_U32 = struct.Struct("<I")
_U64 = struct.Struct("<Q")


class Sink(Protocol):
    """Where the bytes go: ``write(bytes)``, ``writev(pieces)`` (each to the OS at once), ``tell()``."""

    def write(self, data: bytes | bytearray | memoryview) -> int: ...

    def writev(self, pieces: Sequence[bytes | bytearray | memoryview]) -> int: ...

    def tell(self) -> int: ...


def _bare(name: str) -> str:
    """``pkg/msg/Type`` -> ``pkg/Type`` (ROS 2 spelling to ROS 1)."""
    parts = name.split("/")
    return f"{parts[0]}/{parts[-1]}" if len(parts) == 3 else name


def _record(record: McapRecord) -> bytes:
    builder = RecordBuilder()
    record.write(builder)
    return builder.end()


#: pieces shorter than this are joined into runs before they are fed to the compressor (record heads,
#: small messages); longer ones (camera frames) are fed as they are, never copied
_SMALL_PIECE = 4096


def _runs(pieces: list[Any]) -> Iterator[Any]:
    """``pieces`` with each run of small ones joined: what a streaming compressor is fed."""
    small: list[Any] = []
    for piece in pieces:
        if len(piece) < _SMALL_PIECE:
            small.append(piece)
            continue
        if small:
            yield b"".join(small)
            small = []
        yield piece
    if small:
        yield b"".join(small)


def _compressor(compression: str) -> Callable[[list[Any], int, bool], bytes]:
    """``compress(pieces, size, fast)`` for ``zstd`` (level 3, or :data:`FAST_LEVEL` when ``fast``; the
    content size in the frame header) or ``lz4`` (frame; ``fast`` changes nothing). zstd is fed as a stream
    with the chunk's ``size`` pledged, which gives it the parameters of its one-shot call (the same ratio)
    without joining the chunk first: a chunk of the sim's camera frames 1.3 ms instead of 1.9 ms (the join
    was a copy of every frame), a noisy camera's chunk the same ratio and time."""
    if compression == "zstd":
        import zstandard

        normal = zstandard.ZstdCompressor(level=3, write_content_size=True)
        quick = zstandard.ZstdCompressor(level=FAST_LEVEL, write_content_size=True)

        def zstd(pieces: list[Any], size: int, fast: bool) -> bytes:
            stream = (quick if fast else normal).compressobj(size=size)
            out = [stream.compress(run) for run in _runs(pieces)]
            out.append(stream.flush())
            return b"".join(out)

        return zstd
    if compression == "lz4":
        import lz4.frame

        return lambda pieces, size, fast: lz4.frame.compress(b"".join(pieces), store_size=True)
    raise ValueError(f"compression must be zstd, lz4 or none; got {compression!r}")


class McapFile:
    """One MCAP file being written to ``out`` (see the module docstring). ``compression``: ``zstd``,
    ``lz4`` or ``none``; a chunk is closed once it holds ``chunk_size`` bytes (or when told)."""

    def __init__(self, out: Sink, *, compression: str = "zstd", chunk_size: int = 4 << 20) -> None:
        self.out = out
        self.compression = "" if compression == "none" else compression
        self._compress = _compressor(self.compression) if self.compression else None
        self.chunk_size = chunk_size
        self.schemas: dict[int, Schema] = {}
        self.channels: dict[int, Channel] = {}
        self._compressed_channel: set[int] = set()
        self._chunk_indexes: list[ChunkIndex] = []
        self._metadata_indexes: list[MetadataIndex] = []
        self._counts: dict[int, int] = {}
        self.message_count = 0
        self.chunk_count = 0
        self.stored_chunks = 0  #: chunks written without compression (their payloads are compressed already)
        self.fast_chunks = 0  #: chunks compressed at zstd's fast level (after one that compressed moderately)
        self._start_time = 0
        self._end_time = 0
        self._skip = 0  # chunks still to store as they are after a poor one
        self._fast = 0  # chunks still to compress at the fast level after a moderate one
        self._finished = False
        self._pieces: list[Any] = []  # the open chunk: record heads and the messages' own bytes
        self._index: dict[int, list[tuple[int, int]]] = {}  # channel id -> (log time, offset in the chunk)
        self._size = 0
        self._messages = 0
        self._compressed_bytes = 0
        self._chunk_start = 0
        self._chunk_end = 0

    # ------------------------------------------------------------------ records

    def start(self, profile: str, library: str) -> None:
        self.out.write(MAGIC + _record(Header(profile=profile, library=library)))

    def add_metadata(self, name: str, data: dict[str, str]) -> None:
        self.close_chunk()
        offset = self.out.tell()
        record = _record(Metadata(name=name, metadata=dict(data)))
        self.out.write(record)
        self._metadata_indexes.append(MetadataIndex(offset=offset, length=len(record), name=name))

    def add_schema(self, name: str, encoding: str, data: bytes) -> int:
        schema = Schema(id=len(self.schemas) + 1, name=name, encoding=encoding, data=data)
        self.schemas[schema.id] = schema
        self._add_piece(_record(schema))
        return schema.id

    def add_channel(self, topic: str, message_encoding: str, schema_id: int,
                    metadata: dict[str, str] | None = None) -> int:
        channel = Channel(id=len(self.channels) + 1, topic=topic, message_encoding=message_encoding,
                          schema_id=schema_id, metadata=dict(metadata or {}))
        self.channels[channel.id] = channel
        schema = self.schemas.get(schema_id)
        if schema is not None and _bare(schema.name) in COMPRESSED_TYPES:
            self._compressed_channel.add(channel.id)
        self._add_piece(_record(channel))
        return channel.id

    def add_message(self, channel_id: int, log_time: int, publish_time: int, data: bytes | memoryview,
                    sequence: int = 0) -> None:
        """Add one message to the open chunk (its bytes are kept, not copied, until the chunk is written)."""
        size = len(data)
        index = self._index.get(channel_id)
        if index is None:
            index = self._index[channel_id] = []
        index.append((log_time, self._size))
        self._pieces.append(_MESSAGE.pack(Opcode.MESSAGE, _MESSAGE_FIXED + size, channel_id, sequence, log_time,
                                          publish_time))
        self._pieces.append(data)
        self._size += _MESSAGE.size + size
        if channel_id in self._compressed_channel:
            self._compressed_bytes += size
        if self._messages == 0 or log_time < self._chunk_start:
            self._chunk_start = log_time
        if log_time > self._chunk_end:
            self._chunk_end = log_time
        self._messages += 1
        self._counts[channel_id] = self._counts.get(channel_id, 0) + 1
        if self.message_count == 0 or log_time < self._start_time:
            self._start_time = log_time
        if log_time > self._end_time:
            self._end_time = log_time
        self.message_count += 1
        if self._size >= self.chunk_size:
            self.close_chunk()

    @property
    def open_bytes(self) -> int:
        """Bytes in the chunk not written yet."""
        return self._size

    # ------------------------------------------------------------------ chunks

    def _reset_chunk(self) -> None:
        self._pieces = []
        self._index = {}
        self._size = 0
        self._messages = 0
        self._compressed_bytes = 0
        self._chunk_start = 0
        self._chunk_end = 0

    def _add_piece(self, record: bytes) -> None:
        self._pieces.append(record)
        self._size += len(record)

    def _compression_for_chunk(self) -> str:
        if not self.compression:
            return ""
        if self._compressed_bytes * 2 >= self._size:  # mostly JPEG, video...: compressed already
            return ""
        if self._skip > 0:
            self._skip -= 1
            return ""
        return self.compression

    def close_chunk(self) -> None:
        """Write the open chunk (if it holds a message) and its message indexes."""
        if self._messages == 0:
            return
        pieces, size = self._pieces, self._size
        compression = self._compression_for_chunk()
        body: list[Any]
        if compression and self._compress is not None:
            fast = self._fast > 0
            if fast:
                self._fast -= 1
                self.fast_chunks += 1
            packed = self._compress(pieces, size, fast)
            if len(packed) > POOR_RATIO * size:
                self._skip, self._fast = SKIP_AFTER_POOR, 0
            elif not fast and compression == "zstd" and len(packed) > FAST_RATIO * size:
                self._fast = SKIP_AFTER_POOR
            body = [packed]
            body_size = len(packed)
        else:
            compression = ""
            body = pieces
            body_size = size
            self.stored_chunks += bool(self.compression)
        name = compression.encode()
        length = 8 + 8 + 8 + 4 + 4 + len(name) + 8 + body_size
        head = (_CHUNK_HEAD.pack(Opcode.CHUNK, length, self._chunk_start, self._chunk_end, size, 0)
                + _U32.pack(len(name)) + name + _U64.pack(body_size))
        chunk_start = self.out.tell()
        self.out.writev([head, *body])
        chunk_length = 9 + length
        offsets: dict[int, int] = {}
        indexes = bytearray()
        index_start = self.out.tell()
        for channel_id, entries in self._index.items():
            offsets[channel_id] = index_start + len(indexes)
            indexes += _record(MessageIndex(channel_id=channel_id, records=entries))
        self.out.write(bytes(indexes))
        self._chunk_indexes.append(ChunkIndex(
            message_start_time=self._chunk_start, message_end_time=self._chunk_end,
            chunk_start_offset=chunk_start, chunk_length=chunk_length, message_index_offsets=offsets,
            message_index_length=len(indexes), compression=compression, compressed_size=body_size,
            uncompressed_size=size))
        self.chunk_count += 1
        self._reset_chunk()

    # ------------------------------------------------------------------ the end

    def finish(self) -> None:
        """Close the open chunk, write the data end, the summary, the footer and the closing magic."""
        if self._finished:
            return
        self._finished = True
        self.close_chunk()
        self.out.write(_record(DataEnd(data_section_crc=0)))
        summary_start = self.out.tell()
        summary = bytearray()
        offsets: list[SummaryOffset] = []

        def group(opcode: int, records: list[Any]) -> None:
            start = len(summary)
            for r in records:
                summary.extend(_record(r))
            offsets.append(SummaryOffset(group_opcode=opcode, group_start=summary_start + start,
                                         group_length=len(summary) - start))

        stats = Statistics(message_count=self.message_count, schema_count=len(self.schemas),
                           channel_count=len(self.channels), attachment_count=0,
                           metadata_count=len(self._metadata_indexes), chunk_count=self.chunk_count,
                           message_start_time=self._start_time, message_end_time=self._end_time,
                           channel_message_counts=dict(self._counts))
        group(Opcode.SCHEMA, list(self.schemas.values()))
        group(Opcode.CHANNEL, list(self.channels.values()))
        group(Opcode.STATISTICS, [stats])
        group(Opcode.CHUNK_INDEX, self._chunk_indexes)
        group(Opcode.ATTACHMENT_INDEX, [])
        group(Opcode.METADATA_INDEX, self._metadata_indexes)
        offset_start = summary_start + len(summary)
        for o in offsets:
            summary.extend(_record(o))
        crc = zlib.crc32(bytes(summary))
        crc = zlib.crc32(struct.pack("<BQQQ", Opcode.FOOTER, 8 + 8 + 4, summary_start, offset_start), crc)
        self.out.write(bytes(summary))
        self.out.write(_record(Footer(summary_start=summary_start, summary_offset_start=offset_start,
                                      summary_crc=crc)) + MAGIC)
