"""The safety envelope of one robot: the largest motion command anything may send it. No Qt, no I/O.

An :class:`Envelope` holds a robot's maximum linear speed (m/s) and maximum angular speed (rad/s); either
may be None (no limit on that). It is one of the robot's settings (``Robot.envelope``, saved with the
workspace) and it is applied to every motion command that leaves for that robot, whoever made it: the
bridge client's :meth:`~rcon_core.bridge.session.Session.publish` calls :func:`enforce` on each message
(``client.envelope``), so a teleop pad, a slider, a Compound, a text field, a lab's plugin, a raw node of
the client and ``rcon pub --envelope`` are held alike. Widgets read the same envelope (their port's
``envelope``) to show what is actually sent; the bridge is the backstop that holds when they do not.

Which messages: the motion commands ``geometry_msgs/Twist`` and ``geometry_msgs/TwistStamped`` (its
``twist``), in both the ROS 1 (``geometry_msgs/Twist``) and ROS 2 (``geometry_msgs/msg/Twist``)
spellings. Every other type passes untouched.

Decision: clamp each component, refuse what is not a number.
    A speed limit does what an operator expects of it: a command beyond it is sent *at* the limit, each
    component of ``linear`` (x, y, z) clamped to ``±max_linear`` and each of ``angular`` to
    ``±max_angular`` (a pad pushed past the limit drives at the limit; it does not stop). Clamping per
    component, not the vector's length, keeps the command's axes apart (turning never slows forward
    motion) and is what ``twist_mux``-style limiters on robots do. A value that is not a finite number --
    NaN, infinity (both travel as JSON ``null``), a string, a bool -- or a ``linear``/``angular`` that is
    not a mapping, is *refused*: nothing is sent (:class:`EnvelopeRefused`, a ``ValueError`` whose text is
    the sentence for the operator). This holds even with no envelope set (:data:`NO_LIMITS`): such a
    command is never meaningful. A missing field is left out (rosbridge fills in 0).

What :func:`enforce` counts: ``stats.envelope_clamped`` and ``stats.envelope_refused`` (the client's
``stats``, a ``BridgeStats``). A clamped message is a copy; the caller's dict is never changed.
"""

from __future__ import annotations

import math
import numbers
from typing import Any

import attrs

from rcon_core.msgs.names import pkg_type

from .stats import BridgeStats

__all__ = ["Envelope", "EnvelopeRefused", "Verdict", "NO_LIMITS", "COMMAND_TYPES", "MAX_LINEAR", "MAX_ANGULAR",
           "enforce", "is_command", "motion_path"]

#: the motion command types (``pkg/Type`` keys) -> where the twist sits in the message
COMMAND_TYPES: dict[str, str] = {"geometry_msgs/Twist": "", "geometry_msgs/TwistStamped": "twist"}
#: the most an envelope itself may allow: 100 m/s (360 km/h) and 50 rad/s; more is a slip of a finger
MAX_LINEAR = 100.0
MAX_ANGULAR = 50.0
_UNITS = {"linear": "m/s", "angular": "rad/s"}


class EnvelopeRefused(ValueError):
    """A motion command that is not sent (a value that is not a finite number); the text says why."""


def is_command(type_name: str) -> bool:
    """Whether messages of ``type_name`` (either spelling) are motion commands the envelope holds."""
    return isinstance(type_name, str) and pkg_type(type_name) in COMMAND_TYPES


def motion_path(type_name: str, path: str) -> tuple[str, str] | None:
    """``("linear"|"angular", axis or "")`` for a field path inside a motion command (``linear.x``,
    ``twist.angular.z``, ``linear``); None for any other path or type."""
    if not is_command(type_name):
        return None
    base = COMMAND_TYPES[pkg_type(type_name)]
    if base:
        if path != base and not path.startswith(base + "."):
            return None
        path = path[len(base) + 1:]
    part, _, axis = path.partition(".")
    if part not in _UNITS or (axis and axis not in ("x", "y", "z")):
        return None
    return part, axis


def _fmt(v: float) -> str:
    return f"{v:.3g}"


@attrs.frozen
class Verdict:
    """What the envelope makes of one message: ``msg`` to send (the same object when nothing changed,
    else a copy), ``clamped`` ((path, asked, sent) for each clamped value), ``refused`` (why nothing may be
    sent; ``msg`` is then None)."""

    msg: dict[str, Any] | None
    clamped: tuple[tuple[str, float, float], ...] = ()
    refused: str = ""

    @property
    def sentence(self) -> str:
        """One sentence for the operator ("" when the message went out as it was)."""
        if self.refused:
            return self.refused
        if not self.clamped:
            return ""
        parts = ", ".join(f"{p} {_fmt(a)} → {_fmt(s)}" for p, a, s in self.clamped)
        return f"held to the safety envelope: {parts}"


