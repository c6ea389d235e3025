"""The view-only guard of a Foxglove link: the same :class:`~rcon_core.bridge.guard.LinkGuard` semantics on
this protocol's frames.

A view-only Foxglove link sends nothing the robot acts on.  Reads pass (:data:`READ_OPS`: ``subscribe``,
``unsubscribe``, ``getParameters``, the parameter and connection-graph subscriptions, ``fetchAsset``); a
client ``advertise`` is an offer (kept by the client, not sent, until the mark is lifted; its
``unadvertise`` is the withdrawal, sent when the mark is set); ``setParameters``, a client message and a
service call request are refused and counted.  The protocol has no read-only services (nothing says which
service only reads), so every service call is refused on a view-only link.

:data:`OUTGOING_OPS` lists every op the Foxglove link writes (binary frames by the names ``publish`` and
``call_service``); ``tests/test_view_only_link.py`` checks the link's source names no other.
"""

from __future__ import annotations

from typing import Any

from rcon_core.bridge.guard import LinkGuard

READ_OPS = frozenset({"subscribe", "unsubscribe", "getParameters", "subscribeParameterUpdates",
                      "unsubscribeParameterUpdates", "subscribeConnectionGraph", "unsubscribeConnectionGraph"})
OFFER_OPS = frozenset({"advertise"})
WITHDRAW_OPS = frozenset({"unadvertise"})
CHANGE_OPS = frozenset({"setParameters", "publish", "call_service"})
OUTGOING_OPS = READ_OPS | OFFER_OPS | WITHDRAW_OPS | CHANGE_OPS

_WORDS = {"setParameters": "setting parameter {}", "publish": "publishing on {}",
          "call_service": "the call to {}", "advertise": "advertising {}"}


class FoxgloveGuard(LinkGuard):
    """``LinkGuard`` over Foxglove ops: ``admit(op, target)`` for each frame about to be written."""

    def admit_op(self, kind: str, target: str) -> bool:
        """The backstop for one frame (loop thread): False (dropped, counted) when a view-only link may not
        send it; keeps track of what the link offers (client channels, by topic)."""
        if kind in OFFER_OPS:
            if self.reason is not None:
                self.refuse(_WORDS["advertise"].format(target))
                return False
            self.offered.add(("advertise", target))
            return True
        if kind in WITHDRAW_OPS:
            key = ("advertise", target)
            if key in self.offered:
                self.offered.discard(key)
                return True
            return self.reason is None
        if kind in READ_OPS or self.reason is None:
            return True
        self.refuse(_WORDS.get(kind, "the op {}").format(target or kind))
        return False

    def admit(self, op: dict[str, Any]) -> bool:  # the rosbridge-shaped entry, for callers that use it
        kind = op.get("op")
        target = op.get("topic") or op.get("service") or op.get("name") or ""
        return self.admit_op(str(kind), str(target))

    def withdrawals(self) -> list[dict[str, Any]]:
        return [{"op": "unadvertise", "topic": name} for kind, name in sorted(self.offered) if kind == "advertise"]
