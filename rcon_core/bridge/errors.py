"""Exceptions raised by the rosbridge client."""

from __future__ import annotations


class BridgeError(Exception):
    """Base class for everything the bridge raises."""


class NotConnectedError(BridgeError):
    """The operation needs a live connection and there is none (and it could not wait for one)."""


class ServiceError(BridgeError):
    """A ``call_service`` failed.

    ``message`` is the server's own text when the server answered ``result: false`` (rosbridge puts the
    error string in ``values``), or a description of the client-side failure (timeout, connection lost).
    """

    def __init__(self, message: str, service: str | None = None) -> None:
        super().__init__(message)
        self.message = message
        self.service = service

    def __str__(self) -> str:
        if self.service:
            return f"{self.service}: {self.message}"
        return self.message


class ServiceTimeoutError(ServiceError, TimeoutError):
    """No answer arrived within the client-side timeout (a missing or hung service)."""


class RosapiRefusedError(ServiceError):
    """RCON did not send this rosapi call: it would kill or wedge the server's rosapi (``rosapi_guard.py``
    says which calls and why).  Nothing was written; the message names the hazard."""


class ConnectionLostError(ServiceError):
    """The connection dropped while a call or action goal was waiting for its answer."""


class ActionError(BridgeError):
    """An action goal could not be run: the server answered ``result: false`` (its error string is the
    message), an error ``status`` named the goal, the action does not exist, or the client-side timeout
    ran out.  ``status`` is the GoalStatus code when the server gave one (0, STATUS_UNKNOWN, on failures).

    A goal that *ran* and ended cancelled or aborted is not an error: its result arrives normally with
    ``ActionGoal.status`` 5 or 6 (rosbridge sends those with ``result: true``)."""

    def __init__(self, message: str, action: str | None = None, status: int | None = None) -> None:
        super().__init__(message)
        self.message = message
        self.action = action
        self.status = status

    def __str__(self) -> str:
        return f"{self.action}: {self.message}" if self.action else self.message


class ActionTimeoutError(ActionError, TimeoutError):
    """No result arrived within the goal's client-side timeout (the client then cancels the goal)."""


class ActionNoAnswerError(ActionError, TimeoutError):
    """Nothing came back for a goal -- no feedback, no result -- within its ``answer_timeout``.  rosbridge 2.1.0
    answers a goal the action server *rejected* with nothing at all (``rosbridge-ros2-2.1.0/actions.jsonl:14-15``),
    and a goal to an action nobody serves the same (``:16-17``), so this is the only way to tell."""


class ProtocolError(BridgeError):
    """A frame from the server could not be understood (logged, never raised out of the reader)."""


class AuthRefusedError(BridgeError):
    """The robot closed the link right after the ``auth`` op: it refused the rosauth credentials (a wrong
    secret, or a clock too far from the robot's).  Fatal: the client does not retry."""


class LinkSettingsError(BridgeError, ValueError):
    """A CA file, client certificate, key or auth secret that cannot be used; the message says which and
    why.  Fatal: nothing is retried with settings that cannot work."""
