"""Opening any recording: a bare MCAP file, a rosbag1 ``.bag``, a rosbag2 folder (sqlite3 or mcap storage).

``open_recording(path)`` gives a :class:`Recording`: its topics (:class:`Track`: type, definition text,
encoding, latched), its flavour (``ros2``), start, end, and the messages as serialized bytes in log-time
order from any time on (``messages(start_ns)``), plus the latest message of each topic before a time
(``latest_before(t)``, what a seek shows). Nothing is decoded here; ``sim/playback.py`` decodes what a
subscriber needs, with the definitions the file carries.

Decisions:

* MCAP files are read with the ``mcap`` package's seeking reader (chunk indexes: a seek reads only the
  chunks it needs); a file without a summary (cut short) is refused with the way to mend it
  (``rcon record --recover``). Channels may be ``ros1`` (profile ros1, ``ros1msg`` schemas), ``cdr``
  (``ros2msg``) or schema-less ``json``.
* Bags are read with ``rosbags`` (``AnyReader``): rosbag1 gives ROS 1 bytes, rosbag2 gives CDR; their
  ``msgdef`` texts are the definitions, and rosbags' own store fills in for a rosbag2 that has none.
* Latched: a rosbag1 connection's ``latching``, a rosbag2 topic offered ``transient_local``, an MCAP
  channel's ``latching`` metadata; also a topic with at most two messages in the whole file, and the usual
  latched names (``/map``, ``/tf_static``, ``/robot_description``), so a late subscriber still gets them.
"""

from __future__ import annotations

import heapq
import logging
import os
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from rcon_core.msgs import names

log = logging.getLogger(__name__)

__all__ = ["Track", "Recording", "RecordingError", "open_recording"]

LATCHED_NAMES = ("/map", "/tf_static", "/robot_description")


class RecordingError(ValueError):
    """A file that cannot be played, with the reason in words."""


class Track:
    """One topic of a recording."""

    __slots__ = ("topic", "type", "definition", "encoding", "latched", "count", "ids")

    def __init__(self, topic: str, type_name: str, definition: str, encoding: str, latched: bool,
                 count: int) -> None:
        self.topic = topic
        self.type = names.normalize(type_name) if "/" in type_name else type_name
        self.definition = definition  #: the full definition text ("" when the file has none)
        self.encoding = encoding  #: "ros1", "cdr" or "json"
        self.latched = latched
        self.count = count
        self.ids: list[Any] = []  # the reader's channel/connection ids of this topic

    def __repr__(self) -> str:
        return f"<Track {self.topic} [{self.type}] {self.encoding} x{self.count}{' latched' if self.latched else ''}>"


class Recording:
    """A recording opened for reading (see the module docstring). Close it when done."""

    kind = ""
    path = ""
    ros2 = False
    tracks: dict[str, Track]
    start_ns = 0
    end_ns = 0

    @property
    def duration(self) -> float:
        return max(0.0, (self.end_ns - self.start_ns) / 1e9)

    @property
    def message_count(self) -> int:
        return sum(t.count for t in self.tracks.values())

    def messages(self, start_ns: int | None = None) -> Iterator[tuple[str, int, bytes]]:
        """``(topic, log_time_ns, data)`` in log-time order, from ``start_ns`` (inclusive) on."""
        raise NotImplementedError

    def latest_before(self, t_ns: int, topics: list[str] | None = None) -> dict[str, tuple[int, bytes]]:
        """``{topic: (log_time_ns, data)}``: each topic's last message before ``t_ns``."""
        raise NotImplementedError

    def close(self) -> None:
        return None

    def __enter__(self) -> Recording:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _mark_latched(self) -> None:
        for t in self.tracks.values():
            if t.count <= 2 or t.topic in LATCHED_NAMES or t.topic.endswith(LATCHED_NAMES):
                t.latched = True
        self._check_definitions()

    def _check_definitions(self) -> None:
        """Drop a definition that has only part of a known type's fields (``schema.truncated``)."""
        from rcon_core.msgs import TypeRegistry

        from .schema import truncated

        reg = None
        for t in self.tracks.values():
            if not t.definition or t.encoding == "json":
                continue
            reg = reg or TypeRegistry.standard(ros2=self.ros2)
            if truncated(reg, t.type, t.definition):
                log.warning("%s: the file's definition of %s (%s) has only some of its fields; using the "
                            "standard definition", self.path, t.type, t.topic)
                t.definition = ""


