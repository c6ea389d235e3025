"""Slider: sets (publish) or shows (subscribe) one numeric field: std_msgs Float32/64, Int8..64,
UInt8..64 or any numeric field of a larger message. Settings and model; the view is ``slider_view``."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import attrs

from rcon_core.plugins import Role
from rcon_core.plugins.paths import PathError, get_path

from .base import StdModel
from .common import INT_LIMITS, SANE_LIMIT, RateLimiter, envelope_limit, field_at, sane_limits, type_limits

__all__ = ["SliderSettings", "SliderModel", "NumberRange", "PUBLISH_ON_RELEASE", "PUBLISH_CONTINUOUS"]

PUBLISH_ON_RELEASE = "release"
PUBLISH_CONTINUOUS = "continuous"


@attrs.define
class SliderSettings:
    minimum: float = attrs.field(default=0.0, metadata={"label": "Minimum"})
    maximum: float = attrs.field(default=1.0, metadata={"label": "Maximum"})
    step: float = attrs.field(default=0.01, metadata={"label": "Step", "help": "values snap to minimum + n*step"})
    rate_hz: float = attrs.field(
        default=10.0, metadata={"label": "Update rate (Hz)", "min": 0.1, "max": 100.0,
                                "help": "at most this many messages per second while dragging"}
    )
    publish_mode: str = attrs.field(
        default=PUBLISH_ON_RELEASE,
        metadata={"label": "Publish", "choices": [PUBLISH_ON_RELEASE, PUBLISH_CONTINUOUS],
                  "help": "release: once when the handle is let go; continuous: while dragging too"},
    )
    decimals: int = attrs.field(default=2, metadata={"label": "Decimals", "min": 0, "max": 9})
    units: str = attrs.field(default="", metadata={"label": "Units"})
    stale_after: float = attrs.field(default=5.0, metadata={"label": "Stale after (s)", "min": 0.0,
                                                           "help": "0 = a static (latched) topic: never stale once it delivered"})
    initial: float = attrs.field(
        default=0.0, metadata={"label": "Start value",
                               "help": "publish sliders: where the handle rests until something is sent or heard "
                                       "(the value reads \"not set\" until then)"}
    )
    follow_topic: bool = attrs.field(
        default=True, metadata={"label": "Follow the topic",
                                "help": "publish sliders: also show values others publish on the topic"}
    )

    def problems(self) -> list[str]:
        out = [] if isinstance(self.initial, (int, float)) and math.isfinite(self.initial) else [
            f"start value must be a finite number, not {self.initial!r}"]
        if not out and abs(self.initial) > SANE_LIMIT:
            out.append(f"start value {self.initial:g} is out of any sane range (at most ±{SANE_LIMIT:g})")
        return out + range_problems(self.minimum, self.maximum, self.step, self.rate_hz) + (
            [] if self.publish_mode in (PUBLISH_ON_RELEASE, PUBLISH_CONTINUOUS)
            else [f"publish must be {PUBLISH_ON_RELEASE!r} or {PUBLISH_CONTINUOUS!r}, not {self.publish_mode!r}"]
        )

    def commands(self, binding: Any) -> list[tuple[str, float]]:
        """(field path, the largest value it may send there): checked against the robot's safety envelope."""
        return numeric_commands(self, binding)


def numeric_commands(settings: Any, binding: Any) -> list[tuple[str, float]]:
    """A Slider's or Stepper's ``commands(binding)``: the largest number it may send on its field (what the
    app compares with the robot's safety envelope before saving the settings)."""
    if getattr(binding, "role", None) not in (Role.PUBLISH, "publish"):
        return []
    try:
        top = max(abs(float(settings.minimum)), abs(float(settings.maximum)))
    except (TypeError, ValueError):
        return []
    return [(binding.field_path, top)]


def range_problems(minimum: float, maximum: float, step: float, rate_hz: float) -> list[str]:
    out = []
    for name, v in (("minimum", minimum), ("maximum", maximum), ("step", step), ("update rate", rate_hz)):
        if not isinstance(v, (int, float)) or not math.isfinite(v):
            out.append(f"{name} must be a finite number, not {v!r}")
    if out:
        return out
    for name, v in (("minimum", minimum), ("maximum", maximum), ("step", step)):
        if abs(v) > SANE_LIMIT:  # 999999999999 typed for 1.0: a slip of a finger, never a range
            out.append(f"{name} {v:g} is out of any sane range (at most ±{SANE_LIMIT:g}): a slip of a finger?")
    if out:
        return out
    if minimum >= maximum:
        out.append(f"minimum ({minimum:g}) must be less than maximum ({maximum:g})")
    if step <= 0:
        out.append(f"step must be more than 0, not {step:g}")
    elif step > maximum - minimum > 0:
        out.append(f"step ({step:g}) is larger than the range ({maximum - minimum:g})")
    if rate_hz <= 0:
        out.append(f"update rate must be more than 0 Hz, not {rate_hz:g}")
    return out


