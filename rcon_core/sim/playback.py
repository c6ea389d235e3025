"""A recording served as a robot: ``rcon sim --play FILE`` and the app's replay.

A :class:`Player` lives on a bare ``SimServer`` (``robot=False``: rosapi, no vessel) whose flavour is the
recording's (``--ros2`` forces ROS 2). It lists the recording's topics and types, with the file's own
definitions learned into the sim's registry (so rosapi's ``message_details`` and ``topics_and_raw_types``
describe them), and releases the messages at the recorded pace.

Decisions:

* **Pace.** Each message is released when ``anchor_wall + (log_time - anchor_log) / rate`` comes; the
  anchor is taken again on play, seek and change of rate, so a pause or a slow moment never makes a
  burst. The file is read ahead by a thread of its own (decompressing a chunk never delays a release);
  the loop only waits and sends.
* **Bytes unchanged.** A ``cbor-raw`` subscriber gets the recorded bytes as they are in the file (the
  flavours match); other encodings get the message decoded once with the file's definitions
  (``fanout.py`` takes a :class:`RecordedMessage`'s ``raw`` bytes for ``cbor-raw``).
* **Latched topics** (``files.py`` says which) keep their latest message for late subscribers, as a
  latched publisher does.
* **Seek** sends each topic's latest message before the new time at once (what a widget would show
  there), then goes on from there. ``--loop`` starts again at ``start`` after the end.
* **Commands go nowhere.** A client's publish is accepted (after ``advertise``, as rosbridge wants),
  logged, counted in ``absorbed`` and said on ``/rosout`` once per topic, and not passed on; a call to a
  service the recording does not have fails with a sentence saying the robot is a recording. Nothing fails
  silently.

Thread safety: ``play``, ``pause``, ``set_rate`` and ``seek`` may be called from any thread; everything
else runs on the server's loop.
"""

from __future__ import annotations

import asyncio
import collections
import contextlib
import logging
import queue
import threading
import time
from collections.abc import Iterator
from typing import TYPE_CHECKING, Any

import orjson

from rcon_core.record.files import Recording, Track
from rcon_core.record.schema import learn_full_text

from . import fanout

if TYPE_CHECKING:
    from .connection import Connection
    from .server import SimServer

log = logging.getLogger("rcon.sim.playback")

__all__ = ["Player", "RecordedMessage", "PLAYER_NODE"]

PLAYER_NODE = "/rcon_player"
SEEK_NODE = "/rcon_player/seek"  # the state at a seek point, kept for subscribers that come right after
PREFETCH = 64


def _get(q: queue.Queue[Any]) -> Any:
    try:
        return q.get(timeout=0.25)
    except queue.Empty:
        return None


class RecordedMessage(dict):  # type: ignore[type-arg]
    """A message as decoded for JSON/CBOR subscribers, carrying its recorded bytes for cbor-raw ones."""

    __slots__ = ("raw",)

    def __init__(self, values: dict[str, Any], raw: bytes | None) -> None:
        super().__init__(values)
        self.raw = raw


def _time_shape(value: Any, to_ros2: bool) -> Any:
    """A message decoded in one flavour, in the other's time shape (``secs/nsecs`` <-> ``sec/nanosec``;
    a ROS 1 header's ``seq`` dropped)."""
    if isinstance(value, dict):
        keys = set(value)
        if to_ros2 and keys == {"secs", "nsecs"}:
            return {"sec": value["secs"], "nanosec": value["nsecs"]}
        if not to_ros2 and keys == {"sec", "nanosec"}:
            return {"secs": value["sec"], "nsecs": value["nanosec"]}
        out = {k: _time_shape(v, to_ros2) for k, v in value.items()}
        if to_ros2 and {"seq", "stamp", "frame_id"} <= keys:
            out.pop("seq", None)
        return out
    if isinstance(value, list):
        return [_time_shape(v, to_ros2) for v in value]
    return value