def open_recording(path: str | os.PathLike[str]) -> Recording:
    """Open ``path``: ``.mcap`` file, ``.bag`` file or a rosbag2 folder; RecordingError when it cannot."""
    p = Path(path)
    if not p.exists():
        raise RecordingError(f"{p}: no such file or folder")
    if p.is_dir() or p.suffix == ".bag" or (p.suffix == ".db3"):
        return BagRecording(p.parent if p.suffix == ".db3" else p)
    if p.suffix == ".mcap" or _is_mcap(p):
        return McapRecording(p)  # a rosbag2 folder's own .mcap file reads the same way
    raise RecordingError(f"{p}: not a recording RCON can play (an .mcap file, a .bag file or a rosbag2 folder)")


def _ends_whole(p: Path) -> bool:
    """An MCAP file that was closed ends with the magic bytes after its footer."""
    try:
        with open(p, "rb") as f:
            f.seek(-8, os.SEEK_END)
            return f.read(8) == b"\x89MCAP0\r\n"
    except OSError:
        return False


def _is_mcap(p: Path) -> bool:
    try:
        with open(p, "rb") as f:
            return f.read(8) == b"\x89MCAP0\r\n"
    except OSError:
        return False


# ---------------------------------------------------------------------------------------------- MCAP


class McapRecording(Recording):
    kind = "mcap"

    def __init__(self, path: Path) -> None:
        from mcap.reader import make_reader

        self.path = str(path)
        if _is_mcap(path) and not _ends_whole(path):
            raise RecordingError(f"{path}: the file stops short, without its summary (was the recorder killed?); "
                                 f"mend it with rcon record --recover {path}")
        self._file = open(path, "rb")  # noqa: SIM115 - kept open while playing
        try:
            self._reader = make_reader(self._file)
            header = self._reader.get_header()
            summary = self._reader.get_summary()
        except Exception as exc:  # noqa: BLE001
            self._file.close()
            raise RecordingError(f"{path}: not a readable MCAP file ({exc})") from None
        if summary is None:
            self._file.close()
            raise RecordingError(f"{path}: the file has no summary (was the recorder killed?); mend it with "
                                 f"rcon record --recover {path}")
        self.tracks = {}
        counts = summary.statistics.channel_message_counts if summary.statistics else {}
        encodings = {c.message_encoding for c in summary.channels.values()}
        self.ros2 = header.profile == "ros2" or (header.profile != "ros1" and "cdr" in encodings)
        for cid, ch in summary.channels.items():
            schema = summary.schemas.get(ch.schema_id)
            enc = ch.message_encoding
            if enc not in ("ros1", "cdr", "json"):
                log.warning("%s: channel %s has message encoding %r, which RCON cannot play; left out",
                            path, ch.topic, enc)
                continue
            if schema is not None and schema.encoding not in ("ros1msg", "ros2msg"):
                log.warning("%s: channel %s has a %s schema, which RCON cannot read; left out",
                            path, ch.topic, schema.encoding)
                continue
            if enc == "json":
                type_name = ch.metadata.get("type", "") or (schema.name if schema else "")
                definition = ""
            else:
                if schema is None:
                    continue
                type_name, definition = schema.name, schema.data.decode("utf-8", "replace")
            track = self.tracks.get(ch.topic)
            if track is None:
                latched = ch.metadata.get("latching", "") in ("1", "true")
                track = self.tracks[ch.topic] = Track(ch.topic, type_name, definition, enc, latched, 0)
            track.ids.append(cid)
            track.count += counts.get(cid, 0)
        st = summary.statistics
        if st is not None and st.message_count:
            self.start_ns, self.end_ns = st.message_start_time, st.message_end_time
        elif summary.chunk_indexes:
            self.start_ns = min(c.message_start_time for c in summary.chunk_indexes)
            self.end_ns = max(c.message_end_time for c in summary.chunk_indexes)
        self._mark_latched()

    def messages(self, start_ns: int | None = None) -> Iterator[tuple[str, int, bytes]]:
        topics = list(self.tracks)
        for _schema, channel, message in self._reader.iter_messages(topics=topics, starting_at=start_ns,
                                                                   log_time_order=True):
            yield channel.topic, message.log_time, message.data

    def latest_before(self, t_ns: int, topics: list[str] | None = None) -> dict[str, tuple[int, bytes]]:
        out: dict[str, tuple[int, bytes]] = {}
        for topic in topics if topics is not None else list(self.tracks):
            for _s, _c, message in self._reader.iter_messages(topics=[topic], ending_before=t_ns,
                                                             log_time_order=True, reverse=True):
                out[topic] = (message.log_time, message.data)
                break
        return out

    def close(self) -> None:
        self._file.close()