@attrs.frozen
class NumberRange:
    """The usable range of a numeric field: settings clamped to what the field's type holds."""

    minimum: float
    maximum: float
    step: float
    integer: bool
    base: str = "float64"
    clamped: bool = False  #: the settings asked for more than the type holds (or the envelope allows)
    why: str = ""  #: what limits it, in words, when ``clamped`` ("what a int8 holds", "the safety envelope")

    def coerce(self, value: float) -> float | int:
        """Clamp into the range and snap to the step grid (ints for integer fields)."""
        v = min(self.maximum, max(self.minimum, float(value)))
        n = round((v - self.minimum) / self.step)
        v = min(self.maximum, self.minimum + n * self.step)
        if self.integer:
            return int(min(self.maximum, max(self.minimum, round(v))))
        return round(v, 12)

    @property
    def steps(self) -> int:
        return max(1, round((self.maximum - self.minimum) / self.step))


def number_range(minimum: float, maximum: float, step: float, base: str, limit: float | None = None,
                 units: str = "") -> NumberRange:
    """The usable range: the settings' ``minimum..maximum`` within what ``base`` holds and, when ``limit``
    is given (the robot's safety envelope on this field), within ``±limit``."""
    lo, hi = type_limits(base) or (-math.inf, math.inf)
    integer = base in INT_LIMITS
    cmin, cmax = max(minimum, lo), min(maximum, hi)
    why = f"what a {base} holds" if (cmin, cmax) != (minimum, maximum) else ""
    if limit is not None and (cmin < -limit or cmax > limit):
        cmin, cmax = max(cmin, -limit), min(cmax, limit)
        why = f"the robot's safety envelope (at most {limit:g} {units})".replace(" )", ")")
    if integer:
        cmin, cmax, step = math.ceil(cmin), math.floor(cmax), max(1, round(step))
    clamped = (cmin, cmax) != (minimum, maximum)
    return NumberRange(cmin, cmax, step, integer, base, clamped, why if clamped else "")


class NumericModel(StdModel):
    """Shared by Slider and Stepper: the bound field's type, the range, rate-limited publishing.

    ``schedule(delay, fn)`` arranges the rate limiter's one delayed send of a kept value (default: the
    bridge loop's ``call_later``); a test passes its own to run that send when it chooses, with the
    model's ``clock``.
    """

    def __init__(self, settings: Any, *args: Any,
                 schedule: Callable[[float, Callable[[], None]], Any] | None = None, **kwargs: Any) -> None:
        super().__init__(settings, *args, **kwargs)
        self._limiter = RateLimiter(self._send, settings.rate_hz if settings is not None else 10.0,
                                    schedule=schedule, clock=self._clock)

    @property
    def field_base(self) -> str:
        """The numeric type of the bound field (``float64`` until the type is known)."""
        if not self.types_ready:
            return "float64"
        try:
            f = field_at(self.types, self.binding.type, self.binding.field_path, self.binding.role.is_service)
        except (PathError, KeyError, ValueError):
            return "float64"
        return f.base if f is not None else "float64"

    @property
    def envelope_limit(self) -> float | None:
        """The robot's safety envelope on the bound field (a Twist's ``linear.x``: its maximum linear
        speed), None when it holds nothing here. Read at each use: the envelope may change."""
        return envelope_limit(self.port, self.binding.type, self.binding.field_path)

    @property
    def range(self) -> NumberRange:
        s = self.settings
        return number_range(s.minimum, s.maximum, s.step, self.field_base, self.envelope_limit,
                            "m/s" if ".angular" not in f".{self.binding.field_path}" else "rad/s")

    def problems(self) -> list[str]:
        out = super().problems()
        b = self.binding
        if b.problems() or not self.types_ready:
            return out
        try:
            f = field_at(self.types, b.type, b.field_path, b.role.is_service)
        except (PathError, KeyError, ValueError) as exc:
            return [*out, f"field: {exc}"]
        if f is None or not f.is_builtin or f.array_len is not None or type_limits(f.base) is None:
            what = "the whole message" if f is None else f"{f.name} ({f.type})"
            return [*out, f"the bound field must be a number, but it is {what}"]
        s = self.settings
        if out:  # the settings' own problems first (not a number, out of any sane range)
            return out
        lo, hi, what = sane_limits(f.base, b.type, b.field_path)
        for name, v in (("minimum", s.minimum), ("maximum", s.maximum)):
            if not lo <= v <= hi:  # a slip of a finger: refused, never silently clamped
                out.append(f"{name} {v:g} is beyond what {what}")
        r = self.range
        if not out and r.minimum >= r.maximum:
            out.append(f"the range {s.minimum:g}..{s.maximum:g} holds no value {r.why} allows"
                       if "envelope" in r.why else f"the range {s.minimum:g}..{s.maximum:g} holds no {f.base} value")
        return out

    # -- publishing (any thread) ---------------------------------------------------------------------
    def _send(self, value: float | int) -> None:
        if self.publish_value(value):
            self.set_value(value)

    def offer(self, value: float) -> float | int:
        """Rate-limited publish of the coerced value (latest wins). Returns the coerced value."""
        v = self.range.coerce(value)
        self._dispatch(lambda: self._limiter.offer(v))
        return v

    def send_now(self, value: float) -> float | int:
        """Publish the coerced value at once (a release, a click), dropping any kept one."""
        v = self.range.coerce(value)
        self._dispatch(lambda: self._limiter.now(v))
        return v

    def on_stop(self) -> None:
        self._limiter.cancel()

    # -- inside a Compound (loop thread) ---------------------------------------------------------------
    @property
    def in_compound(self) -> bool:
        """A Compound's child (its port ``composes``): nothing goes out until the compound sends, and it
        shows the number the compound *will* send (before it is touched: the start value), never "not set"."""
        return self.port.composes

    def shown_number(self) -> float | int | None:
        """The number the widget shows (None before it shows one)."""
        v = self.state.value
        return v if isinstance(v, (int, float)) and not isinstance(v, bool) else None

    def shown_message(self) -> dict[str, Any] | None:
        """For a Compound: a message holding the number shown, also before the first touch (the start
        value), so the compound sends what the operator sees, never the type's default."""
        v = self.shown_number()
        return None if v is None else self.build_message(self.range.coerce(v))


