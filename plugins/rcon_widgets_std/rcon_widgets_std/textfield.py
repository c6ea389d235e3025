"""Text Field: shows the raw data of any topic or field (subscribe), or publishes what the operator
types (publish). Typed text is YAML or JSON turned into the topic's type with the type registry; a
string field takes the text as it is. Wrong text publishes nothing and the error names the field; NaN and
infinity count as wrong unless the "Allow NaN and infinity" setting is on."""

from __future__ import annotations

import copy
from typing import Any

import attrs

from rcon_core.msgs import MessageTextError
from rcon_core.msgs.text import parse_text
from rcon_core.plugins import Role
from rcon_core.plugins.paths import PathError, get_path, set_path

from .base import StdModel
from .common import field_at, format_value

__all__ = ["TextFieldSettings", "TextFieldModel", "TextValue"]


@attrs.define
class TextFieldSettings:
    decimals: int = attrs.field(default=-1, metadata={"label": "Decimals", "min": -1, "max": 12,
                                                      "help": "for numbers shown; -1 as they arrive"})
    placeholder: str = attrs.field(default="", metadata={"label": "Hint", "help": "grey text in the empty field"})
    clear_after_send: bool = attrs.field(default=False, metadata={"label": "Clear after sending"})
    stale_after: float = attrs.field(default=10.0, metadata={"label": "Stale after (s)", "min": 0.0,
                                                            "help": "0 = a static (latched) topic: never stale once it delivered"})
    allow_nonfinite: bool = attrs.field(
        default=False, metadata={"label": "Allow NaN and infinity",
                                 "help": "off: nan, inf and null are refused for numbers (JSON sends them as null)"})

    def problems(self) -> list[str]:
        out = []
        if not -1 <= self.decimals <= 12:
            out.append(f"decimals must be between -1 and 12, not {self.decimals}")
        if not self.stale_after >= 0:
            out.append("'stale after' cannot be negative (0 = a static topic)")
        return out


@attrs.frozen
class TextValue:
    text: str  #: what arrived (subscribe) or what was sent (publish), as text
    sent: bool = False


class TextFieldModel(StdModel):
    def __init__(self, settings: TextFieldSettings | None, *args: Any, **kwargs: Any) -> None:
        super().__init__(settings if settings is not None else TextFieldSettings(), *args, **kwargs)

    @property
    def needs_types(self) -> bool:  # type: ignore[override]
        return self.binding.role is Role.PUBLISH

    def on_message(self, msg: dict[str, Any]) -> None:
        path = self.binding.field_path
        try:
            value = get_path(msg, path) if path else msg
        except PathError as exc:
            self.set_error(str(exc))
            return
        self.set_value(TextValue(format_value(value, self.settings.decimals)), message=msg)

    # -- typed text -> message -----------------------------------------------------------------------
    def _is_string_field(self) -> bool:
        path = self.binding.field_path
        if not path:
            return False
        try:
            f = field_at(self.types, self.binding.type, path)
        except (PathError, KeyError, ValueError):
            return False
        return f is not None and f.is_builtin and f.array_len is None and f.base in ("string", "wstring")

    def parse(self, text: str) -> dict[str, Any]:
        """The message to publish for ``text``; raises MessageTextError (``.path`` names the field)."""
        b = self.binding
        if not self.types_ready:
            raise MessageTextError("", f"the type {b.type} is not known yet (asking the robot)")
        path = b.field_path
        finite = not self.settings.allow_nonfinite  # NaN/inf only when the operator allowed them
        if not path:
            return self.types.from_text(b.type, text, finite=finite)
        value: Any = text if self._is_string_field() else parse_text(text)
        if value == {} and not text.strip():
            raise MessageTextError(path, "nothing typed")
        msg = set_path(copy.deepcopy(self.types.default(b.type)), path, value)
        return self.types.complete(b.type, msg, finite=finite)

    def submit(self, text: str) -> None:
        """Parse and publish ``text`` on the bridge thread (any thread may call this)."""
        self._dispatch(lambda: self._submit(text))

    def _submit(self, text: str) -> bool:
        try:
            msg = self.parse(text)
        except MessageTextError as exc:
            self.set_error(f"not sent: {exc}")
            return False
        if self.publish(msg):
            self.set_value(TextValue(text, sent=True), message=msg)
            return True
        return False
