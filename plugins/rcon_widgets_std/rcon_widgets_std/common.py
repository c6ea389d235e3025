"""Helpers shared by the standard widgets' models: field types and limits, number formatting, message
summaries, learning unknown types from the robot, and a rate limiter. Pure Python, no Qt."""

from __future__ import annotations

import asyncio
import copy
import math
import time
from collections.abc import Callable
from typing import Any

from rcon_core.msgs import FieldDef
from rcon_core.plugins import Port
from rcon_core.plugins.paths import PathError, parse_path, split_service_path

__all__ = [
    "INT_LIMITS",
    "FLOAT32_MAX",
    "NUMERIC_TYPES",
    "field_at",
    "part_type",
    "type_limits",
    "SANE_LIMIT",
    "sane_limits",
    "envelope_limit",
    "held_to_envelope",
    "format_number",
    "format_value",
    "summarize",
    "shorten_text",
    "copy_message",
    "SHOW_CHARS",
    "SHOW_ROWS",
    "learn_type",
    "RateLimiter",
]

INT_LIMITS: dict[str, tuple[int, int]] = {
    "int8": (-(2**7), 2**7 - 1),
    "uint8": (0, 2**8 - 1),
    "byte": (0, 2**8 - 1),
    "char": (0, 2**8 - 1),
    "int16": (-(2**15), 2**15 - 1),
    "uint16": (0, 2**16 - 1),
    "int32": (-(2**31), 2**31 - 1),
    "uint32": (0, 2**32 - 1),
    "int64": (-(2**63), 2**63 - 1),
    "uint64": (0, 2**64 - 1),
}
FLOAT32_MAX = 3.4028234663852886e38

#: the std_msgs types that hold one number in ``data`` (the Slider's and Stepper's exact types)
NUMERIC_TYPES = tuple(
    f"std_msgs/{t}"
    for t in ("Float32", "Float64", "Int8", "Int16", "Int32", "Int64", "UInt8", "UInt16", "UInt32", "UInt64")
)


def part_type(types: Any, type_name: str, path: str, service: bool) -> tuple[str, str]:
    """(message type, path inside it) for a binding: services strip their ``request``/``response`` head."""
    if not service:
        return types.resolve(type_name), path
    part, rest = split_service_path(path)
    return types.service_part_name(type_name, part), rest


def field_at(types: Any, type_name: str, path: str, service: bool = False) -> FieldDef | None:
    """The definition of the field at ``path`` (None for the whole message or a service side).

    Raises PathError naming the missing part, or the registry's UnknownTypeError.
    """
    msg_type, rest = part_type(types, type_name, path, service)
    found: FieldDef | None = None
    current = msg_type
    for part in parse_path(rest):
        if isinstance(part, int):
            if found is None or found.array_len is None:
                raise PathError(f"{rest!r}: [{part}] indexes something that is not an array")
            found = FieldDef(found.name, found.base, found.base, None, found.is_builtin)
            current = found.base
            continue
        if found is not None and found.is_builtin:
            raise PathError(f"{rest!r}: {found.name!r} is a {found.base}, it has no field {part!r}")
        by_name = {f.name: f for f in types.fields(current)}
        if part not in by_name:
            raise PathError(f"{current} has no field {part!r} (path {rest!r})")
        found = by_name[part]
        current = found.base
    return found


def type_limits(base: str) -> tuple[float, float] | None:
    """(lowest, highest) a numeric field type can hold; None for non-numeric types."""
    if base in INT_LIMITS:
        return INT_LIMITS[base]
    if base == "float32":
        return (-FLOAT32_MAX, FLOAT32_MAX)
    if base == "float64":
        return (-math.inf, math.inf)
    return None


#: a Slider's or Stepper's numbers beyond this are a slip of a finger (999999999999 typed for 1.0), never a
#: range anyone means: a slider has at most 100,000 positions, and floats lose their steps up there
SANE_LIMIT = 1e9


def sane_limits(base: str, type_name: str = "", path: str = "") -> tuple[float, float, str]:
    """(lowest, highest, words) a numeric setting for the field at ``path`` of ``type_name`` (a ``base``
    number) may be: what the type holds, within :data:`SANE_LIMIT`; on a motion command's field (a Twist's
    ``linear.x``) what any robot's safety envelope may allow (100 m/s, 50 rad/s). ``words`` says which, to
    follow "beyond what": "a int8 holds (-128..127)"."""
    from rcon_core.bridge.envelope import MAX_ANGULAR, MAX_LINEAR, motion_path

    motion = motion_path(type_name, path) if type_name else None
    if motion is not None:
        top, units = (MAX_LINEAR, "m/s") if motion[0] == "linear" else (MAX_ANGULAR, "rad/s")
        return -top, top, f"any safety envelope allows on {motion[0]} (±{top:g} {units})"
    lo, hi = type_limits(base) or (-SANE_LIMIT, SANE_LIMIT)
    if base in INT_LIMITS:
        return lo, hi, f"a {base} holds ({lo}..{hi})"
    lo, hi = max(lo, -SANE_LIMIT), min(hi, SANE_LIMIT)
    return lo, hi, f"is sane (±{SANE_LIMIT:g})"