class _Reader(threading.Thread):
    """Reads the file ahead into a bounded queue; a seek restarts it at the new time (``generation``)."""

    def __init__(self, recording: Recording) -> None:
        super().__init__(name="rcon-player-reader", daemon=True)
        self.recording = recording
        self.out: queue.Queue[Any] = queue.Queue(maxsize=PREFETCH)
        self._cmd: queue.Queue[Any] = queue.Queue()
        self.generation = 0
        self.errors = 0

    def restart(self, start_ns: int, snapshot: bool) -> int:
        self.generation += 1
        self._cmd.put((self.generation, start_ns, snapshot))
        return self.generation

    def stop(self) -> None:
        self._cmd.put(None)

    def _put(self, gen: int, item: Any) -> bool:
        while gen == self.generation:
            try:
                self.out.put((gen, item), timeout=0.1)
                return True
            except queue.Full:
                if not self._cmd.empty():
                    return False
        return False

    def run(self) -> None:
        cmd = self._cmd.get()
        while cmd is not None:
            gen, start_ns, snapshot = cmd
            nxt = None
            try:
                if snapshot:
                    self._put(gen, ("snapshot", start_ns, self.recording.latest_before(start_ns)))
                for item in self.recording.messages(start_ns):
                    if not self._cmd.empty() or not self._put(gen, item):
                        break
                else:
                    self._put(gen, ("end", 0, None))
            except Exception as exc:  # noqa: BLE001 - a damaged chunk ends the play, not the server
                self.errors += 1
                log.error("reading %s failed: %s", self.recording.path, exc)
                self._put(gen, ("end", 0, None))
            nxt = self._cmd.get()
            while not self._cmd.empty() and nxt is not None:
                nxt = self._cmd.get()
            cmd = nxt


