"""Button: calls a service when pressed (and optionally another when released), or publishes a fixed
message (role PUBLISH). Requests and messages are YAML (or JSON) text in the settings, checked against
the type's definition with ``TypeRegistry.from_text``. Calls never block: the view calls :meth:`press`
and paints ``state.value`` (a :class:`CallStatus`) as it changes."""

from __future__ import annotations

import time
from typing import Any

import attrs

from rcon_core.msgs import MessageTextError
from rcon_core.msgs.text import parse_text, to_text
from rcon_core.plugins import CallPhase, Role

from .base import StdModel
from .common import format_value, learn_type, shorten_text, types_part_name

__all__ = ["ButtonSettings", "ButtonModel", "CallStatus"]


def _text_problem(what: str, text: str) -> list[str]:
    try:
        parse_text(text)
    except MessageTextError as exc:
        return [f"{what}: {exc.problem}"]
    return []


@attrs.define
class ButtonSettings:
    text: str = attrs.field(default="", metadata={"label": "Text", "help": "what the button says (default: the name)"})
    payload: str = attrs.field(
        default="", metadata={"label": "Request / message", "multiline": True,
                              "help": "YAML or JSON: the service request (or the message to publish); "
                                      "missing fields take their defaults, e.g. 'data: true'"}
    )
    release_service: str = attrs.field(
        default="", metadata={"label": "On release, call", "help": "another service called when the button is released"}
    )
    release_type: str = attrs.field(
        default="", metadata={"label": "Its type", "help": "type of that service (default: the pressed one's)"}
    )
    release_payload: str = attrs.field(
        default="", metadata={"label": "Release request / message", "multiline": True,
                              "help": "YAML or JSON for the release call (or a message published on release)"}
    )
    confirm: bool = attrs.field(
        default=False, metadata={"label": "Ask before sending",
                                 "help": "a dialog shows the exact service and request (or topic and message) first; nothing is sent until Send"}
    )
    hold_to_send: bool = attrs.field(
        default=False, metadata={"label": "Hold to send",
                                 "help": "press and hold 1 s (a bar fills) to send; a shorter press sends nothing"}
    )

    def problems(self) -> list[str]:
        out = _text_problem("request", self.payload)
        out += _text_problem("release request", self.release_payload)
        if self.release_service and not self.release_service.startswith("/"):
            out.append(f"release service {self.release_service!r} must start with '/'")
        if self.release_type and not self.release_service:
            out.append("a release type is set but no release service")
        return out


@attrs.frozen
class CallStatus:
    """One press (or release): ``phase`` is a :class:`~rcon_core.plugins.CallPhase` (busy, ok, failed; a
    ``str``, so ``"ok"`` is taken too); ``text`` is the result (the response's message, or a YAML summary of
    it) or the server's error."""

    phase: CallPhase = attrs.field(converter=CallPhase)
    target: str
    text: str = ""
    started: float = 0.0
    seconds: float | None = None  #: how long the call took

    @property
    def busy(self) -> bool:
        return self.phase is CallPhase.BUSY


