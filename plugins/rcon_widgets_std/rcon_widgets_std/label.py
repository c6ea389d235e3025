"""Label: shows one field (or the whole message) of any subscribed topic, with decimals, units and the
age of the data. Settings and model; the Qt view is in ``label_view``.

A field the message definition gives as a fraction of 1 (``sensor_msgs/BatteryState.percentage``: "charge
percentage on 0 to 1 range") is shown in % when the settings leave the scale at 1 and the units empty:
``85 %``, never ``0.85`` (the decimals count for the percentage, less two, so the default 2 shows a whole
percent)."""

from __future__ import annotations

from typing import Any

import attrs

from rcon_core.msgs.names import pkg_type

from .base import StdModel
from .common import format_value, shorten_text

__all__ = ["LabelSettings", "LabelModel", "LabelValue"]


@attrs.define
class LabelSettings:
    decimals: int = attrs.field(
        default=2, metadata={"label": "Decimals", "min": -1, "max": 12, "special": "as received",
                             "help": "digits after the point; 'as received' (-1) shows numbers as they arrive"}
    )
    units: str = attrs.field(default="", metadata={"label": "Units", "help": "e.g. m/s, %, V"})
    scale: float = attrs.field(
        default=1.0, metadata={"label": "Scale", "help": "numbers are multiplied by this (100 for a 0..1 fraction in %)"}
    )
    stale_after: float = attrs.field(
        default=5.0, metadata={"label": "Stale after (s)", "min": 0.0, "max": 3600.0,
                               "help": "mark the value stale when nothing new arrived for this long; "
                                       "0 = a static (latched) topic: never stale once it delivered"}
    )

    def problems(self) -> list[str]:
        out = []
        if not -1 <= self.decimals <= 12:
            out.append(f"decimals must be between -1 and 12, not {self.decimals}")
        if not self.stale_after >= 0:
            out.append(f"'stale after' cannot be negative (0 = a static topic), not {self.stale_after}")
        if self.scale == 0:
            out.append("scale must not be 0")
        return out


@attrs.frozen
class LabelValue:
    """What the view paints: the text, ready (formatted on the bridge thread), and the raw value."""

    text: str
    raw: Any
    numeric: bool


#: fields defined as a fraction of 1, by (type, field path): shown in % unless the settings scale them
FRACTIONS = frozenset({("sensor_msgs/BatteryState", "percentage"),
                       ("sensor_msgs/RelativeHumidity", "relative_humidity")})


class LabelModel(StdModel):
    """Subscriber: the bound field becomes a :class:`LabelValue`."""

    needs_types = False

    def __init__(self, settings: LabelSettings | None, *args: Any, **kwargs: Any) -> None:
        super().__init__(settings if settings is not None else LabelSettings(), *args, **kwargs)
        b = self.binding
        #: the bound field is a fraction of 1 (BatteryState.percentage): shown in % (see the module docstring)
        self.fraction = (pkg_type(b.type), b.field_path) in FRACTIONS if b.type else False

    def to_value(self, field_value: Any, msg: dict[str, Any]) -> LabelValue:
        return self.make_value(field_value)

    def make_value(self, value: Any) -> LabelValue:
        s = self.settings
        numeric = isinstance(value, (int, float)) and not isinstance(value, bool)
        if numeric and self.fraction and s.scale == 1.0 and not s.units:
            percent = value * 100.0
            decimals = max(0, s.decimals - 2) if s.decimals >= 0 else -1
            return LabelValue(format_value(percent, decimals, "%"), percent, True)
        if numeric and s.scale != 1.0:
            value = value * s.scale
        # a value of any size shows at most SHOW_CHARS / SHOW_ROWS (a 1 MB String took the GUI 1 s to
        # measure per value); "Copy value" still copies a whole string (``raw``)
        text, _whole = shorten_text(format_value(value, s.decimals, s.units))
        return LabelValue(text, value, numeric)