class Player:
    """Plays ``recording`` on ``server`` (see the module docstring)."""

    def __init__(self, server: SimServer, recording: Recording, *, rate: float = 1.0, loop: bool = False,
                 start: float = 0.0, paused: bool = False) -> None:
        if not rate > 0:
            raise ValueError(f"rate must be positive, got {rate}")
        self.server = server
        self.recording = recording
        self.rate = rate
        self.loop = loop
        self.start_offset = max(0.0, start)
        self.playing = not paused
        self.ended = False
        #: nanoseconds since the recording's start of the last message released (or the seek point)
        self.position_ns = int(self.start_offset * 1e9)
        self.released = 0
        self.absorbed: collections.Counter[str] = collections.Counter()
        #: (wall time released - wall time due) of each message, seconds (the bench reads it)
        self.lateness: collections.deque[float] = collections.deque(maxlen=100_000)
        self._reader = _Reader(recording)
        self._wake: asyncio.Event | None = None
        self._anchor = (0.0, 0)  # (monotonic, log_time ns)
        self._decoders: dict[str, Any] = {}
        self._task: asyncio.Task[Any] | None = None
        self._said: set[str] = set()
        self.seeks = 0  #: seeks done (a listener can tell a seek happened)

    # ------------------------------------------------------------------ set up (server loop)

    @property
    def duration(self) -> float:
        return self.recording.duration

    @property
    def position(self) -> float:
        return self.position_ns / 1e9

    def install(self) -> None:
        """Advertise the recording's topics with its definitions, take over publishes and missing
        services, and start playing. Call on the server's loop after ``server.start()``."""
        server = self.server
        reg = server.types.registry
        same = self.recording.ros2 == server.ros2
        for track in self.recording.tracks.values():
            if track.definition and same:
                try:
                    learn_full_text(reg, track.type, track.definition)
                except ValueError as exc:
                    log.warning("%s: %s", track.topic, exc)
            server.advertise_internal(track.topic, server.flavour.wire(track.type), PLAYER_NODE,
                                      latched=track.latched)
            self._decoders[track.topic] = self._decoder(track, reg, same)
        server.absorb = self._absorb
        original_call = server.service_ops.call

        async def call(name: str, args: Any = None) -> tuple[bool, Any]:
            if name not in server.services:
                self._note("call", name)
                return False, (f"this robot is a recording ({self.recording.path}): nothing serves {name}, "
                               "the call was not made")
            return await original_call(name, args)

        server.service_ops.call = call  # type: ignore[method-assign]
        self._wake = asyncio.Event()
        self._reader.start()
        self._reader.restart(self.recording.start_ns + self.position_ns, snapshot=self.position_ns > 0)
        self._task = server.spawn(self._run())

    def _decoder(self, track: Track, reg: Any, same: bool) -> Any:
        if track.encoding == "json":
            return lambda data: RecordedMessage(orjson.loads(data), None)
        if same:
            de = reg.deserialize_cdr if track.encoding == "cdr" else reg.deserialize_ros1
            return lambda data, _t=track.type: RecordedMessage(de(_t, data), data)
        from rcon_core.msgs import TypeRegistry

        own = TypeRegistry.standard(ros2=self.recording.ros2)  # the file's flavour, then the server's shape
        if track.definition:
            try:
                learn_full_text(own, track.type, track.definition)
            except ValueError as exc:
                log.warning("%s: %s", track.topic, exc)
        de = own.deserialize_cdr if track.encoding == "cdr" else own.deserialize_ros1
        to_ros2 = self.server.ros2
        return lambda data, _t=track.type: RecordedMessage(_time_shape(de(_t, data), to_ros2), None)

    async def stop(self) -> None:
        self._reader.stop()
        if self._task is not None:
            self._task.cancel()

    # ------------------------------------------------------------------ control (any thread)

    def _call(self, fn: Any, *args: Any) -> None:
        loop = self.server.loop
        if loop is None:
            fn(*args)
            return
        try:
            running = asyncio.get_running_loop()
        except RuntimeError:
            running = None
        if running is loop:
            fn(*args)
        else:
            loop.call_soon_threadsafe(fn, *args)

    def play(self) -> None:
        self._call(self._play)

    def pause(self) -> None:
        self._call(self._pause)

    def set_rate(self, rate: float) -> None:
        if not rate > 0:
            raise ValueError(f"rate must be positive, got {rate}")
        self._call(self._set_rate, rate)

    def seek(self, seconds: float) -> None:
        """Go to ``seconds`` after the recording's start: each topic's latest message before it is sent at
        once, then playing goes on from there (or stays paused)."""
        self._call(self._seek, seconds)

    # ------------------------------------------------------------------ control (loop)

    def _reanchor(self) -> None:
        self._anchor = (time.monotonic(), self.recording.start_ns + self.position_ns)
        if self._wake is not None:
            self._wake.set()

    def _play(self) -> None:
        if self.ended:
            self._seek(0.0 if self.position >= self.duration else self.position)
        self.playing = True
        self._reanchor()

    def _pause(self) -> None:
        self.playing = False
        self._reanchor()

    def _set_rate(self, rate: float) -> None:
        self.rate = rate
        self._reanchor()

    def _seek(self, seconds: float) -> None:
        seconds = min(max(0.0, seconds), self.duration)
        self.position_ns = int(seconds * 1e9)
        self.ended = False
        self.seeks += 1
        self._reader.restart(self.recording.start_ns + self.position_ns, snapshot=True)
        self._reanchor()

    # ------------------------------------------------------------------ the pace

    async def _next(self) -> Any:
        q = self._reader.out
        loop = asyncio.get_running_loop()
        while True:
            try:
                gen, item = q.get_nowait()
            except queue.Empty:
                # waited for in a worker thread, a short while at a time: a worker blocked for good would
                # hold up the loop's shutdown (asyncio.run waits for its executor)
                got = await loop.run_in_executor(None, _get, q)
                if got is None:
                    continue
                gen, item = got
            if gen == self._reader.generation:
                return item

    async def _run(self) -> None:
        assert self._wake is not None
        wake = self._wake
        self._reanchor()
        while True:
            gen = self._reader.generation
            item = await self._next()
            topic, t, data = item
            if topic == "snapshot":
                for name, (_lt, payload) in sorted(data.items(), key=lambda kv: kv[1][0]):
                    self._release(name, payload, seek=True)
                self._reanchor()
                continue
            if topic == "end":
                if self.loop and self.playing:
                    self._seek(self.start_offset)
                    continue
                self.ended = True
                self.position_ns = self.recording.end_ns - self.recording.start_ns
                wake.clear()
                await wake.wait()
                continue
            while True:
                if gen != self._reader.generation:
                    break
                if not self.playing:
                    wake.clear()
                    await wake.wait()
                    continue
                wall0, log0 = self._anchor
                due = wall0 + (t - log0) / 1e9 / self.rate
                delay = due - time.monotonic()
                if delay <= 0:
                    self.lateness.append(-delay)
                    self._release(topic, data)
                    self.position_ns = t - self.recording.start_ns
                    break
                wake.clear()
                try:
                    await asyncio.wait_for(wake.wait(), delay)
                except TimeoutError:
                    pass

    def _release(self, topic: str, data: bytes, seek: bool = False) -> None:
        """Send one recorded message. ``seek``: it is the state at a seek point, which a subscriber that
        comes right after (the app restarts its widgets on a seek) gets too, until the topic's next message."""
        t = self.server.topics.get(topic)
        decode = self._decoders.get(topic)
        if t is None or decode is None:
            return
        if not seek:
            t.latched_msgs.pop(SEEK_NODE, None)
        if not (t.latched or seek or t.client_subscribers or t.internal_subscribers):
            return
        needs_dict = (t.latched or seek or bool(t.internal_subscribers) or self.recording.ros2 != self.server.ros2
                      or any((sub := conn.subscriptions.get(topic)) is not None and sub.compression != "cbor-raw"
                             for conn in t.client_subscribers))
        try:
            msg = decode(data) if needs_dict else RecordedMessage({}, data)
        except Exception as exc:  # noqa: BLE001 - one bad message is skipped, the play goes on
            if topic not in self._said:
                self._said.add(topic)
                log.error("%s: a recorded message cannot be decoded (%s); such messages are skipped", topic, exc)
            return
        self.released += 1
        if t.latched:
            t.latched_msgs[PLAYER_NODE] = msg
        elif seek:
            t.latched_msgs[SEEK_NODE] = msg
        for callbacks in list(t.internal_subscribers.values()):
            for cb in list(callbacks):
                try:
                    cb(msg)
                except Exception:  # noqa: BLE001
                    log.exception("subscriber callback on %s failed", topic)
        if t.client_subscribers:
            fanout.fan_out(t, msg, self.server.flavour, self.server.types)

    # ------------------------------------------------------------------ commands go nowhere

    def _absorb(self, conn: Connection, topic: str, msg: dict[str, Any]) -> bool:
        self._note("publish", topic)
        return True

    def _note(self, what: str, name: str) -> None:
        self.absorbed[name] += 1
        log.info("recording: %s on %s absorbed (nothing is sent to a recording)", what, name)
        key = f"{what}:{name}"
        if key not in self._said:
            self._said.add(key)
            words = "publishes on" if what == "publish" else "calls to"
            self.server.log(PLAYER_NODE, "warn", f"this robot is a recording: {words} {name} go nowhere")


