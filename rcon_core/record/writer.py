"""``McapSink``: the one writer of a recording -- an MCAP file written in its own thread.

Threading: ``add_channel`` and ``write`` may be called from any thread (the bridge loop calls them from a
message callback); they only queue. One writer thread owns the ``McapFile`` (``mcapfile.py``) and the file, so
compressing a chunk never holds up the bridge loop or the GUI.

Decisions:

* **Chunked, compressed, indexed.** Chunks of ``chunk_size`` (4 MB) compressed with zstd (or lz4, or
  none), message indexes after each chunk, and a summary (schemas, channels, statistics, chunk indexes)
  when the file is closed: Foxglove, Lichtblick, ``rosbags`` and the ``mcap`` reader open it. The file is
  written by :class:`~rcon_core.record.mcapfile.McapFile`: no copy of a message's bytes, no CRC of the
  data (the format allows 0), no compression of a chunk of payloads compressed already (JPEG...).
* **A crash loses at most the open chunk.** A chunk is also closed after ``chunk_seconds`` (1 s) however
  small, and every record goes straight to the OS (no buffer in the process), so after SIGKILL or a power
  cut of the process the file holds every complete chunk: ``recover.py`` rewrites it with a summary
  (``rcon record --recover``).
* **The writer thread wakes per batch, not per message.** ``write`` appends to a deque; the thread is
  woken once ``wake_bytes`` (the chunk size) are queued, else every ``wake_every`` (0.1 s): a camera's
  frames do not cost a thread switch (and a fight for the GIL) each. It then writes the batch in one tight
  run (``_write_run``): the budget, split and chunk-age checks are made once for the run, not per
  message, as long as no message of it can reach an edge (then one at a time): about 1.9 us of the
  writer's CPU a small message instead of 2.7.
* **The writer runs in the background** (``priority.lower_this_thread``: SCHED_BATCH, nice 5). Compressing
  a camera's frames costs more CPU than receiving them; at normal priority on a 2-core machine beside the
  robot's process the writer preempted the thread that receives about 40 times a second (``rcon record``
  of a 120 Hz camera; about once after), and in the app it would compete with the bridge loop that times
  the teleop pad. It only needs to keep up on average: the queue below absorbs the rest.
* **Nothing blocks the sender.** The queue is bounded in bytes (``max_queue``, 256 MB); a message that
  would pass it is dropped and counted (``stats.dropped``) -- the bench checks none is at the fleet's rate.
* **Disk budget.** ``budget`` bytes (None: none): ``warning`` is set once 90 % is used, and at 100 %
  the file is closed properly and later messages are dropped and counted.
* **Disk full or any write error** (``OSError``): the recorder stops writing, says what happened in
  ``problem``, keeps counting what it drops, and tries to close the file; what was written up to the last
  complete chunk stays readable.
* **Split.** With ``split_size`` the file is closed once it passes that size and the next one opened,
  ``run.mcap`` then ``run_1.mcap``, ``run_2.mcap``...; each has every schema and channel again.
"""

from __future__ import annotations

import logging
import os
import threading
import time
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from rcon_core.priority import lower_this_thread, name_this_thread

from .mcapfile import McapFile

log = logging.getLogger(__name__)

__all__ = ["McapSink", "SinkStats", "COMPRESSIONS"]

COMPRESSIONS = ("zstd", "lz4", "none")
LIBRARY = "rcon"


class _DirectFile:
    """The stream the ``mcap`` writer writes to: each write goes to the OS at once (``os.write``), so
    what was written survives the process being killed; ``tell`` is counted, not asked."""

    def __init__(self, path: str) -> None:
        self.fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
        self.position = 0

    def write(self, data: bytes | bytearray | memoryview) -> int:
        view = memoryview(data)
        while view:
            n = os.write(self.fd, view)
            view = view[n:]
        self.position += len(data)
        return len(data)

    def writev(self, pieces: Sequence[bytes | bytearray | memoryview]) -> int:
        """Write ``pieces`` in order with as few system calls as the OS allows, copying none of them."""
        views = [memoryview(p) for p in pieces]
        total = sum(v.nbytes for v in views)
        i = 0
        while i < len(views):
            n = os.writev(self.fd, views[i:i + _IOV_MAX])
            self.position += n
            while n and i < len(views):  # drop what was written (a short write leaves part of a piece)
                size = views[i].nbytes
                if n >= size:
                    n -= size
                    i += 1
                else:
                    views[i] = views[i][n:]
                    n = 0
        return total

    def tell(self) -> int:
        return self.position

    def flush(self) -> None:
        return None

    def close(self) -> None:
        if self.fd >= 0:
            try:
                os.fsync(self.fd)
            except OSError:
                pass
            os.close(self.fd)
            self.fd = -1


