"""What every op handler of the sim shares: refusing a frame, reading its fields, sending a reply.

A handler (``server.py``'s topic ops, ``services.py``, ``actions.py``, ``ros2_actions.py``) raises
:class:`OpError` for a frame it refuses; the server logs it and answers nothing, as rosbridge 0.11 does.
:func:`field` reads a required field of one type with rosbridge's wording when it is missing or wrong.
:func:`send_frame` sends a non-publish frame (a reply or a request) to one connection, fragmented if the
connection asked for fragments. This module imports nothing of the server, so the handlers need not either.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from . import encoding

if TYPE_CHECKING:
    from .connection import Connection
    from .graph import Topic

__all__ = ["OpError", "field", "nonneg_int", "retype", "send_frame"]


class OpError(Exception):
    """A client frame the server refuses; logged, never answered (rosbridge 0.11)."""


def field(msg: dict[str, Any], name: str, kind: type) -> Any:
    """``msg[name]``, which must be a ``kind`` (never a bool), or :class:`OpError` in rosbridge's words."""
    if name not in msg:
        raise OpError(f"Expected a {name} field but none was found.")
    value = msg[name]
    if not isinstance(value, kind) or isinstance(value, bool):
        raise OpError(f"Expected field {name} to be one of ({kind},). Invalid value: {value}")
    return value


def nonneg_int(value: Any) -> int:
    """A positive number as an int; anything else (missing, negative, a bool, text) is 0."""
    if isinstance(value, int | float) and not isinstance(value, bool) and value > 0:
        return int(value)
    return 0


def retype(topic: Topic, type_name: str) -> Topic:
    """A topic nobody publishes or subscribes any more takes a new type (and forgets its latched messages)."""
    topic.type = type_name
    topic.latched_msgs.clear()
    return topic


def send_frame(conn: Connection, frame: dict[str, Any]) -> None:
    """Send a non-publish frame (a reply or a request), fragmented if the connection asked for it (the
    fragments' ``id`` is the frame's, as rosbridge does). It is never dropped from the connection's queue
    (``connection.py``)."""
    conn.send(encoding.dumps(frame), fragment_size=conn.fragment_size, fragment_id=frame.get("id", 0))