def envelope_limit(port: Port, type_name: str, path: str) -> float | None:
    """The robot's safety envelope on the field at ``path`` of ``type_name`` as ``port`` tells it (None
    outside a canvas): None when nothing limits it."""
    env = port.envelope
    if env is None:
        return None
    try:
        return env.limit_for(type_name, path)
    except Exception:  # a port's odd envelope never stops a widget: the bridge still holds the robot
        return None


def held_to_envelope(port: Port, type_name: str, msg: dict[str, Any]) -> tuple[dict[str, Any] | None, str]:
    """(the message that will actually be sent, a sentence) for ``msg`` under the robot's safety envelope:
    the message clamped ("held to the safety envelope: linear.x 5 → 1"), or None with why it is refused
    (NaN, infinity). The bridge holds every command to the same envelope; a widget calls this to *say*
    what is sent. A motion command is judged even without an envelope (non-numbers are never sent)."""
    from rcon_core.bridge.envelope import NO_LIMITS, Envelope

    env = port.envelope
    verdict = (env if isinstance(env, Envelope) else NO_LIMITS).judge(type_name, msg)
    return verdict.msg, verdict.sentence


def format_number(value: float | None, decimals: int = -1) -> str:
    """``decimals`` < 0: as it came -- ints stay ints, floats with every digit they carry (15 significant
    digits: 43.6532117 stays 43.6532117, never rounded to 6; a whole float without its ".0")."""
    if value is None:
        return "NaN"  # NaN/Inf arrive as None on the JSON wire
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value) if decimals < 0 else f"{value:.{decimals}f}"
    if not math.isfinite(value):
        return str(value)
    text = f"{value:.15g}" if decimals < 0 else f"{value:.{decimals}f}"
    if text.startswith("-") and float(text) == 0.0:
        return text[1:]  # -0.001 at 2 decimals, or -0.0 itself: "0.00", never "-0.00"
    return text


#: the most a text widget shows of one value: characters and rows (the rest is cut, see shorten_text)
SHOW_CHARS = 2000
SHOW_ROWS = 40
#: keys of one mapping and levels of nesting a summary shows (a message is a handful of each)
_SUMMARY_KEYS = 64
_SUMMARY_DEPTH = 12


def summarize(value: Any, max_items: int = 8, max_chars: int = 80, _depth: int = 0) -> Any:
    """A shortened copy of a message for people: long arrays and strings cut, bytes counted; bounded in
    keys per mapping and in depth too (a hostile message of 200,000 keys took 10 s to write as YAML)."""
    if _depth >= _SUMMARY_DEPTH and isinstance(value, (dict, list)):
        return "…"
    if isinstance(value, dict):
        out = {}
        for i, (k, v) in enumerate(value.items()):
            if i == _SUMMARY_KEYS:
                out["…"] = f"{len(value) - _SUMMARY_KEYS} more"
                break
            out[k] = summarize(v, max_items, max_chars, _depth + 1)
        return out
    if isinstance(value, (bytes, bytearray)):
        return f"<{len(value)} bytes>"
    if isinstance(value, list):
        if len(value) > max_items:
            head = [summarize(v, max_items, max_chars, _depth + 1) for v in value[:max_items]]
            return [*head, f"... {len(value) - max_items} more"]
        return [summarize(v, max_items, max_chars, _depth + 1) for v in value]
    if isinstance(value, float) and value == 0.0:
        return 0.0  # -0.0 reads as a sign where there is none
    if isinstance(value, str) and len(value) > max_chars:
        return value[: max_chars - 1] + "…"
    return value


_ATOMIC = frozenset({int, float, str, bool, type(None), bytes})


def copy_message(value: Any) -> Any:
    """A deep copy of a message (dicts, lists, scalars), about ten times faster than ``copy.deepcopy`` on
    long arrays: a list is copied at C speed and only its dict or list items are copied again (a
    1,000,000-element array took 0.5 s per ``deepcopy``, several per service request). Anything else is
    ``deepcopy``'d."""
    kind = type(value)
    if kind is dict:
        return {k: v if type(v) in _ATOMIC else copy_message(v) for k, v in value.items()}
    if kind is list:
        out = value.copy()
        for i, v in enumerate(out):
            if type(v) not in _ATOMIC:
                out[i] = copy_message(v)
        return out
    if kind in _ATOMIC:
        return value
    return copy.deepcopy(value)