@dataclass
class SinkStats:
    """Counters (read from any thread; updated by the writer thread)."""

    messages: int = 0  #: written
    bytes_in: int = 0  #: message bytes written (before compression)
    dropped: int = 0  #: not written: queue full, budget reached, write error, closed
    files: list[str] = field(default_factory=list)  #: every file written, in order
    per_topic: dict[str, int] = field(default_factory=dict)
    started: float = field(default_factory=time.monotonic)
    closed_size: int = 0  #: bytes of the files already closed

    def elapsed(self) -> float:
        return time.monotonic() - self.started


_STOP = object()
#: pieces per ``writev`` call (the OS's limit is at least 1024 on Linux, 16 by POSIX)
_IOV_MAX = min(os.sysconf("SC_IOV_MAX"), 1024) if hasattr(os, "sysconf") else 16


class McapSink:
    """A recording being written (see the module docstring)."""

    def __init__(self, path: str, profile: str, *, compression: str = "zstd", chunk_size: int = 4 << 20,
                 chunk_seconds: float = 1.0, split_size: int | None = None, budget: int | None = None,
                 max_queue: int = 256 << 20, metadata: dict[str, str] | None = None,
                 on_problem: Callable[[str], None] | None = None) -> None:
        if compression not in COMPRESSIONS:
            raise ValueError(f"compression must be one of {', '.join(COMPRESSIONS)}; got {compression!r}")
        if profile not in ("ros1", "ros2", ""):
            raise ValueError(f"profile must be ros1, ros2 or empty, got {profile!r}")
        self.path = path
        self.profile = profile
        self.compression = compression
        self.chunk_size = chunk_size
        self.chunk_seconds = chunk_seconds
        self.split_size = split_size
        self.budget = budget
        self.max_queue = max_queue
        self.metadata = dict(metadata or {})
        self.on_problem = on_problem
        self.stats = SinkStats()
        #: what went wrong, in words (None while all is well); ``warning``: the budget is nearly used
        self.problem: str | None = None
        self.warning: str | None = None
        self.stopped = False  #: no more messages are written (budget, error or close)
        self._queue: deque[Any] = deque()  # appended by any thread, drained by the writer thread
        self._wake = threading.Event()
        #: queued bytes that wake the writer thread at once (else it looks every ``wake_every`` s)
        self.wake_bytes = chunk_size
        self.wake_every = min(0.1, chunk_seconds / 2)
        self._queued_bytes = 0
        self._lock = threading.Lock()
        self._channels: dict[str, tuple[str, str, bytes, str, dict[str, str]]] = {}
        self._ids: dict[str, int] = {}  # topic -> channel id in the current file
        self._writer: McapFile | None = None
        self._file: _DirectFile | None = None
        self._index = 0
        self._last_chunk = time.monotonic()
        self._closed = threading.Event()
        self._thread = threading.Thread(target=self._run, name="rcon-record-writer", daemon=True)
        self._open(path)  # raises OSError at once when the file cannot be created
        self._thread.start()

    # ------------------------------------------------------------------ any thread

    def add_channel(self, topic: str, schema_name: str, schema_encoding: str, schema_data: bytes,
                    message_encoding: str, metadata: dict[str, str] | None = None) -> None:
        """Declare ``topic`` (once; later calls for the same topic are ignored)."""
        with self._lock:
            if topic in self._channels:
                return
            self._channels[topic] = (schema_name, schema_encoding, schema_data, message_encoding,
                                     dict(metadata or {}))
        self._queue.append(("channel", topic))

    def has_channel(self, topic: str) -> bool:
        return topic in self._channels

    def write(self, topic: str, log_time: int, publish_time: int, data: bytes) -> bool:
        """Queue one message; False when it was dropped (counted)."""
        size = len(data)
        if self.stopped or self._queued_bytes + size > self.max_queue or topic not in self._channels:
            self.stats.dropped += 1
            return False
        with self._lock:
            self._queued_bytes += size
            queued = self._queued_bytes
        self._queue.append((topic, log_time, publish_time, data))
        if queued >= self.wake_bytes:
            self._wake.set()
        return True

    @property
    def size(self) -> int:
        """Bytes on disk so far (every file of the recording)."""
        f = self._file
        return self.stats.closed_size + (f.position if f is not None else 0)

    @property
    def queued(self) -> int:
        return self._queued_bytes

    def close(self, timeout: float = 30.0) -> None:
        """Write what is queued, the summary and the footer; idempotent. Waits for the writer thread."""
        if not self._closed.is_set():
            self._queue.append(_STOP)
            self._wake.set()
            self._thread.join(timeout)

    # ------------------------------------------------------------------ the writer thread

    def _open(self, path: str) -> None:
        self._file = _DirectFile(path)
        self.stats.files.append(path)
        self._writer = McapFile(self._file, compression=self.compression, chunk_size=self.chunk_size)
        self._writer.start(profile=self.profile, library=LIBRARY)
        if self.metadata:
            self._writer.add_metadata("rcon", self.metadata)
        self._ids = {}
        self._schema_ids: dict[tuple[str, str, bytes], int] = {}
        for topic in list(self._channels):
            self._register(topic)
        self._last_chunk = time.monotonic()

    def _register(self, topic: str) -> None:
        assert self._writer is not None
        name, encoding, data, message_encoding, metadata = self._channels[topic]
        schema_id = 0
        if encoding:
            key = (name, encoding, data)
            schema_id = self._schema_ids.get(key, 0)
            if not schema_id:
                schema_id = self._schema_ids[key] = self._writer.add_schema(name, encoding, data)
        self._ids[topic] = self._writer.add_channel(topic, message_encoding, schema_id, metadata)

    def _finish_file(self) -> None:
        writer, f = self._writer, self._file
        self._writer = self._file = None
        try:
            if writer is not None:
                writer.finish()
        finally:
            if f is not None:
                self.stats.closed_size += f.position
                f.close()

    def _next_path(self) -> str:
        self._index += 1
        base, ext = os.path.splitext(self.path)
        return f"{base}_{self._index}{ext or '.mcap'}"

    def _fail(self, text: str) -> None:
        self.stopped = True
        if self.problem is None:
            self.problem = text
            log.error("recording %s: %s", self.path, text)
            if self.on_problem is not None:
                try:
                    self.on_problem(text)
                except Exception:  # noqa: BLE001
                    log.exception("problem listener failed")

    def _close_chunk(self) -> None:
        if self._writer is not None:
            self._writer.close_chunk()
        self._last_chunk = time.monotonic()

    def _run(self) -> None:
        name_this_thread("rcon-record-wr")  # as top -H and the benchmarks see it
        lower_this_thread()  # bulk work: behind the loops that receive (rcon_core/priority.py)
        items = self._queue
        try:
            while True:
                self._wake.wait(self.wake_every)
                self._wake.clear()
                stop = False
                while items:
                    stop = self._write_run()
                    if stop or not items:
                        break
                    item = items.popleft()  # one at a time, with every check, near a budget or split edge
                    if item is _STOP:
                        stop = True
                        break
                    self._take(item)
                if stop:
                    break
                if self._writer is not None and time.monotonic() - self._last_chunk >= self.chunk_seconds:
                    self._guarded(self._close_chunk)
        finally:
            self.stopped = True
            try:
                if self._writer is not None:
                    self._finish_file()
            except OSError as exc:
                self._fail(_os_words(exc))
                self._abandon()
            self._closed.set()

    def _write_run(self) -> bool:
        """Write queued messages while no check can trip (the hot path: no budget, split, or chunk-age test
        per message, one lock for the run); True when the stop mark was taken. Returns as soon as the next
        message could reach the disk budget's warning or a split (``_take`` then goes one at a time)."""
        writer, f = self._writer, self._file
        if writer is None or f is None or self.stopped:
            return False
        room = 1 << 62
        size = self.size
        if self.budget is not None:
            room = int(0.9 * self.budget) - size if self.warning is None else self.budget - size
        if self.split_size is not None:
            room = min(room, self.split_size - f.position)
        room -= writer.open_bytes + (64 << 10)  # the open chunk may reach the disk whole, with its indexes
        tally = [0, 0, False]  # bytes written, messages written, the stop mark taken
        try:
            self._guarded(self._write_items, writer, room, tally)
        finally:
            self._unqueue(tally[0])
            st = self.stats
            st.messages += tally[1]
            st.bytes_in += tally[0]
        stop = bool(tally[2])
        if self._writer is not None and time.monotonic() - self._last_chunk >= self.chunk_seconds:
            self._guarded(self._close_chunk)
        return stop

    def _write_items(self, writer: McapFile, room: int, tally: list[Any]) -> None:
        """``_write_run``'s loop: queued messages while ``room`` lasts, counted in ``tally`` as they go."""
        items, ids, add = self._queue, self._ids, writer.add_message
        per_topic = self.stats.per_topic
        while items and tally[0] < room:
            item = items.popleft()
            if item is _STOP:
                tally[2] = True
                return
            if len(item) != 4:  # ("channel", topic)
                self._handle(item)
                continue
            topic, log_time, publish_time, data = item
            add(ids[topic], log_time, publish_time, data)
            tally[0] += len(data)
            tally[1] += 1
            per_topic[topic] = per_topic.get(topic, 0) + 1
            room -= 31  # the message's record head

    def _take(self, item: Any) -> None:
        if self._writer is None:
            if isinstance(item, tuple) and len(item) == 4:
                self._unqueue(len(item[3]))
                self.stats.dropped += 1
            return
        self._guarded(self._handle, item)
        if time.monotonic() - self._last_chunk >= self.chunk_seconds:
            self._guarded(self._close_chunk)

    def _guarded(self, fn: Callable[..., Any], *args: Any) -> None:
        """Run one step of writing: a write error stops the recording (said), any other error is said and
        the recording goes on."""
        try:
            fn(*args)
        except OSError as exc:
            self._fail(_os_words(exc))
            self._abandon()
        except Exception as exc:  # noqa: BLE001 - one bad message never ends the recording
            log.exception("recording %s: a record could not be written", self.path)
            if self.problem is None:
                self.problem = f"a record could not be written ({exc})"

    def _unqueue(self, size: int) -> None:
        with self._lock:
            self._queued_bytes -= size

    def _abandon(self) -> None:
        """After a write error: let the file be (readable up to its last complete chunk)."""
        f = self._file
        self._writer = self._file = None
        if f is not None:
            self.stats.closed_size += f.position
            try:
                f.close()
            except OSError:
                pass

    def _handle(self, item: tuple[Any, ...]) -> None:
        if item[0] == "channel":
            if item[1] not in self._ids:
                self._register(item[1])
            return
        topic, log_time, publish_time, data = item
        self._unqueue(len(data))
        if self.stopped:
            self.stats.dropped += 1
            return
        assert self._writer is not None and self._file is not None
        self._writer.add_message(self._ids[topic], log_time, publish_time, data)
        st = self.stats
        st.messages += 1
        st.bytes_in += len(data)
        st.per_topic[topic] = st.per_topic.get(topic, 0) + 1
        size = self.size
        if self.budget is not None:
            if size >= self.budget:
                self._fail(f"the disk budget of {self.budget / 1e6:.0f} MB is used up; the recording was "
                           "closed there")
                self._finish_file()
                return
            if self.warning is None and size >= 0.9 * self.budget:
                self.warning = (f"90 % of the disk budget ({self.budget / 1e6:.0f} MB) is used; the recording "
                                "stops when it is full")
                log.warning("recording %s: %s", self.path, self.warning)
        if self.split_size is not None and self._file.position >= self.split_size:
            self._finish_file()
            self._open(self._next_path())


def _os_words(exc: OSError) -> str:
    import errno

    if exc.errno == errno.ENOSPC:
        return "the disk is full; the recording stopped there (it is readable up to that point)"
    if exc.errno == errno.EDQUOT:
        return "the disk quota is used up; the recording stopped there (it is readable up to that point)"
    return f"cannot write the recording ({exc.strerror or exc}); it stopped there"
