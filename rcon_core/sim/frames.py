"""Reading one client frame of the sim: the JSON values in it, as leniently as rosbridge 0.11 reads them,
in time linear in the frame's size.

* One JSON value (the normal case): ``orjson``.
* A ``NaN`` or ``Infinity`` literal (Python's ``json.dumps`` writes them): the standard library's parser.
* Several objects back to back in one frame (``{...}{...}``), or garbage between objects: each balanced
  top-level ``{...}`` is found with a brace matcher that skips strings (regular expressions, no
  backtracking), then parsed once; one that does not parse, or nests deeper than :data:`MAX_DEPTH`
  (checked before parsing: the standard library's parser recurses, and how deep it may go depends on the
  interpreter's recursion limit), is skipped as a whole. At most
  :data:`MAX_VALUES` objects are tried per frame, and only frames up to :data:`LENIENT_LIMIT` bytes are
  scanned this way (a bigger frame must be one JSON value).

The old scanner retried ``raw_decode`` at every ``{`` after a failure; each failure builds an error
message that counts the lines before its position, so a 1 MB frame of ``{`` took many seconds.

**Decoded-size budget.** The frame limit (32 MB) does not bound what a frame becomes once parsed: a 30 MB
frame of small values (``[{},{},...]``, ``[1.5,1.5,...]``) took +300 to +880 MB and up to 6 s. Every
value but the last in a container is followed by a comma, and one parsed value costs at most about
:data:`BYTES_PER_VALUE` (the parser's own node, the list slot, the object), so a frame whose commas
promise more than :data:`DECODED_BUDGET` is refused before parsing (one line in the log). A camera image
sent as rosbridge sends it (base64 text) has a handful of commas; the same 640x480 image as a JSON list
of numbers (921,600 of them) fits, a 1080p one does not. Big frames are parsed with the cyclic garbage
collector paused (it would walk the new objects again and again as they are made: 2.6 million empty
lists took 3.3 s instead of 0.3 s).

Nothing here raises: what cannot be read is logged (bounded) and dropped.
"""

from __future__ import annotations

import gc
import json
import logging
import re
from collections.abc import Callable
from typing import Any

import orjson

log = logging.getLogger("rcon.sim")

__all__ = ["parse_frame", "scan_objects", "decoded_estimate", "LENIENT_LIMIT", "MAX_VALUES", "DECODED_BUDGET"]

#: frames larger than this must be a single JSON value (no scanning for several objects)
LENIENT_LIMIT = 1024 * 1024
#: at most this many objects are tried in one frame
MAX_VALUES = 1000
#: objects nested deeper than this are skipped unparsed (no ROS message comes near it)
MAX_DEPTH = 100
#: the most memory one frame may take once parsed, estimated before parsing
DECODED_BUDGET = 128 * 1024 * 1024
#: the most one parsed value costs (bytes): the parser's node, a list slot, a dict (the biggest object)
BYTES_PER_VALUE = 100
#: below this size a frame cannot exceed the budget (at most one value per 3 characters: ``[],``)
_CHECK_FROM = DECODED_BUDGET * 3 // BYTES_PER_VALUE

_decoder = json.JSONDecoder()
_TOKEN = re.compile(r'\{+|\}+|"')
_STRING_REST = re.compile(r'(?:[^"\\]++|\\.)*+"', re.DOTALL)  # possessive: never backtracks
_NEST = re.compile(r'[\[\]{}"]')


def _nests_deeper(text: str, limit: int) -> bool:
    """Whether brackets and braces outside strings nest deeper than ``limit`` in ``text`` (linear)."""
    depth = 0
    pos = 0
    while True:
        m = _NEST.search(text, pos)
        if m is None:
            return False
        c = m.group()
        if c == '"':
            rest = _STRING_REST.match(text, m.end())
            if rest is None:
                return False  # an unterminated string: the parser refuses it anyway
            pos = rest.end()
            continue
        depth = depth + 1 if c in "[{" else depth - 1
        if depth > limit:
            return True
        pos = m.end()


def _segment_end(text: str, start: int) -> int | None:
    """The index after the ``}`` that closes the ``{`` at ``start`` (strings skipped), or None."""
    depth = 0
    pos = start
    while True:
        m = _TOKEN.search(text, pos)
        if m is None:
            return None
        token = m.group()
        if token == '"':
            rest = _STRING_REST.match(text, m.end())
            if rest is None:
                return None  # an unterminated string: nothing after it closes
            pos = rest.end()
        elif token[0] == "{":
            depth += len(token)
            pos = m.end()
        elif len(token) >= depth:
            return m.start() + depth
        else:
            depth -= len(token)
            pos = m.end()


def scan_objects(text: str) -> list[Any]:
    """Every balanced top-level ``{...}`` in ``text`` that parses (``NaN`` accepted), in order."""
    values: list[Any] = []
    pos = 0
    for _ in range(MAX_VALUES):
        start = text.find("{", pos)
        if start < 0:
            break
        end = _segment_end(text, start)
        if end is None:
            break
        segment = text[start:end]
        if not _nests_deeper(segment, MAX_DEPTH):
            try:
                values.append(_decoder.decode(segment))
            except (ValueError, RecursionError):
                pass  # this object is broken: skip it whole
        pos = end
    return values


def decoded_estimate(text: str) -> int:
    """An upper bound of the memory ``text`` takes once parsed (bytes): :data:`BYTES_PER_VALUE` a value."""
    return BYTES_PER_VALUE * (text.count(",") + 1)


def parse_frame(message: str | bytes, label: str, warn: Callable[..., None] | None = None) -> list[Any]:
    """The JSON values in one frame. ``label`` names the client in log lines; ``warn(level, text, *args)``,
    when given, logs them instead (the connection's rate-limited logger, which adds the label)."""

    def say(text: str, *args: Any) -> None:
        if warn is not None:
            warn(logging.WARNING, text, *args, logger=log)
        else:
            log.warning("%s " + text, label, *args)

    if isinstance(message, bytes):
        try:
            message = message.decode("utf-8")
        except UnicodeDecodeError:
            say("ignored a binary frame that is not JSON text")
            return []
    if len(message) < LENIENT_LIMIT:
        try:
            return [orjson.loads(message)]
        except orjson.JSONDecodeError:
            pass
    else:
        if len(message) >= _CHECK_FROM and (estimate := decoded_estimate(message)) > DECODED_BUDGET:
            say("ignored a frame of %d characters: parsed, it could take up to %d MB (more than %d MB)",
                len(message), estimate >> 20, DECODED_BUDGET >> 20)
            return []
        paused = gc.isenabled()
        gc.disable()  # a big frame's many new objects would have the collector walk them again and again
        try:
            return [orjson.loads(message)]
        except orjson.JSONDecodeError:
            pass
        finally:
            if paused:
                gc.enable()
    text = message.strip()
    if len(text) > LENIENT_LIMIT:
        try:
            return [_decoder.decode(text)]  # one value with NaN/Infinity literals
        except (ValueError, RecursionError):
            say("ignored a frame of %d characters that is not one JSON value", len(text))
            return []
    frames = scan_objects(text)
    if not frames and text:
        say("ignored a frame that is not valid JSON")
    return frames
