"""Frames in: the hot path, frame decoding, fragments, ``png`` frames and bad-frame accounting.

Decision: the hot path
    Per message: one ``orjson.loads`` of the message's bytes (CBOR for binary frames), a few dict lookups,
    two additions to the topic's traffic row and a direct call of the topic's ``fast`` function -- for a
    topic with one consumer, its callback -- all inside the transport's callback (``receive.py``'s
    ``Receiver`` does these steps itself for a small text message, on picows straight from picows' parser;
    :meth:`Inbound.take` for the rest).
    Everything unusual (other ops, unknown topics, malformed frames) takes the slow path
    (:meth:`Inbound.other`), which unwraps ``fragment`` and ``png`` frames and hands every op to the
    session (``session.handle``).  Frames above ``big_frame`` (1 MB), and every ``png`` frame whatever its
    size (its pixels may be far larger than the frame), are decoded in a worker thread while the next
    messages wait, so the event loop keeps serving and the order of delivery is kept
    (``offload.py``).  A frame of a latest-only topic (every consumer asked for ``queue_length`` 1) is
    skipped before decoding when a newer frame of the same topic already waits (``latest.py``).
    Sharing the loop (a turn of the loop holds about 1 ms of messages) is ``receive.py``'s rule.

Decision: bad input from the server
    No exception raised while handling one frame ends the link: the hot path, :meth:`Inbound.one` and the slow path
    catch everything at the frame boundary (``stats.frame_errors``).  Invalid JSON, unknown ops,
    missing or mistyped fields, JSON nested too deep to format, broken fragments, ``png`` data that is no
    image, PNGs whose header declares more pixel bytes than ``max_size`` (refused before decoding,
    ``stats.png_refused``), publish frames whose ``msg`` is not an object
    (``stats.non_object_msgs``) and frames above ``max_size`` are logged (rate limited by
    :class:`BadFrames`, with a bounded repr from ``safety.py``: never ``str()`` of an untrusted value),
    counted in ``client.stats`` and dropped; the connection, the process and other subscriptions carry on.
    A callback that raises is logged and does not affect other callbacks (``topics.py``).

Decision: unfinished fragmented messages
    Bounded per message (``max_size``), in all (twice that), by age (``fragment_timeout``, also when no
    fragment comes any more: a timer sweeps them) and by connection (a lost link drops them all): 256 MB
    of unfinished messages used to stay for good, and up to 2 GB could (``protocol.FragmentAssembler``).

Test hooks (public): ``inbound.fragments`` and ``inbound.png_fragments`` (the assemblers: ``len()`` is the
number of messages in progress, ``buffered_bytes`` what they hold, ``completed`` counts the finished
ones).
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Awaitable, Callable, Iterable
from typing import Any

import orjson

from .errors import NotUtf8, ProtocolError
from .latest import LatestOnly, topic_of
from .offload import BigFrames, decode_big
from .protocol import DecodedTooBig, FragmentAssembler, RefusedFrame, decode_binary, decode_png, loads_text
from .safety import safe_text
from .stats import BridgeStats
from .traffic import Traffic

log = logging.getLogger(__name__)

_loads = orjson.loads


class BadFrames:
    """Counts bad frames from the server and logs them: the first 20 of each kind, then every 1000th."""

    def __init__(self, url: str, stats: BridgeStats) -> None:
        self.url = url
        self.stats = stats
        self.counts: dict[str, int] = {}

    def report(self, kind: str, message: str) -> None:
        self.stats.bad_frames += 1
        n = self.counts[kind] = self.counts.get(kind, 0) + 1
        if n <= 20 or n % 1000 == 0:
            log.warning("bad frame from %s: %s", self.url, message)
        elif n == 21:
            log.warning("bad frame from %s: %s (more %s problems are counted in stats and logged every 1000th)",
                        self.url, message, kind)

    def failed(self, exc: BaseException) -> None:
        """A frame whose handling raised: counted, logged with a bounded text, dropped; the loop goes on."""
        self.stats.frame_errors += 1
        self.report("error", f"handling a frame failed, dropped it ({safe_text(exc)})")


class Inbound:
    """Turns what the socket delivers into messages for the session's topics and ops for the session."""

    def __init__(self, session: Any, bad: BadFrames, stats: BridgeStats, *, typed_arrays: str,
                 max_size: int, big_frame: int, fragment_timeout: float, max_decoded: int | None = None) -> None:
        self.session = session
        self.bad = bad
        self.stats = stats
        self.typed_arrays = typed_arrays
        self.max_size = max_size
        self.big_frame = big_frame
        #: the bytes of objects one frame may decode to (big frames; see offload.py)
        self.max_decoded = max_decoded
        self.big = BigFrames(typed_arrays, max_size, max_decoded)
        self.latest = LatestOnly(session.topics, stats)
        #: bytes in by topic (``traffic.py``): the connection bar's bandwidth readout
        self.traffic = Traffic()
        warn = self._fragment_warning
        self.fragments = FragmentAssembler(timeout=fragment_timeout, max_bytes=max_size, warn=warn)
        self.png_fragments = FragmentAssembler(timeout=fragment_timeout, max_bytes=max_size, warn=warn)
        #: a big message completed by fragments or a big png: the read loop awaits it (order is kept)
        self.deferred: Callable[[], Awaitable[Any]] | None = None
        self._sweeper: asyncio.TimerHandle | None = None  # expires unfinished messages without new fragments
        self.topics = session.topics
        #: messages of ``heavy`` bytes or more take the awaitable path (:meth:`one`)
        self.heavy = min(self.latest.min_size, big_frame)
        #: the transport's receive queue (``Receiver.waiting``), for skipping stale latest-only frames
        self.waiting: Callable[[], Iterable[bytes | str]] | None = None

    def take(self, raw: Any, text: bool) -> Awaitable[None] | None:
        """One whole message from the transport (``receive.Receiver``): ``raw`` is bytes-like and valid only
        during this call (a view into the transport's read buffer), ``text`` says it came in a text frame
        (its UTF-8 is checked here: orjson parses only valid UTF-8, and text it refuses is decoded to say
        which).  A small message is handled now and None returned; one that must wait (a big frame decoded
        in the worker, a frame of a latest-only topic, a big message completed by fragments) is copied and
        returned as an awaitable the caller must await before the next message.  Raises :class:`NotUtf8`
        for a text message that is not UTF-8 (the transport then closes the link)."""
        if len(raw) >= self.heavy and (len(raw) > self.big_frame or self._latest_only(raw)):
            return self.one(raw if raw.__class__ is bytes else bytes(raw), text)
        try:  # the frame boundary: nothing raised while handling one frame ends the link
            if text:
                try:
                    m = _loads(raw)
                except orjson.JSONDecodeError:
                    try:
                        raw = str(raw, "utf-8")
                    except UnicodeDecodeError as exc:
                        raise NotUtf8(exc) from None
                    m = self.lenient(raw)  # rosbridge 2.x's bare NaN tokens (protocol.loads_text)
                    if m is None:
                        return None
            else:
                m = self.decode_binary(raw if raw.__class__ is bytes else bytes(raw))
                if m is None:
                    return None
            self.traffic.count(m, len(raw))
        except NotUtf8:
            raise
        except Exception as exc:
            self.bad.failed(exc)
            return None
        return self.deliver(m)

    def deliver(self, m: Any) -> Awaitable[None] | None:
        """A decoded message: the fast path (a publish of a subscribed topic whose ``msg`` is an object goes
        to the topic's ``fast`` function), else the slow path; an awaitable when a big message completed by
        fragments waits to be decoded off the loop (see :meth:`take`).  Never raises."""
        try:
            try:
                entry = self.topics[m["topic"]] if m["op"] == "publish" else None
                msg = m["msg"]
            except (KeyError, TypeError):  # not a publish of a subscribed topic, or malformed: slow path
                entry = None
            if entry is not None and msg.__class__ is dict:
                try:
                    entry.fast(msg)
                except Exception:
                    entry.callback_failed()
                return None
            self.other(m)
            if self.deferred is not None:
                return self._deferred()
        except Exception as exc:
            self.bad.failed(exc)
        return None

    def _latest_only(self, raw: Any) -> bool:
        """Whether a frame names a latest-only topic in its head (``latest.topic_of``), while a receive queue
        can be looked into."""
        if self.waiting is None:
            return False
        entry = self.topics.get(topic_of(raw))  # type: ignore[arg-type]
        return entry is not None and entry.latest_only

    async def one(self, raw: bytes, text: bool) -> None:
        """A message of ``heavy`` size or more (a copy; a text message's UTF-8 unchecked): skipped when stale
        (latest-only), decoded in the worker when above ``big_frame``, then delivered.  Raises
        :class:`NotUtf8` for a text message that is not UTF-8."""
        try:
            waiting = self.waiting
            if waiting is not None and await self.latest.stale(raw, waiting):
                self.traffic.count_name(topic_of(raw), len(raw))  # skipped, but it crossed the link
                return
            if len(raw) > self.big_frame:
                m = await self.decode_big(raw, text)
                if m is None:
                    return
            elif text:
                try:
                    m = _loads(raw)
                except orjson.JSONDecodeError:
                    try:
                        decoded = str(raw, "utf-8")
                    except UnicodeDecodeError as exc:
                        raise NotUtf8(exc) from None
                    m = self.lenient(decoded)
                    if m is None:
                        return
            else:
                m = self.decode_binary(raw)
                if m is None:
                    return
            self.traffic.count(m, len(raw))
            try:
                entry = self.topics[m["topic"]] if m["op"] == "publish" else None
                msg = m["msg"]
            except (KeyError, TypeError):
                entry = None
            if entry is not None and msg.__class__ is dict:
                try:
                    entry.fast(msg)
                except Exception:
                    entry.callback_failed()
                return
            self.other(m)
            await self._deferred()
        except NotUtf8:
            raise
        except Exception as exc:
            self.bad.failed(exc)

    async def _deferred(self) -> None:
        while self.deferred is not None:  # a big message completed by fragments: decoded off the loop
            job, self.deferred = self.deferred, None
            inner = await job()
            if inner is not None:
                self.other(inner)

    def disconnected(self) -> None:
        """The connection is gone: nothing it started is finished on the next one (a big message waiting
        to be decoded, unfinished fragmented messages)."""
        self.deferred = None
        self.fragments.clear()
        self.png_fragments.clear()
        self._stop_sweeping()

    def close(self) -> None:
        self._stop_sweeping()
        self.big.close()

    # -- unfinished fragmented messages expire by age, also when no fragment comes any more -------------

    def _sweep_later(self) -> None:
        if self._sweeper is not None or not (len(self.fragments) or len(self.png_fragments)):
            return
        try:
            loop = asyncio.get_running_loop()
        except RuntimeError:  # called off the loop (a test feeding frames by hand): expiry on the next add
            return
        oldest = min(t for t in (self.fragments.oldest_update(), self.png_fragments.oldest_update())
                     if t is not None)
        delay = max(0.01, oldest + self.fragments.timeout - time.monotonic() + 0.01)
        self._sweeper = loop.call_later(delay, self._sweep)

    def _sweep(self) -> None:
        self._sweeper = None
        self.fragments.expire()
        self.png_fragments.expire()
        self._sweep_later()

    def _stop_sweeping(self) -> None:
        sweeper, self._sweeper = self._sweeper, None
        if sweeper is not None:
            sweeper.cancel()

    # -- decoding -------------------------------------------------------------------------------------

    async def decode_big(self, raw: str | bytes, text: bool = False) -> Any:
        """Decode a frame above ``big_frame`` in the worker thread (see ``offload.py``; ``text``: bytes of a
        text frame); None when dropped.  Raises :class:`NotUtf8` for a text frame that is not UTF-8."""
        if len(raw) > self.max_size:
            self.stats.oversize_frames += 1
            self.bad.report("size", f"frame of {len(raw)} bytes exceeds max_message_size={self.max_size}; dropped")
            return None
        return await self._offloaded(decode_big, raw, self.typed_arrays, self.max_size, text, self.max_decoded)

    async def _offloaded(self, fn: Callable[..., Any], *args: Any) -> Any:
        self.stats.big_frames += 1
        try:
            return await self.big.run(fn, *args)
        except ProtocolError as exc:
            if isinstance(exc, DecodedTooBig):
                self.stats.decode_refused += 1
            elif isinstance(exc, RefusedFrame):
                self.stats.png_refused += 1
            self.bad.report("big", f"big frame dropped: {exc}")
            return None

    def lenient(self, raw: str) -> Any:
        """A text frame orjson refused: parsed again allowing bare ``NaN``/``Infinity``; None (counted) when
        it is not JSON at all."""
        try:
            return loads_text(raw)
        except ProtocolError as exc:
            self.bad.report("json", f"text frame is {exc}: {raw[:80]!r}")
            return None

    def decode_binary(self, raw: bytes) -> Any:
        try:
            return decode_binary(raw, self.typed_arrays)
        except Exception as exc:
            self.bad.report("binary", f"binary frame of {len(raw)} bytes dropped: {exc}")
            return None

    def _fragment_warning(self, message: str) -> None:
        self.bad.report("fragment", message)

    # -- the slow path --------------------------------------------------------------------------------

    def other(self, m: Any) -> None:
        """The slow path (and what fragments and png frames carry); never raises."""
        try:
            op = m.get("op") if isinstance(m, dict) else None
            if op == "fragment" or op == "png":
                try:
                    self._on_fragment(m) if op == "fragment" else self._on_png(m)
                except (KeyError, TypeError, ValueError, AttributeError) as exc:
                    self.bad.report("field", f"malformed {op!r} frame ignored ({safe_text(exc)})")
            else:
                self.session.handle(m)
        except Exception as exc:
            self.bad.failed(exc)

    def _dispatch_text(self, text: str | bytes) -> None:
        try:
            m = loads_text(text)
        except ProtocolError as exc:
            self.bad.report("json", f"reassembled frame is {exc}")
            return
        self.other(m)

    def _on_fragment(self, m: dict[str, Any]) -> None:
        try:
            text = self.fragments.add(m)
        except ProtocolError as exc:
            self.bad.report("fragment", str(exc))
            return
        finally:
            self._sweep_later()
        if text is not None and len(text) > self.big_frame:
            self.deferred = lambda: self.decode_big(text)
        elif text is not None:
            self._dispatch_text(text)

    def _on_png(self, m: dict[str, Any]) -> None:
        try:
            data = m["data"]
            if "num" in m and "total" in m:
                data = self.png_fragments.add(m)
                self._sweep_later()
                if data is None:
                    return
            if not isinstance(data, str):
                raise ProtocolError(f"png frame: 'data' must be a string, got {type(data).__name__}")
            # every PNG, small or not, is decoded in the worker (a 5.6 KB one held the loop 2.2 s)
            self.deferred = lambda: self._offloaded(decode_png, data, self.max_size)
        except ProtocolError as exc:
            if isinstance(exc, RefusedFrame):
                self.stats.png_refused += 1
            self.bad.report("png", str(exc))
