"""Decoding big frames off the event loop, in the order they arrived.

Decisions:

* A frame larger than the client's ``big_frame`` threshold (1 MB by default; a 640x480 rgb8 image in JSON
  is about 1.2 MB) is decoded in one worker thread (``run_in_executor``) instead of on the event loop:
  JSON or CBOR, and for a complete ``png`` frame also the PNG and the JSON inside it.  The read loop
  awaits the result before it reads the next frame, so delivery keeps the order of arrival (per topic and
  overall) while the loop goes on serving pings, writes, timers and other tasks.  The same holds for a big
  message completed by ``fragment`` frames and for the base64 data of a ``png`` frame assembled from
  pieces.  Small frames never come here: their path is one length comparison longer than before.
* One worker thread per client, started on the first big frame and shut down by ``close()``.
* The frame limit bounds the bytes on the wire, not the objects they become (a 30 MB frame of numbers
  took +300-450 MB): a big frame is refused (a :class:`~rcon_core.bridge.protocol.RefusedFrame`, counted in
  ``stats["decode_refused"]``) when its objects would take more than ``max_decoded`` bytes (the client's
  ``max_decoded``, four times ``max_size`` by default): a JSON frame by an estimate counted in its text
  before parsing (``protocol.json_decoded_size``), a CBOR frame as it is decoded (typed arrays made lists,
  maps). Frames below ``big_frame`` are not estimated: at most 1 MB, they decode to a bounded size.
* What the worker cannot decode raises :class:`~rcon_core.bridge.errors.ProtocolError`, which the client
  counts as a bad frame.  (orjson does not release the GIL while it parses, so a huge JSON frame still
  holds the loop for its parse time -- tens of ms for a 30 MB image -- but no longer for the CBOR typed-array
  conversion, the base64 and PNG decoding, which dominated.)
"""

from __future__ import annotations

import asyncio
from concurrent.futures import ThreadPoolExecutor
from typing import Any

from .errors import ProtocolError
from .protocol import check_json_size, decode_binary, decode_png, loads_text
from .safety import safe_text


def decode_big(raw: str | bytes, typed_arrays: str, max_bytes: int, max_decoded: int | None = None) -> Any:
    """Decode one frame completely (runs in the worker thread). ``max_decoded``: the bytes of Python
    objects the frame may decode to (see the module docstring); over it the frame is refused."""
    if isinstance(raw, str):
        check_json_size(raw, max_decoded)
        try:
            m = loads_text(raw)
        except ProtocolError as exc:
            raise ProtocolError(f"text frame of {len(raw)} bytes is {exc}") from None
    else:
        m = decode_binary(raw, typed_arrays, max_decoded)
    if isinstance(m, dict) and m.get("op") == "png" and "num" not in m and "total" not in m:
        data = m.get("data")
        if not isinstance(data, str):
            raise ProtocolError(f"png frame: 'data' must be a string, got {type(data).__name__}")
        return decode_png(data, max_bytes)
    return m


class BigFrames:
    """The worker that decodes big frames for one client."""

    def __init__(self, typed_arrays: str, max_bytes: int, max_decoded: int | None = None) -> None:
        self.typed_arrays = typed_arrays
        self.max_bytes = max_bytes
        self.max_decoded = max_decoded
        self._pool: ThreadPoolExecutor | None = None

    async def decode(self, raw: str | bytes) -> Any:
        """One frame, completely decoded (:func:`decode_big`) in the worker."""
        return await self.run(decode_big, raw, self.typed_arrays, self.max_bytes, self.max_decoded)

    async def run(self, fn: Any, *args: Any) -> Any:
        """``fn(*args)`` in the worker; what it raises becomes a ProtocolError."""
        if self._pool is None:
            self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="rcon-bridge-decode")
        loop = asyncio.get_running_loop()
        try:
            return await loop.run_in_executor(self._pool, fn, *args)
        except ProtocolError:
            raise
        except (MemoryError, RecursionError, ValueError, TypeError) as exc:
            raise ProtocolError(f"a big frame cannot be decoded ({safe_text(exc)})") from None

    def close(self) -> None:
        pool, self._pool = self._pool, None
        if pool is not None:
            pool.shutdown(wait=False, cancel_futures=True)