class ButtonModel(StdModel):
    def __init__(self, settings: ButtonSettings | None, *args: Any, **kwargs: Any) -> None:
        super().__init__(settings if settings is not None else ButtonSettings(), *args, **kwargs)
        self._busy = 0

    # -- building requests ---------------------------------------------------------------------------
    def _payload_type(self, release: bool) -> str:
        b = self.binding
        if b.role is Role.PUBLISH:
            return b.type
        service_type = (self.settings.release_type or b.type) if release else b.type
        return types_part_name(service_type, "request")

    def build(self, release: bool = False) -> dict[str, Any]:
        """The request (or message) from the settings' text; raises MessageTextError naming the field."""
        text = self.settings.release_payload if release else self.settings.payload
        return self.types.from_text(self._payload_type(release), text)

    def problems(self) -> list[str]:
        out = super().problems()
        if self.binding.problems() or not self.types_ready or out:
            return out
        for release in (False, True):
            if release and not (self.settings.release_service or
                                (self.binding.role is Role.PUBLISH and self.settings.release_payload)):
                continue
            what = "release request" if release else "request"
            if self.binding.role is Role.PUBLISH:
                what = "release message" if release else "message"
            try:
                if self.types.has(self._payload_type(release)):
                    self.build(release)
            except MessageTextError as exc:
                out.append(f"{what}: {exc}")
            except (KeyError, ValueError) as exc:
                out.append(f"{what}: {exc}")
        return out

    def describe_send(self) -> tuple[str, str] | None:
        """What a press sends, for "ask before sending": ``(what, detail)`` with the exact service (or
        topic), type and request (or message) as YAML; None when it cannot be built yet."""
        b, s = self.binding, self.settings
        if b.problems() or not self.types_ready:
            return None
        try:
            first = to_text(self.build()).strip() or "{}"
            if b.role is Role.PUBLISH:
                detail = f"Message:\n{first}"
                if s.release_payload:
                    detail += f"\n\nThen, on release, the message:\n{to_text(self.build(True)).strip() or '{}'}"
                return f"Publish on {b.name} ({b.type})?", detail
            detail = f"Request:\n{first}"
            if s.release_service and self.types.has(self._payload_type(True)):
                again = to_text(self.build(True)).strip() or "{}"
                detail += f"\n\nThen, on release: call {s.release_service} with:\n{again}"
        except (MessageTextError, KeyError, ValueError):
            return None
        return f"Call {b.name} ({b.type})?", detail

    # -- actions (any thread) -----------------------------------------------------------------------
    def press(self) -> None:
        """Call the service (or publish the message). Returns at once; watch ``state.value``."""
        self._act(release=False)

    def release(self) -> None:
        """Call the release service (or publish the release message), if configured."""
        s = self.settings
        if self.binding.role is Role.PUBLISH and s.release_payload:
            self._act(release=True)
        elif self.binding.role is Role.CALL and s.release_service:
            self._act(release=True)

    def _act(self, release: bool) -> None:
        b = self.binding
        target = (self.settings.release_service if release and b.role is Role.CALL else b.name)
        if b.problems():
            self.set_error("; ".join(b.problems()))
            return
        if b.role is Role.PUBLISH:
            try:
                msg = self.build(release)
            except (MessageTextError, KeyError, ValueError) as exc:
                self.set_error(f"message: {exc}")
                return
            if self.publish(msg):
                self.set_value(CallStatus(CallPhase.OK, target, "published", time.time(), 0.0), message=msg)
            return
        started = time.time()
        self.set_value(CallStatus(CallPhase.BUSY, target, "", started))
        self._dispatch(lambda: self.spawn(self._call_one(target, release, started)))

    async def _call_one(self, target: str, release: bool, started: float) -> None:
        t0 = self._clock()
        try:
            if release and self.settings.release_type:
                await learn_type(self.port, self.types, self.settings.release_type, service=True)
            args = self.build(release) if self.types_ready else None
        except (MessageTextError, KeyError, ValueError) as exc:
            self._finish(CallStatus(CallPhase.FAILED, target, f"request: {exc}", started, 0.0), None, error=True)
            return
        try:
            resp = await self.port.call_service(target, args, timeout=self.call_timeout)
        except Exception as exc:
            self._finish(CallStatus(CallPhase.FAILED, target, str(exc), started, self._clock() - t0), None, error=True)
            return
        seconds = self._clock() - t0
        if isinstance(resp, dict) and resp.get("success") is False:
            text = str(resp.get("message") or "success: false")
            self._finish(CallStatus(CallPhase.FAILED, target, text, started, seconds), resp, error=True)
            return
        self._finish(CallStatus(CallPhase.OK, target, describe_response(resp), started, seconds), resp)

    def _finish(self, status: CallStatus, resp: Any, error: bool = False) -> None:
        self.set_value(status, message=resp)
        if error:
            self.set_error(f"{status.target}: {status.text}")


def describe_response(resp: Any) -> str:
    """A short text for a response: its ``message`` when it has one, else the fields as YAML."""
    if not isinstance(resp, dict) or not resp:
        return "done"
    if isinstance(resp.get("message"), str) and resp["message"]:
        return shorten_text(resp["message"])[0]  # a status line never holds a megabyte (issue 22.1)
    return shorten_text(format_value(resp))[0]
