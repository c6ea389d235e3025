"""Thread hand-off for GUI front ends: the bridge's loop in a daemon thread, and a latest-value mailbox.

Decoding happens on the loop thread (in the client's reader); the GUI thread only takes finished dicts
from a ``LatestValue`` -- at most one per frame, older values are counted as dropped, never queued.

Decision: the bridge thread's event loop
    uvloop (Linux, macOS) or winloop (Windows) where it imports, else asyncio's own loop
    (:func:`new_event_loop`; ``RCON_EVENT_LOOP=asyncio`` keeps asyncio's).  Measured in
    ``benchmarks/bench_bridge.py`` (``rcon`` beside ``rcon_asyncio``, same run): it cut a round trip's CPU
    by about a third (38 to 24 us) and image ingest by 5-15 %, and changed small-message ingest little.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import os
import sys
import threading
from collections.abc import Awaitable, Callable
from typing import Any, TypeVar

from rcon_core import priority

T = TypeVar("T")
#: ``asyncio`` keeps asyncio's own event loop on the bridge thread (see the module docstring)
LOOP_ENV = "RCON_EVENT_LOOP"


def new_event_loop() -> asyncio.AbstractEventLoop:
    """A new event loop for the bridge thread: uvloop or winloop where installed, else asyncio's."""
    if os.environ.get(LOOP_ENV, "").strip().lower() != "asyncio":
        try:
            if sys.platform == "win32":
                import winloop as fast
            else:
                import uvloop as fast
        except ImportError:
            pass
        else:
            return fast.new_event_loop()  # type: ignore[no-any-return]
    return asyncio.new_event_loop()


class BridgeThread:
    """An asyncio loop running in a daemon thread.

    The thread asks the OS to run it as soon as it wakes (:func:`rcon_core.priority.raise_this_thread`):
    it reads the robots' frames and times and writes the teleop pad's commands, the work that must not
    wait behind bulk work (see "who waits when the CPU is short" in ``rcon_core/priority.py``).
    """

    def __init__(self, name: str = "rcon-bridge") -> None:
        self.name = name
        self.loop: asyncio.AbstractEventLoop | None = None
        self._thread: threading.Thread | None = None
        self._ready = threading.Event()

    def start(self) -> BridgeThread:
        if self._thread is not None:
            raise RuntimeError("BridgeThread already started")
        self._thread = threading.Thread(target=self._main, name=self.name, daemon=True)
        self._thread.start()
        self._ready.wait()
        return self

    def _main(self) -> None:
        priority.raise_this_thread()
        loop = new_event_loop()
        asyncio.set_event_loop(loop)
        self.loop = loop
        self._ready.set()
        try:
            loop.run_forever()
        finally:
            tasks = [t for t in asyncio.all_tasks(loop) if not t.done()]
            for t in tasks:
                t.cancel()
            if tasks:
                loop.run_until_complete(asyncio.gather(*tasks, return_exceptions=True))
            loop.run_until_complete(loop.shutdown_asyncgens())
            loop.close()

    @property
    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    def in_loop_thread(self) -> bool:
        return threading.current_thread() is self._thread

    def _require(self) -> asyncio.AbstractEventLoop:
        if self.loop is None or not self.running:
            raise RuntimeError("BridgeThread is not running")
        return self.loop

    def run(self, coro: Awaitable[T]) -> concurrent.futures.Future[T]:
        """Schedule a coroutine on the loop; thread-safe.  Do not block on the result from the loop thread."""
        return asyncio.run_coroutine_threadsafe(coro, self._require())  # type: ignore[arg-type]

    def call(self, fn: Callable[..., T], *args: Any) -> concurrent.futures.Future[T]:
        """Run a plain function on the loop thread; its return value (or exception) lands in the future."""
        loop = self._require()
        fut: concurrent.futures.Future[T] = concurrent.futures.Future()

        def runner() -> None:
            if not fut.set_running_or_notify_cancel():
                return
            try:
                fut.set_result(fn(*args))
            except BaseException as exc:
                fut.set_exception(exc)

        loop.call_soon_threadsafe(runner)
        return fut

    def stop(self, timeout: float = 5.0) -> None:
        """Stop the loop (pending tasks are cancelled) and join the thread."""
        if self._thread is None:
            return
        if self.loop is not None and self._thread.is_alive():
            self.loop.call_soon_threadsafe(self.loop.stop)
        if threading.current_thread() is not self._thread:
            self._thread.join(timeout)
        self._thread = None

    def __enter__(self) -> BridgeThread:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()


class LatestValue:
    """Latest-value-wins mailbox, safe between threads.

    ``put(v)`` (producer) replaces any value not yet taken and counts it in ``dropped``; ``take()``
    (consumer) returns ``(True, v)`` once per put value, else ``(False, None)``.  ``seq`` counts puts.
    ``on_put`` (optional) is called after each put from the producer's thread, e.g. to wake a GUI.
    """

    __slots__ = ("_lock", "_value", "_has", "seq", "dropped", "on_put")

    def __init__(self, on_put: Callable[[], None] | None = None) -> None:
        self._lock = threading.Lock()
        self._value: Any = None
        self._has = False
        self.seq = 0
        self.dropped = 0
        self.on_put = on_put

    def put(self, value: Any) -> None:
        with self._lock:
            if self._has:
                self.dropped += 1
            self._value = value
            self._has = True
            self.seq += 1
        if self.on_put is not None:
            self.on_put()

    def take(self) -> tuple[bool, Any]:
        with self._lock:
            if not self._has:
                return False, None
            value, self._value, self._has = self._value, None, False
            return True, value

    def peek(self) -> tuple[bool, Any]:
        with self._lock:
            return self._has, self._value

    def __bool__(self) -> bool:
        return self._has
