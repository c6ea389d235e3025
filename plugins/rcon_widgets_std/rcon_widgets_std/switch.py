"""Switch: one bool. Publishes it (std_msgs/Bool or any bool field), shows it (subscribe), or asks a
service to set it (std_srvs/SetBool or any service with a bool in its request, e.g. ``/lights/set``).

Service case, decided: the switch calls the service with the new value and shows "in progress" until
the answer. A failed call, or a response whose ``success`` is false, puts the switch back and shows the
server's message. The switch shows the robot's real state when ``state_topic`` is set (``/lights/state``):
it subscribes to it and follows it, whoever changed the lights. Without it, the last successful request
is the state."""

from __future__ import annotations

from typing import Any

import attrs

from rcon_core.msgs.text import to_text
from rcon_core.plugins import NotAValue, Role
from rcon_core.plugins.paths import PathError, get_path, set_path, split_service_path

from .base import StdModel
from .common import field_at, part_type

__all__ = ["SwitchSettings", "SwitchModel", "SwitchValue"]


@attrs.define
class SwitchSettings:
    on_text: str = attrs.field(default="On", metadata={"label": "On text"})
    off_text: str = attrs.field(default="Off", metadata={"label": "Off text"})
    state_topic: str = attrs.field(
        default="", metadata={"label": "State topic",
                              "help": "service switches: a topic with the robot's real state, e.g. /lights/state"}
    )
    state_field: str = attrs.field(default="data", metadata={"label": "State field", "help": "bool field in it"})
    stale_after: float = attrs.field(default=30.0, metadata={"label": "Stale after (s)", "min": 0.0,
                                                            "help": "0 = a static (latched) topic: never stale once it delivered"})
    confirm: bool = attrs.field(
        default=False, metadata={"label": "Ask before sending",
                                 "help": "a dialog shows the exact service and request (or topic and message) first; nothing is sent until Send"}
    )
    hold_to_send: bool = attrs.field(
        default=False, metadata={"label": "Hold to send",
                                 "help": "press and hold 1 s (a bar fills) to send; a shorter press sends nothing"}
    )

    def problems(self) -> list[str]:
        out = []
        if self.state_topic and not self.state_topic.startswith("/"):
            out.append(f"state topic {self.state_topic!r} must start with '/'")
        if self.state_topic and not self.state_field:
            out.append("state field must name the bool field of the state topic (e.g. data)")
        if not self.stale_after >= 0:
            out.append("'stale after' cannot be negative (0 = a static topic)")
        return out


@attrs.frozen
class SwitchValue:
    on: bool | None  #: the state shown; None = not known yet
    busy: bool = False  #: a service call is on its way
    wanted: bool | None = None  #: what the busy call asked for
    reply: str = ""  #: the server's message of the last call
    #: the state ``reply`` speaks about (what the call set, or kept on a refusal); once the robot's
    #: state moves away from it the reply is old news and is dropped
    reply_for: bool | None = None


