"""Reading an MCAP file cut short (the recorder was killed, the disk filled, the power went) and mending it.

Such a file has its header and every chunk written before the cut, then a partial record, and no summary
or footer, so readers that start from the summary refuse it. ``mcap``'s ``StreamReader`` reads records
from the start (the recovery path: no summary needed) until the cut; :func:`read_complete` gives what it
read -- every complete chunk, a chunk whose bytes do not decompress or whose CRC fails ends it -- and
:func:`recover` writes it again as a whole file, summary and index included, which every reader opens.
"""

from __future__ import annotations

import logging
from collections.abc import Iterator
from typing import Any

from mcap.records import Channel, Header, Message, Metadata, Schema
from mcap.stream_reader import StreamReader
from mcap.writer import CompressionType, Writer

log = logging.getLogger(__name__)

__all__ = ["read_complete", "recover", "Recovered"]


class Recovered:
    """What :func:`read_complete` found: ``profile``, ``schemas``, ``channels``, ``messages`` read,
    ``cut`` (why reading stopped, or "" when the file was whole)."""

    def __init__(self) -> None:
        self.profile = ""
        self.schemas: dict[int, Schema] = {}
        self.channels: dict[int, Channel] = {}
        self.metadata: list[Metadata] = []
        self.messages = 0
        self.cut = ""

    def __str__(self) -> str:
        return (f"{self.messages} messages on {len(self.channels)} channels recovered"
                + (f" (the file stops there: {self.cut})" if self.cut else " (the file was whole)"))


def read_complete(path: str, found: Recovered | None = None) -> Iterator[tuple[Channel, Message]]:
    """Every message of the complete chunks of ``path``, in file order; ``found`` is filled as it goes."""
    found = found if found is not None else Recovered()
    with open(path, "rb") as f:
        reader = StreamReader(f, validate_crcs=True, record_size_limit=1 << 30)
        records = reader.records
        while True:
            try:
                record: Any = next(records)
            except StopIteration:
                return
            except Exception as exc:  # noqa: BLE001 - the cut: a partial record, a bad chunk
                found.cut = f"{type(exc).__name__}: {exc}" if str(exc) else type(exc).__name__
                return
            if isinstance(record, Header):
                found.profile = record.profile
            elif isinstance(record, Schema):
                found.schemas[record.id] = record
            elif isinstance(record, Channel):
                found.channels[record.id] = record
            elif isinstance(record, Metadata):
                found.metadata.append(record)
            elif isinstance(record, Message):
                channel = found.channels.get(record.channel_id)
                if channel is None:
                    continue
                found.messages += 1
                yield channel, record


def recover(path: str, out: str, compression: str = "zstd") -> Recovered:
    """Write every message of ``path``'s complete chunks to ``out`` as a whole MCAP file."""
    found = Recovered()
    comp = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4, "none": CompressionType.NONE}[compression]
    with open(out, "wb") as f:
        writer = Writer(f, compression=comp)
        started = False
        schema_ids: dict[int, int] = {}
        channel_ids: dict[int, int] = {}
        for channel, message in read_complete(path, found):
            if not started:
                writer.start(profile=found.profile, library="rcon record --recover")
                for md in found.metadata:
                    writer.add_metadata(md.name, md.metadata)
                started = True
            if channel.id not in channel_ids:
                sid = 0
                if channel.schema_id:
                    if channel.schema_id not in schema_ids:
                        s = found.schemas[channel.schema_id]
                        schema_ids[channel.schema_id] = writer.register_schema(s.name, s.encoding, s.data)
                    sid = schema_ids[channel.schema_id]
                channel_ids[channel.id] = writer.register_channel(channel.topic, channel.message_encoding, sid,
                                                                  channel.metadata)
            writer.add_message(channel_ids[channel.id], message.log_time, message.data, message.publish_time,
                               message.sequence)
        if not started:
            if found.cut and not found.profile:
                raise ValueError(f"not an MCAP file, or cut before its first record ({found.cut})")
            writer.start(profile=found.profile, library="rcon record --recover")
        writer.finish()
    return found
