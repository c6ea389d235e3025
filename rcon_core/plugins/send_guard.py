"""Confirm-before-send and hold-to-send for dangerous commands: the decisions, without Qt.

Any widget that sends something dangerous (a Button or Switch that docks, arms, starts a pump) can make
the operator hold its control for :data:`HOLD_S` seconds and/or confirm exactly what goes to the robot.
:class:`SendGate` decides; the view only draws (a bar that fills, a dialog) and forwards the touches.
The std package's Qt ``SendGuard`` (``rcon_widgets_std.send_guard``) is one such view, usable by any
widget's view; a view in another toolkit (or a test) drives the gate the same way::

    gate = SendGate(ask=settings.confirm, hold=settings.hold_to_send)
    gate.press()                 # finger down
    gate.progress()              # 0..1: how full the hold bar is (draw it while gate.holding)
    if gate.due():               # once, when the hold is complete (poll it from a timer)
        ...                      # ask (gate.ask), else send: then gate.sent_one()
    outcome = gate.release()     # finger up: Outcome.CONFIRM (no hold: ask or send now),
                                 # Outcome.TOO_SHORT (nothing is sent), Outcome.HELD (it fired) ...
    gate.answered(yes)           # the dialog's answer (counts a refusal on Cancel)

:func:`describe_send` words the confirmation: the exact topic or service, its type and the message or
request as YAML, as the std widgets' dialogs show it. Keys are never sent before the hold is complete
and the keyboard cannot hold (a view sends nothing on Space/Enter for a held control).
"""

from __future__ import annotations

import enum
import time
from collections.abc import Callable
from typing import Any

__all__ = ["HOLD_S", "Outcome", "SendGate", "describe_send"]

#: how long a hold-to-send control must be held, in seconds
HOLD_S = 1.0


class Outcome(enum.Enum):
    """What a release means (:meth:`SendGate.release`)."""

    NONE = "none"  #: the gate is off (neither setting), or no press was going on
    CONFIRM = "confirm"  #: no hold needed: ask now (``gate.ask``), else send now
    TOO_SHORT = "too short"  #: let go before the hold was complete: nothing is sent (counted refused)
    HELD = "held"  #: the hold completed and fired (``due()`` said so); the release ends it


class SendGate:
    """The state of one guarded control (use one per control). Not thread-safe: the GUI thread's."""

    def __init__(self, *, ask: bool, hold: bool, hold_s: float = HOLD_S,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.ask, self.hold = bool(ask), bool(hold)
        self.hold_s = hold_s
        self._clock = clock
        self.sent = 0  #: commands this gate let through
        self.refused = 0  #: presses that sent nothing (a short press, Cancel)
        self._since: float | None = None  # when the current hold began
        self._fired = False

    @property
    def active(self) -> bool:
        """Whether the control is guarded at all (else it sends as it always did)."""
        return self.ask or self.hold

    @property
    def holding(self) -> bool:
        return self._since is not None

    def press(self) -> None:
        """Finger down. Starts a hold when the control needs one."""
        if self.hold:
            self._since, self._fired = self._clock(), False

    def progress(self) -> float:
        """How much of the hold is done, 0..1 (0 when not holding)."""
        if self._since is None:
            return 0.0
        return min(1.0, (self._clock() - self._since) / self.hold_s) if self.hold_s > 0 else 1.0

    def due(self) -> bool:
        """True exactly once per hold, when it completes: the view then asks (``ask``) or sends."""
        if self._since is None or self._fired or self.progress() < 1.0:
            return False
        self._fired = True
        return True

    def release(self) -> Outcome:
        """Finger up (or the hold is abandoned): what it means."""
        if not self.active:
            return Outcome.NONE
        if not self.hold:
            return Outcome.CONFIRM
        if self._since is None:
            return Outcome.NONE
        fired = self._fired  # only a hold that due() reported fired: the view sent on it
        self._since, self._fired = None, False
        if fired:
            return Outcome.HELD
        self.refused += 1
        return Outcome.TOO_SHORT

    def sent_one(self) -> None:
        """The view sent (after the hold, or the confirmation)."""
        self.sent += 1

    def answered(self, yes: bool) -> None:
        """The confirmation's answer: yes sends (count it with :meth:`sent_one`), no is a refusal."""
        if not yes:
            self.refused += 1

    def hint(self) -> str:
        """The words for a press that sent nothing because it was too short."""
        return f"hold {self.hold_s:g} s to send"


def describe_send(binding: Any, payload: dict[str, Any], then: str = "") -> tuple[str, str]:
    """``(question, detail)`` for a confirmation: ``("Call /lights/set (std_srvs/SetBool)?", "Request:\\n
    data: true")`` or ``("Publish on /cmd (pkg/Msg)?", "Message:\\n...")``; ``then`` (e.g. what the release
    sends) is added after an empty line."""
    from rcon_core.msgs.text import to_text

    from .spec import Role

    text = to_text(payload).strip() or "{}"
    if Role.parse(binding.role) is Role.PUBLISH:
        question, detail = f"Publish on {binding.name} ({binding.type})?", f"Message:\n{text}"
    else:
        question, detail = f"Call {binding.name} ({binding.type})?", f"Request:\n{text}"
    return question, detail + (f"\n\n{then}" if then else "")