# ---------------------------------------------------------------------------------------------- bags


class BagRecording(Recording):
    def __init__(self, path: Path) -> None:
        from rosbags.highlevel import AnyReader

        self.path = str(path)
        try:
            self._reader = AnyReader(_bag_files(path))
            self._reader.open()
        except Exception as exc:  # noqa: BLE001
            raise RecordingError(f"{path}: not a readable bag ({exc})") from None
        self.ros2 = bool(self._reader.is2)
        self.kind = "rosbag2" if self.ros2 else "rosbag1"
        self.tracks = {}
        self._conns: dict[str, list[Any]] = {}
        for c in self._reader.connections:
            definition = c.msgdef.data if c.msgdef is not None and c.msgdef.format.name == "MSG" else ""
            latched = False
            ext = c.ext
            if hasattr(ext, "latching"):
                latched = bool(getattr(ext, "latching", 0))
            else:
                for q in getattr(ext, "offered_qos_profiles", None) or []:
                    durability = getattr(q, "durability", "")
                    if "transient" in str(durability).lower() or durability == 1:
                        latched = True
            track = self.tracks.get(c.topic)
            if track is None:
                track = self.tracks[c.topic] = Track(c.topic, c.msgtype, definition, "cdr" if self.ros2 else "ros1",
                                                     latched, 0)
            track.count += c.msgcount
            track.latched = track.latched or latched
            self._conns.setdefault(c.topic, []).append(c)
        self.start_ns, self.end_ns = self._reader.start_time, self._reader.end_time
        self._mark_latched()

    def messages(self, start_ns: int | None = None) -> Iterator[tuple[str, int, bytes]]:
        for c, t, data in self._reader.messages(start=start_ns):
            yield c.topic, t, bytes(data)

    def latest_before(self, t_ns: int, topics: list[str] | None = None) -> dict[str, tuple[int, bytes]]:
        out: dict[str, tuple[int, bytes]] = {}
        wanted = [t for t in (topics if topics is not None else list(self.tracks)) if t in self._conns]
        window = 1_000_000_000
        while wanted:
            lo = max(self.start_ns, t_ns - window)
            conns = [c for t in wanted for c in self._conns[t]]
            last: dict[str, tuple[int, bytes]] = {}
            for c, t, data in self._reader.messages(connections=conns, start=lo, stop=t_ns):
                last[c.topic] = (t, bytes(data))
            out.update(last)
            wanted = [t for t in wanted if t not in last]
            if lo <= self.start_ns:
                break
            window *= 10
        return out

    def close(self) -> None:
        try:
            self._reader.close()
        except Exception:  # noqa: BLE001
            pass


def _bag_files(path: Path) -> list[Path]:
    """What rosbags opens: a rosbag1 file, or a rosbag2 folder's storage files themselves. (Through the
    folder rosbags matches each topic's QoS in metadata.yaml with the storage's, and real bags whose two
    differ -- rosbag2's own test bags do -- then yield no message at all.)"""
    if not path.is_dir():
        return [path]
    meta = path / "metadata.yaml"
    if meta.exists():
        import yaml

        try:
            info = yaml.safe_load(meta.read_text())["rosbag2_bagfile_information"]
            files = [path / f for f in info.get("relative_file_paths", [])]
            if files and all(f.exists() for f in files):
                return files
        except Exception as exc:  # noqa: BLE001
            log.debug("%s: metadata.yaml not read (%s)", path, exc)
    files = sorted(path.glob("*.mcap")) + sorted(path.glob("*.db3"))
    return files or [path]


def merge(*streams: Iterator[tuple[str, int, bytes]]) -> Iterator[tuple[str, int, bytes]]:
    """Several message streams in log-time order (for recordings split over files)."""
    return heapq.merge(*streams, key=lambda m: m[1])