def shorten_text(text: str, chars: int = SHOW_CHARS, rows: int = SHOW_ROWS) -> tuple[str, int | None]:
    """``text`` cut to at most ``chars`` characters and ``rows`` rows (line ends made ``\n``), and the
    whole length when it was cut (else None). Costs at most ``chars`` whatever the length of ``text``: a
    view never measures or lays out a megabyte-long string."""
    head = text[:chars]
    if "\r" in head:
        head = head.replace("\r\n", "\n").replace("\r", "\n")
    parts = head.split("\n", rows)
    if len(parts) > rows:
        return "\n".join(parts[:rows]), len(text)
    return head, (len(text) if len(text) > chars else None)


def format_value(value: Any, decimals: int = -1, units: str = "") -> str:
    """Any field value or message as text for a label: numbers with decimals and units, messages as YAML."""
    if isinstance(value, (int, float)) or value is None:
        text = format_number(value, decimals)
        return f"{text} {units}".rstrip() if units else text
    if isinstance(value, str):
        return f"{value} {units}".rstrip() if units else value
    if isinstance(value, dict) and set(value) in ({"secs", "nsecs"}, {"sec", "nanosec"}):
        from rcon_core.msgs import time as rtime

        return f"{rtime.to_float(value):.3f} s"
    import yaml

    short = summarize(value)
    if isinstance(short, list) and all(isinstance(v, (int, float)) or v is None for v in short):
        return "[" + ", ".join(format_number(v, decimals) for v in short) + "]"
    return yaml.safe_dump(short, sort_keys=False, default_flow_style=False, allow_unicode=True).rstrip()


async def learn_type(port: Any, types: Any, type_name: str, service: bool = False) -> bool:
    """Teach ``types`` a message or service type it does not know, from the robot's rosapi typedefs.

    Returns True when the type is known afterwards. Uses only the port (``/rosapi/*`` services), so it
    works for any widget model; the typedefs land in the shared registry for every other widget too.
    """
    if types is None or not type_name:
        return False
    known = types.has_service(type_name) if service else types.has(type_name)
    if known:
        return True
    if service:
        for part in ("request", "response"):
            answer = await port.call_service(f"/rosapi/service_{part}_details", {"type": type_name})
            types.add_typedefs(answer.get("typedefs", []), root=types_part_name(type_name, part))
        return types.has_service(type_name)
    answer = await port.call_service("/rosapi/message_details", {"type": type_name})
    defs = answer.get("typedefs", [])
    if not defs:
        return False
    from rcon_core.msgs import names

    types.add_typedefs(defs, root=names.normalize(type_name))
    return types.has(type_name)


def types_part_name(type_name: str, part: str) -> str:
    """``("std_srvs/SetBool", "request")`` -> ``"std_srvs/srv/SetBool_Request"`` (either spelling)."""
    from rcon_core.msgs import names

    return names.part_name(type_name, part)


class RateLimiter:
    """At most one send per ``1/rate_hz`` seconds; the latest value wins and is never lost.

    ``offer(value)`` sends at once when allowed, else keeps the value and arranges (through
    ``schedule(delay, fn)``) one send at the earliest allowed time. Runs on the bridge loop thread.
    """

    def __init__(
        self,
        send: Callable[[Any], Any],
        rate_hz: float,
        schedule: Callable[[float, Callable[[], None]], Any] | None = None,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.send = send
        self.period = 1.0 / rate_hz if rate_hz and rate_hz > 0 else 0.0
        self._schedule = schedule or _loop_call_later
        self._clock = clock
        self._last: float | None = None
        self._pending: tuple[Any] | None = None
        self._timer: Any = None
        self._scheduled = False

    def offer(self, value: Any) -> None:
        now = self._clock()
        if self._last is None or now - self._last >= self.period:
            self._pending = None
            self._fire(value, now)
            return
        self._pending = (value,)
        if not self._scheduled:
            self._scheduled = True
            self._timer = self._schedule(self.period - (now - self._last), self.flush)

    def flush(self) -> None:
        """Send the kept value now (the scheduled call, or a release that must go out at once)."""
        self._timer = None
        self._scheduled = False
        if self._pending is not None:
            (value,) = self._pending
            self._pending = None
            self._fire(value, self._clock())

    def now(self, value: Any) -> None:
        """Send ``value`` immediately, dropping any kept one (e.g. on release)."""
        self._pending = None
        self._fire(value, self._clock())

    def cancel(self) -> None:
        self._pending = None
        if self._timer is not None and hasattr(self._timer, "cancel"):
            self._timer.cancel()
        self._timer = None
        self._scheduled = False

    def _fire(self, value: Any, now: float) -> None:
        self._last = now
        self.send(value)


def _loop_call_later(delay: float, fn: Callable[[], None]) -> Any:
    try:
        loop = asyncio.get_running_loop()
    except RuntimeError:  # no loop (plain tests): send at once
        fn()
        return None
    return loop.call_later(max(0.0, delay), fn)