#: the value each publish slider last sent or heard, per (topic, field), for this process: a slider
#: rebuilt after a canvas switch, a reconfiguration or a reconnect shows it instead of its start value
_LAST_VALUES: dict[tuple[str, str], float | int] = {}
#: seconds after our own publish during which a different value heard on the topic is taken for an echo
#: of an earlier publish of ours (continuous mode) rather than another publisher's
ECHO_WINDOW_S = 0.5


class SliderModel(NumericModel):
    """PUBLISH: the view calls :meth:`drag` while moving and :meth:`release` when let go. The value is
    what was last sent or heard on the topic (this session); None until then (the view says "not set":
    a start value shown as if it were applied would be a lie), with the handle at :attr:`resting`. With
    ``follow_topic`` the slider also subscribes to its own topic and shows what others publish.
    SUBSCRIBE: the bound field becomes the value (a float or int)."""

    def __init__(self, settings: SliderSettings | None, *args: Any, **kwargs: Any) -> None:
        super().__init__(settings if settings is not None else SliderSettings(), *args, **kwargs)
        self._follow_sub: Any = None
        self._sent: tuple[float, float | int] | None = None  #: (when, value) of our last publish

    @property
    def _key(self) -> tuple[str, str]:
        return (self.binding.name, self.binding.field_path)

    def on_start(self) -> None:
        super().on_start()
        b = self.binding
        if b.role is not Role.PUBLISH or b.problems():
            return
        remembered = _LAST_VALUES.get(self._key)
        if remembered is not None:
            self.replace_value(self.range.coerce(remembered))
        if self.settings.follow_topic:
            self._follow_sub = self.port.subscribe(b.name, self._on_topic, type=b.type)

    @property
    def resting(self) -> float | int:
        """Where a publish slider's handle rests while nothing was sent or heard: the start value, in range."""
        return self.range.coerce(self.settings.initial)

    def shown_number(self) -> float | int | None:
        """Inside a Compound an untouched publish slider shows (and the compound sends) its resting value."""
        v = super().shown_number()
        if v is None and self.in_compound and self.binding.role is Role.PUBLISH:
            return self.resting
        return v

    def on_types_ready(self) -> None:
        super().on_types_ready()
        v = self.state.value
        if self.binding.role is Role.PUBLISH and isinstance(v, (int, float)) and not isinstance(v, bool):
            self.replace_value(self.range.coerce(v))  # the field's real type may narrow the range

    def on_stop(self) -> None:
        super().on_stop()
        if self._follow_sub is not None:
            try:
                self._follow_sub.unsubscribe()
            except Exception as exc:
                self.set_error(f"while stopping: {exc}")
            self._follow_sub = None

    def _send(self, value: float | int) -> None:
        if self.publish_value(value):
            self._sent = (self._clock(), value)
            _LAST_VALUES[self._key] = value
            self.set_value(value)

    def _on_topic(self, msg: dict[str, Any]) -> None:
        """A value on our own topic (loop thread): ours coming back, or another publisher's."""
        path = self.binding.field_path
        try:
            value = get_path(msg, path) if path else None
        except PathError:
            return  # a message without our field: nothing to show
        if not isinstance(value, (int, float)) or isinstance(value, bool):
            return
        if self._sent is not None:
            when, mine = self._sent
            if value != mine and self._clock() - when < ECHO_WINDOW_S:
                return  # an echo of an earlier publish of ours, overtaken by the last one
        _LAST_VALUES[self._key] = value
        self.set_value(value, message=msg)

    def drag(self, value: float) -> float | int:
        """The handle moved: publishes (rate-limited) only in continuous mode."""
        if self.settings.publish_mode == PUBLISH_CONTINUOUS:
            return self.offer(value)
        return self.range.coerce(value)

    def release(self, value: float) -> float | int:
        """The handle was let go: the final value is always published, at once."""
        return self.send_now(value)

    def on_message(self, msg: dict[str, Any]) -> None:
        if self.binding.role is Role.SUBSCRIBE:
            super().on_message(msg)
