"""What the bridge client counts: one typed record, :class:`BridgeStats` (``client.stats``). No Qt.

Each counter is named where it is counted (``stats.bad_frames += 1``); a misspelt counter is a type error,
not a new key. Readers that index it by name (``client.stats["connects"]``, ``dict(client.stats)``, older
tests and benchmarks) still work: the record reads like a mapping of its counters.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import asdict, dataclass, fields

__all__ = ["BridgeStats", "FoxgloveStats"]


@dataclass(slots=True)
class BridgeStats:
    """The client's counters (each an ``int`` that only grows while the client lives)."""

    connects: int = 0  #: connections made (the first and every reconnect)
    bad_frames: int = 0  #: frames that were not understood (logged, dropped)
    dropped_while_down: int = 0  #: publishes made while the link was down (never queued)
    dropped_on_disconnect: int = 0  #: frames still queued when the link dropped
    oversize_frames: int = 0  #: frames over ``max_size``
    frame_errors: int = 0  #: frames whose handling raised (caught at the frame boundary)
    png_refused: int = 0  #: PNG-compressed frames refused (decompression bombs)
    non_object_msgs: int = 0  #: publish frames whose ``msg`` is not an object
    big_frames: int = 0  #: frames parsed off the loop (``decode_big``)
    stale_dropped: int = 0  #: commands older than their freshness limit, never written
    degraded: int = 0  #: times the link was reported stalled
    stall_cuts: int = 0  #: stalled links cut with commands in flight
    stale_skipped: int = 0  #: queued frames of a latest-only topic skipped for a newer one
    envelope_clamped: int = 0  #: motion commands held to the safety envelope
    envelope_refused: int = 0  #: motion commands refused (NaN, infinity)
    status_not_logged: int = 0  #: server status lines counted but not logged (rate limit)
    decode_refused: int = 0  #: frames refused for what they would decode to (``max_decoded``)

    # -- read like a mapping (compatibility: ``stats["connects"]``, ``dict(stats)``) ---------------------
    def keys(self) -> list[str]:
        return [f.name for f in fields(self)]

    def __getitem__(self, name: str) -> int:
        if name not in self.keys():
            raise KeyError(name)
        value: int = getattr(self, name)
        return value

    def get(self, name: str, default: int = 0) -> int:
        return self[name] if name in self.keys() else default

    def __iter__(self) -> Iterator[str]:
        return iter(self.keys())

    def as_dict(self) -> dict[str, int]:
        return asdict(self)


@dataclass(slots=True)
class FoxgloveStats(BridgeStats):
    """The Foxglove link's counters: the bridge's, and two of its own (``rcon_core/foxglove/session.py``)."""

    undecodable: int = 0  #: MessageData payloads that did not decode in their channel's encoding
    unknown_subscription: int = 0  #: MessageData for a subscription already ended (in flight; not an error)
