"""Text Field: shows the raw data of any topic or field (subscribe), or publishes what the operator
types (publish). Typed text is YAML or JSON turned into the topic's type with the type registry; a
string field takes the text as it is. Wrong text publishes nothing and the error names the field; NaN and
infinity count as wrong unless the "Allow NaN and infinity" setting is on.

Inside a Compound (its port ``composes``) nothing reaches the robot until the compound sends: the view
hands every change of the text to :meth:`TextFieldModel.set_draft`, which checks it at once (the error
names the field, or the value reads "will send"), and the compound takes the typed text, parsed, when
it sends (:meth:`TextFieldModel.shown_message`); unparsable or missing text blocks the compound's send."""

from __future__ import annotations

import copy
from typing import Any

import attrs

from rcon_core.msgs import MessageTextError
from rcon_core.msgs.text import parse_text
from rcon_core.plugins import Role
from rcon_core.plugins.paths import PathError, set_path

from .base import StdModel
from .common import field_at, format_value, held_to_envelope, shorten_text

__all__ = ["TextFieldSettings", "TextFieldModel", "TextValue"]


@attrs.define
class TextFieldSettings:
    decimals: int = attrs.field(default=-1, metadata={"label": "Decimals", "min": -1, "max": 12,
                                                      "special": "as received",
                                                      "help": "for numbers shown; 'as received' (-1) as they arrive"})
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
    #: inside a Compound: the typed text parses; it is what the compound will send
    ready: bool = False
    #: what the robot's safety envelope made of it ("held to the safety envelope: linear.x 5 → 1")
    note: str = ""


class TextFieldModel(StdModel):
    def __init__(self, settings: TextFieldSettings | None, *args: Any, **kwargs: Any) -> None:
        super().__init__(settings if settings is not None else TextFieldSettings(), *args, **kwargs)
        self._draft = ""  #: the text in the field (inside a Compound: what it will send)

    @property
    def in_compound(self) -> bool:
        """True when this is a Compound's child: what it publishes is composed, not sent to the robot."""
        return self.port.composes

    @property
    def needs_types(self) -> bool:  # type: ignore[override]
        return self.binding.role is Role.PUBLISH

    def to_value(self, field_value: Any, msg: dict[str, Any]) -> TextValue:
        # shown at most SHOW_CHARS / SHOW_ROWS: Qt lays out a megabyte-long line for seconds (issue 22.1)
        return TextValue(shorten_text(format_value(field_value, self.settings.decimals))[0])

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
        if not text.strip() and not self._is_string_field():
            raise MessageTextError(path, "nothing typed")
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
        self._draft = text
        note = ""
        if not self.in_compound:  # a compound judges its whole message when it sends
            held, note = held_to_envelope(self.port, self.binding.type, msg)
            if held is None:
                self.set_error(note)
                return False
            msg = held
        if self.publish(msg):
            self.set_value(TextValue(text, sent=not self.in_compound, ready=self.in_compound, note=note),
                           message=msg)
            return True
        return False

    # -- inside a Compound -----------------------------------------------------------------------------
    def set_draft(self, text: str) -> None:
        """The operator changed the text (any thread): remembered and, inside a Compound, checked at
        once, so the child says what will be sent or what is wrong before the compound's Publish."""
        self._dispatch(lambda: self._check_draft(text))

    def _check_draft(self, text: str) -> None:
        self._draft = text
        if not self.in_compound:
            return
        try:
            self.parse(text)
        except MessageTextError as exc:
            self.replace_value(TextValue(text))
            self.set_error(None if exc.problem == "nothing typed" else str(exc))
            return
        self.set_error(None)
        self.replace_value(TextValue(text, ready=True))

    def shown_message(self) -> dict[str, Any]:
        """For a Compound: the typed text as a message of the bound type. Raises MessageTextError (a
        ValueError: the compound blocks its send and names this child) for nothing typed or bad text."""
        return self.parse(self._draft)