async def serve_recording(path: str, *, host: str = "127.0.0.1", port: int = 0, ros2: bool | None = None,
                          rate: float = 1.0, loop: bool = False, start: float = 0.0, paused: bool = False,
                          **server_options: Any) -> tuple[SimServer, Player]:
    """A started bare sim playing the recording at ``path`` (ROS flavour from the file unless ``ros2``);
    stop with ``await player.stop(); await server.stop(); player.recording.close()``. Raises
    ``files.RecordingError`` for a file that cannot be played."""
    from rcon_core.record.files import open_recording

    from .server import SimServer

    recording = open_recording(path)
    server = SimServer(host=host, port=port, ros2=recording.ros2 if ros2 is None else ros2, robot=False,
                       **server_options)
    try:
        await server.start()
        player = Player(server, recording, rate=rate, loop=loop, start=start, paused=paused)
        player.install()
    except BaseException:
        recording.close()
        await server.stop()
        raise
    return server, player


@contextlib.contextmanager
def played_in_thread(path: str, **options: Any) -> Iterator[tuple[SimServer, Player]]:
    """``serve_recording`` on its own event loop in a daemon thread (the app's ``rcon --play``)."""
    loop = asyncio.new_event_loop()
    thread = threading.Thread(target=loop.run_forever, name="rcon-player", daemon=True)
    thread.start()
    try:
        server, player = asyncio.run_coroutine_threadsafe(serve_recording(path, **options), loop).result(60)
    except BaseException:
        loop.call_soon_threadsafe(loop.stop)
        raise
    try:
        yield server, player
    finally:
        async def stop() -> None:
            await player.stop()
            await server.stop()

        with contextlib.suppress(Exception):
            asyncio.run_coroutine_threadsafe(stop(), loop).result(10)
        player.recording.close()
        loop.call_soon_threadsafe(loop.stop)
        thread.join(timeout=10)