class SwitchModel(StdModel):
    def __init__(self, settings: SwitchSettings | None, *args: Any, **kwargs: Any) -> None:
        super().__init__(settings if settings is not None else SwitchSettings(), *args, **kwargs)
        self._state_sub: Any = None
        self._on: bool | None = None

    # -- subscribe / state topic ---------------------------------------------------------------------
    def on_start(self) -> None:
        super().on_start()
        s = self.settings
        if self.binding.role is Role.CALL and s.state_topic and not self.binding.problems():
            self._state_sub = self.port.subscribe(s.state_topic, self._on_state)

    def on_stop(self) -> None:
        if self._state_sub is not None:
            try:
                self._state_sub.unsubscribe()
            except Exception as exc:
                self.set_error(f"while stopping: {exc}")
            self._state_sub = None

    def _on_state(self, msg: dict[str, Any]) -> None:
        try:
            on = bool(get_path(msg, self.settings.state_field))
        except PathError as exc:
            self.set_error(f"state topic: {exc}")
            return
        self._on = on
        cur = self.state.value
        if not isinstance(cur, SwitchValue):
            self.set_value(SwitchValue(on), message=msg)
            return
        reply, reply_for = cur.reply, cur.reply_for
        if not cur.busy and reply and reply_for is not None and on != reply_for:
            reply, reply_for = "", None  # the state moved on (changed elsewhere): the old answer no longer applies
        self.set_value(SwitchValue(on, cur.busy, cur.wanted if cur.busy else None, reply, reply_for), message=msg)

    def to_value(self, field_value: Any, msg: dict[str, Any]) -> SwitchValue:
        if not isinstance(field_value, bool):
            raise NotAValue(f"{self.binding.field_path or 'the message'} is not a bool: {field_value!r}")
        self._on = field_value
        return SwitchValue(field_value)

    # -- actions (any thread) -----------------------------------------------------------------------
    def toggle(self) -> None:
        """Flip the shown state (off when unknown)."""
        self.set(not bool(self._on))

    def set(self, on: bool) -> None:
        """Ask for ``on``: publish it, or call the service with it."""
        role = self.binding.role
        if role is Role.PUBLISH:
            if self.publish_value(bool(on)):
                self._on = bool(on)
                self.set_value(SwitchValue(bool(on)))
        elif role is Role.CALL:
            self._call(bool(on))
        else:
            self.set_error("this switch only shows the state (subscribe)")

    def describe_set(self, on: bool) -> tuple[str, str] | None:
        """What :meth:`set` sends, for "ask before sending": ``(what, detail)`` with the exact service (or
        topic), type and request (or message) as YAML; None when it cannot be built yet."""
        b = self.binding
        if b.problems() or not self.types_ready or b.role is Role.SUBSCRIBE:
            return None
        try:
            if b.role is Role.PUBLISH:
                return f"Publish on {b.name} ({b.type})?", f"Message:\n{to_text(self.build_message(bool(on))).strip()}"
            return f"Call {b.name} ({b.type})?", f"Request:\n{to_text(self.request_for(bool(on))).strip()}"
        except (PathError, KeyError, ValueError):
            return None

    def request_for(self, on: bool) -> dict[str, Any]:
        """The service request: the default request with ``on`` at the bound ``request.*`` field."""
        part, rest = split_service_path(self.request_path())
        req = self.types.default(self.types.service_part_name(self.binding.type, part)) if self.types_ready else {}
        return set_path(req, rest, on)

    def request_path(self) -> str:
        for p in self.binding.field_paths:
            if p.startswith("request."):
                return p
        return "request.data"

    def _call(self, on: bool) -> None:
        cur = self.state.value
        reply, reply_for = (cur.reply, cur.reply_for) if isinstance(cur, SwitchValue) else ("", None)
        self.set_value(SwitchValue(self._on, True, on, reply, reply_for))
        try:
            req = self.request_for(on)
        except PathError as exc:
            self.set_value(SwitchValue(self._on, False, None, reply, reply_for))
            self.set_error(str(exc))
            return

        def go() -> None:
            self.spawn(self._do_call(on, req))

        self._dispatch(go)

    async def _do_call(self, on: bool, req: dict[str, Any]) -> None:
        try:
            resp = await self.port.call_service(self.binding.name, req, timeout=self.call_timeout)
        except Exception as exc:
            self.set_value(SwitchValue(self._on, False, None, str(exc), self._on))
            self.set_error(f"{self.binding.name}: {exc}")
            return
        ok = resp.get("success", True) is not False if isinstance(resp, dict) else True
        text = str(resp.get("message", "")) if isinstance(resp, dict) else ""
        if ok and not self.settings.state_topic:
            self._on = on
        # an accepted call speaks about the state it asked for (the state topic may confirm it before or
        # after this answer); a refusal about the state that stayed
        self.set_value(SwitchValue(self._on, False, None, text, on if ok else self._on), message=resp)
        if not ok:
            self.set_error(f"{self.binding.name} refused: {text or 'success is false'}")

    def problems(self) -> list[str]:
        out = super().problems()
        b = self.binding
        if b.problems() or not self.types_ready:
            return out
        path = self.request_path() if b.role is Role.CALL else b.field_path
        try:
            f = field_at(self.types, b.type, path, b.role.is_service)
        except (PathError, KeyError, ValueError) as exc:
            return [*out, f"field: {exc}"]
        if f is None or f.base != "bool" or f.array_len is not None:
            t = part_type(self.types, b.type, path, b.role.is_service)[0]
            return [*out, f"{path or 'the message'} of {t} is not a bool field"]
        return out