@attrs.frozen
class Envelope:
    """A robot's safety envelope (see the module docstring). ``None``: no limit on that part."""

    max_linear: float | None = None  #: m/s, each of linear.x/y/z
    max_angular: float | None = None  #: rad/s, each of angular.x/y/z

    # -- the value ---------------------------------------------------------------------------------------
    def problems(self) -> list[str]:
        """What is wrong with this envelope (empty when it may be used)."""
        out = []
        for name, value, top, units in (("maximum linear speed", self.max_linear, MAX_LINEAR, "m/s"),
                                        ("maximum angular speed", self.max_angular, MAX_ANGULAR, "rad/s")):
            if value is None:
                continue
            if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
                out.append(f"the {name} must be a number, not {value!r}")
            elif not 0 < value <= top:
                out.append(f"the {name} must be more than 0 and at most {top:g} {units}, not {_fmt(value)}")
        return out

    @property
    def limited(self) -> bool:
        """Whether it limits anything (an envelope of two Nones only refuses non-numbers)."""
        return self.max_linear is not None or self.max_angular is not None

    def to_dict(self) -> dict[str, float]:
        """The saved form: only the limits that are set."""
        out: dict[str, float] = {}
        if self.max_linear is not None:
            out["max_linear"] = float(self.max_linear)
        if self.max_angular is not None:
            out["max_angular"] = float(self.max_angular)
        return out

    @classmethod
    def from_dict(cls, data: Any) -> Envelope:
        """An envelope from its saved form; ValueError with a sentence for anything else."""
        if not isinstance(data, dict):
            raise ValueError(f"the safety envelope must be an object with max_linear and max_angular, not {data!r}")
        unknown = sorted(set(data) - {"max_linear", "max_angular"})
        if unknown:
            raise ValueError(f"the safety envelope has unknown keys {', '.join(unknown)} "
                             "(known: max_linear, max_angular)")
        env = cls(data.get("max_linear"), data.get("max_angular"))
        problems = env.problems()
        if problems:
            raise ValueError("safety envelope: " + "; ".join(problems))
        return cls(*(None if v is None else float(v) for v in (env.max_linear, env.max_angular)))

    def limit(self, part: str) -> float | None:
        """The limit of ``"linear"`` or ``"angular"``."""
        return self.max_linear if part == "linear" else self.max_angular if part == "angular" else None

    def limit_for(self, type_name: str, path: str) -> float | None:
        """The limit on the field at ``path`` of a ``type_name`` message (``linear.x`` of a Twist:
        ``max_linear``); None when the envelope does not hold that field."""
        where = motion_path(type_name, path)
        return None if where is None else self.limit(where[0])

    def describe(self) -> str:
        """The envelope in words: ``at most 1 m/s and 0.5 rad/s``."""
        parts = []
        if self.max_linear is not None:
            parts.append(f"{_fmt(self.max_linear)} m/s")
        if self.max_angular is not None:
            parts.append(f"{_fmt(self.max_angular)} rad/s")
        return "at most " + " and ".join(parts) if parts else "no speed limit"

    # -- applying ----------------------------------------------------------------------------------------
    def judge(self, type_name: str, msg: Any) -> Verdict:
        """What this envelope makes of ``msg`` of type ``type_name`` (see the module docstring)."""
        if not is_command(type_name) or not isinstance(msg, dict):
            return Verdict(msg)
        base = COMMAND_TYPES[pkg_type(type_name)]
        twist = msg.get(base) if base else msg
        prefix = f"{base}." if base else ""
        if base and base not in msg:
            return Verdict(msg)
        if not isinstance(twist, dict):
            return Verdict(None, refused=f"not sent: {base} is not a twist ({_bounded(twist)})")
        out: dict[str, Any] | None = None
        clamped: list[tuple[str, float, float]] = []
        for part in ("linear", "angular"):
            if part not in twist:
                continue
            vector = twist[part]
            if not isinstance(vector, dict):
                return Verdict(None, refused=f"not sent: {prefix}{part} is not a vector ({_bounded(vector)})")
            limit = self.limit(part)
            for axis, value in vector.items():
                path = f"{prefix}{part}.{axis}"
                kind = type(value)
                if kind is not float and kind is not int and (  # the common case first: the ABC check is slow
                        isinstance(value, bool) or not isinstance(value, numbers.Real)):  # numpy scalars are Real
                    what = "null (NaN or infinity)" if value is None else _bounded(value)
                    return Verdict(None, refused=f"not sent: {path} is {what}, not a number")
                number = float(value)
                if not math.isfinite(number):
                    return Verdict(None, refused=f"not sent: {path} is {number}, not a finite number")
                if limit is not None and abs(number) > limit:
                    sent = math.copysign(float(limit), number)
                    if out is None:
                        out = _copy_twist(msg, base)
                    (out[base] if base else out)[part][axis] = sent
                    clamped.append((path, number, sent))
        return Verdict(msg if out is None else out, tuple(clamped))

    def apply(self, type_name: str, msg: dict[str, Any]) -> dict[str, Any]:
        """The message to send: ``msg`` itself, or a clamped copy. Raises :class:`EnvelopeRefused`."""
        verdict = self.judge(type_name, msg)
        if verdict.msg is None:
            raise EnvelopeRefused(verdict.refused)
        return verdict.msg


#: what holds when a robot has no envelope: no limits, but non-numbers are still refused
NO_LIMITS = Envelope()


def _copy_twist(msg: dict[str, Any], base: str) -> dict[str, Any]:
    """A copy of ``msg`` whose twist and its two vectors are fresh dicts (the rest is shared, unchanged)."""
    out = dict(msg)
    twist = dict(out[base]) if base else out
    for part in ("linear", "angular"):
        if isinstance(twist.get(part), dict):
            twist[part] = dict(twist[part])
    if base:
        out[base] = twist
    return out


def _bounded(value: Any) -> str:
    text = repr(value) if isinstance(value, str | int | float | bool) else type(value).__name__
    return text if len(text) <= 40 else text[:37] + "..."


def enforce(envelope: Envelope | None, type_name: str, msg: dict[str, Any], stats: BridgeStats) -> dict[str, Any]:
    """The bridge's hook (``Session.publish``): the message to send, clamped to ``envelope``
    (:data:`NO_LIMITS` when None); raises :class:`EnvelopeRefused`. Counts into ``stats``."""
    if not is_command(type_name):
        return msg
    verdict = (envelope or NO_LIMITS).judge(type_name, msg)
    if verdict.msg is None:
        stats.envelope_refused += 1
        raise EnvelopeRefused(verdict.refused)
    if verdict.clamped:
        stats.envelope_clamped += 1
    return verdict.msg
