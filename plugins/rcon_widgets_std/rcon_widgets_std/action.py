"""Action: sends a goal to a ROS 2 action server, shows its live feedback and how it ended; Cancel.

The goal form is generated from the goal type (:meth:`ActionModel.goal_fields`: one entry per leaf field,
a message's own scalars before nested ones, arrays last, ``header`` fields left out: the server fills them); what the operator types is checked against the definition
with ``TypeRegistry.from_text`` before anything is sent, and a bad entry names its field.

Every entry starts empty: a pre-filled ``0.0`` in a latitude is a real place (0°N 0°E) one tap away. An
empty entry sends its default -- the settings' ``goal`` value for it, else nothing (the server's default) --
which the view shows as the entry's placeholder. *Required* entries (``settings.required``; ``auto``: the
coordinates of the place a goal names -- numeric ``latitude``, ``longitude``, ``x``, ``y`` at the top of the
form -- unless the settings' goal gives them a value) have no default: the view marks them and keeps Send
disabled until they are filled (:meth:`ActionModel.missing`), and :meth:`ActionModel.build_goal` refuses an
empty one.

What the view paints is ``state.value``, an :class:`ActionStatus`:

* ``phase``: ``idle``, ``active`` (sent, running), ``canceling``, then one of the final phases:
  ``succeeded``, ``canceled``, ``aborted`` (the server's GoalStatus 4/5/6), ``failed`` (the goal could not
  be run: no action server, args the server refused, a ROS 1 robot) or ``unknown``: the link dropped while
  the goal ran, so its fate is unknown -- never reported as a success; or nothing at all came back (no
  feedback, no result: "no answer from the action server (rejected?)", since rosbridge 2.1.0 answers a
  rejected goal with silence; ``rcon_core/bridge/goals.py``).
* ``feedback``: the last feedback message; ``numbers``: its numeric leaves (``distance_remaining``);
  ``progress``: 0..1 when a feedback field looks like progress (``progress``, ``percent``, ``completion``:
  a fraction, or a percentage above 1) or a distance remaining (progress = 1 - remaining / first remaining).
* ``result``: the result message once the goal ended.
* ``problem``: why the operator's last Send went nowhere (a form entry that does not fit its field), kept
  while a goal runs on; cleared by the next goal sent or when the running goal ends (its end is then said).

A goal in flight when the widget stops (its canvas is switched away, the app closes, the widget is
removed) is cancelled -- a robot must not carry on driving while nobody watches it -- and the widget built
next for the same instance says so (``canceled``, "cancelled: the canvas was switched away").
"""

from __future__ import annotations

import json
import math
import threading
import time
from typing import Any

import attrs

from rcon_core.msgs import MessageTextError
from rcon_core.msgs.text import parse_text
from rcon_core.plugins import GoalPhase
from rcon_core.plugins.paths import PathError, get_path, set_path

from .base import StdModel

__all__ = ["ActionSettings", "ActionModel", "ActionStatus", "GoalField", "FINAL_PHASES", "progress_of"]

#: GoalStatus codes in ``action_result.status`` -> phase
STATUS_PHASE = {4: GoalPhase.SUCCEEDED, 5: GoalPhase.CANCELED, 6: GoalPhase.ABORTED}
FINAL_PHASES = frozenset(p for p in GoalPhase if p.final)
#: feedback field names (last path component) read as progress
PROGRESS_WORDS = ("progress", "percent", "percentage", "completion", "complete")
REMAINING_WORDS = ("distance_remaining", "remaining", "distance_left", "time_remaining")
#: what a stopped model leaves for the next model of the same widget instance (node id -> status)
_LEFT_BEHIND: dict[str, ActionStatus] = {}
_LEFT_LOCK = threading.Lock()


@attrs.define
class ActionSettings:
    goal: str = attrs.field(
        default="", metadata={"label": "Goal", "multiline": True,
                              "help": "YAML or JSON: the goal the form starts with (missing fields take their "
                                      "defaults), e.g. 'order: 5'"})
    progress_field: str = attrs.field(
        default="", metadata={"label": "Progress field",
                              "help": "feedback field shown as the progress bar (default: one named like "
                                      "progress, percent or distance_remaining)"})
    required: str = attrs.field(
        default="auto", metadata={"label": "Required fields",
                                  "help": "goal fields the operator must fill before Send, comma-separated "
                                          "(e.g. 'target.latitude, target.longitude'); auto: the coordinates "
                                          "a goal names (latitude, longitude, x, y); empty: none"})

    def problems(self) -> list[str]:
        try:
            parse_text(self.goal)
        except MessageTextError as exc:
            return [f"goal: {exc.problem}"]
        return []

    def required_paths(self) -> list[str] | None:
        """The paths listed in ``required`` (None for ``auto``)."""
        text = self.required.strip()
        if text == "auto":
            return None
        return [p.strip() for p in text.split(",") if p.strip()]


#: the names of the coordinates of a place a goal names: zero there is a real place (0°N 0°E, the origin)
PLACE_NAMES = frozenset({"latitude", "longitude", "lat", "lon", "x", "y"})
_NUMBERS = frozenset({"float32", "float64", "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64",
                      "uint64", "double", "float"})


@attrs.frozen
class GoalField:
    """One entry of the goal form: ``path`` below the goal (``target.latitude``), its ROS base type,
    whether it is an array, the text it starts with (always empty, but for a check box: its default),
    ``default`` (what an empty entry sends, as text, for the placeholder; "" when the server's default)
    and ``required`` (it must be filled before Send)."""

    path: str
    base: str
    is_array: bool
    text: str
    default: str = ""
    required: bool = False

    @property
    def is_bool(self) -> bool:
        return self.base == "bool" and not self.is_array


@attrs.frozen
class ActionStatus:
    phase: GoalPhase = attrs.field(converter=GoalPhase)
    text: str = ""
    feedback: Any = None
    feedback_count: int = 0
    numbers: tuple[tuple[str, float], ...] = ()
    progress: float | None = None
    progress_label: str = ""
    result: Any = None
    started: float = 0.0
    seconds: float | None = None
    problem: str = ""  #: why the operator's last Send went nowhere (kept until a goal is sent)

    @property
    def final(self) -> bool:
        return self.phase.final

    @property
    def running(self) -> bool:
        return self.phase.running


def _leaves(value: Any, prefix: str = "") -> list[tuple[str, Any]]:
    if isinstance(value, dict):
        out: list[tuple[str, Any]] = []
        for k, v in value.items():
            out += _leaves(v, f"{prefix}.{k}" if prefix else str(k))
        return out
    return [(prefix, value)]


def _number(v: Any) -> float | None:
    if isinstance(v, bool) or not isinstance(v, int | float):
        return None
    return float(v) if math.isfinite(v) else None


def progress_of(feedback: Any, field: str = "", first_remaining: float | None = None
                ) -> tuple[float | None, str, float | None]:
    """(progress 0..1 or None, the field it came from, the remaining value seen first) for a feedback.

    ``field``: the path to use (settings); otherwise the first numeric leaf named like progress/percent,
    else one named like a distance or time remaining (progress = 1 - remaining / first remaining)."""
    numeric = [(p, n) for p, v in _leaves(feedback) if (n := _number(v)) is not None and "header" not in p]
    last = {p: p.rsplit(".", 1)[-1].lower() for p, _ in numeric}
    chosen = [(p, n) for p, n in numeric if p == field] if field else []
    if not chosen:
        chosen = [(p, n) for p, n in numeric if any(w in last[p] for w in PROGRESS_WORDS)]
    if chosen:
        p, n = chosen[0]
        if not any(w in last[p] for w in REMAINING_WORDS):
            frac = n / 100.0 if n > 1.0 else n
            return max(0.0, min(1.0, frac)), p, first_remaining
    if not chosen:
        chosen = [(p, n) for p, n in numeric if any(w in last[p] for w in REMAINING_WORDS)]
    if not chosen:
        return None, "", first_remaining
    p, n = chosen[0]
    first = n if first_remaining is None else first_remaining
    if first <= 0:
        return (1.0 if n <= 0 else 0.0), p, first
    return max(0.0, min(1.0, 1.0 - n / first)), p, first


class ActionModel(StdModel):
    """Role ACTION: ``send(texts)`` / ``cancel()`` from any thread; ``state.value`` is an ActionStatus."""

    stale_after = None

    def __init__(self, settings: ActionSettings | None, *args: Any, **kwargs: Any) -> None:
        super().__init__(settings if settings is not None else ActionSettings(), *args, **kwargs)
        self._goal: Any = None
        self._first_remaining: float | None = None
        self._status = ActionStatus(GoalPhase.IDLE)
        widget_id = self.port.widget_id  # the instance's id, the same across rebuilds
        self._key = widget_id if isinstance(widget_id, str) else None
        with _LEFT_LOCK:
            left = _LEFT_BEHIND.pop(self._key, None) if isinstance(self._key, str) else None
        if left is not None:
            self._status = left
            self.replace_value(left)

    # -- types ------------------------------------------------------------------------------------
    def part_type(self, part: str) -> str:
        return self.types.action_part_name(self.binding.type, part)

    def type_known(self) -> bool:
        try:
            self.types.action_part_name(self.binding.type, "goal")
        except (KeyError, ValueError):
            return False
        return bool(self.binding.type)

    async def _learn(self) -> None:
        """Ask the robot for the goal, result and feedback typedefs: rosapi 2.x's
        ``/rosapi/action_{goal,result,feedback}_details`` (``message_details`` of a part answers nothing
        there: the package's module does not export the parts), else ``message_details``."""
        from rcon_core.msgs import names

        try:
            for part in ("goal", "result", "feedback"):
                name = names.part_name(self.binding.type, part)
                defs: list[Any] = []
                for service, what in ((f"/rosapi/action_{part}_details", self.binding.type),
                                      ("/rosapi/message_details", name)):
                    try:
                        answer = await self.port.call_service(service, {"type": what})
                    except Exception:  # an older rosapi without the service: try the next way
                        continue
                    defs = answer.get("typedefs", []) if isinstance(answer, dict) else []
                    if defs:
                        break
                if defs:
                    self.types.add_typedefs(defs, root=name)
        except Exception as exc:
            self.set_error(f"cannot learn the action type {self.binding.type} from the robot: {exc}")
            return
        if not self.type_known():
            self.set_error(f"the robot does not know the action type {self.binding.type}")
            return
        self._types_ready = True
        self.on_types_ready()

    # -- the goal form ----------------------------------------------------------------------------
    def goal_fields(self) -> list[GoalField]:
        """The goal form's entries (empty until the type is known). Any thread."""
        if not self.type_known():
            return []
        try:
            start = self.types.from_text(self.part_type("goal"), "{}")
            configured = parse_text(self.settings.goal or "{}")
        except (KeyError, ValueError):
            return []
        if not isinstance(configured, dict):
            configured = {}
        found: list[tuple[str, str, bool, Any]] = []

        def walk(type_name: str, prefix: str, value: dict[str, Any], depth: int) -> None:
            for f in self.types.fields(type_name):
                path = f"{prefix}.{f.name}" if prefix else f.name
                v = value.get(f.name) if isinstance(value, dict) else None
                if f.is_builtin or f.array_len is not None or depth > 4:
                    found.append((path, f.base, f.array_len is not None, v))
                elif f.name != "header" and f.name != "structure_needs_at_least_one_member":
                    walk(f.base, path, v if isinstance(v, dict) else {}, depth + 1)

        walk(self.part_type("goal"), "", start, 0)
        found = [g for g in found if g[0] != "structure_needs_at_least_one_member"]
        listed = self.settings.required_paths()
        top = min((p.count(".") for p, _b, arr, _v in found if not arr), default=0)
        out = []
        for path, base, is_array, type_default in found:
            given = _has_path(configured, path)
            default = get_path(configured, path) if given else None
            if listed is not None:
                required = path in listed
            else:  # auto: the coordinates of a place, where 0 is a real place, unless the settings set them
                required = (not given and not is_array and base in _NUMBERS and path.count(".") == top
                            and path.rsplit(".", 1)[-1] in PLACE_NAMES)
            is_bool = base == "bool" and not is_array
            shown = default if given else type_default
            out.append(GoalField(path, base, is_array, _text(shown) if is_bool else "",
                                 "" if required else _text(shown), required))
        # the message's own scalars first (a NavSatFix's latitude before its status.status), arrays last
        out.sort(key=lambda g: (g.is_array, g.path.count(".")))
        return out

    def missing(self, texts: dict[str, str]) -> list[str]:
        """The required entries left empty in ``texts`` (``{path: text}``): Send waits for them."""
        return [g.path for g in self.goal_fields() if g.required and not texts.get(g.path, "").strip()]

    def default_goal(self) -> dict[str, Any]:
        """The goal the form starts with: the settings' goal over the type's default."""
        return self.types.from_text(self.part_type("goal"), self.settings.goal or "{}")

    def build_goal(self, texts: dict[str, str]) -> dict[str, Any]:
        """The goal from the form's texts (``{path: text}``), checked against the goal type: the typed
        entries, and for an empty one its default from the settings' ``goal`` (else it is left out: the
        server's default). A required entry left empty is refused.

        Raises ``MessageTextError`` naming the field (``target.latitude: expected a number, got 'x'``)."""
        goal: dict[str, Any] = {}
        fields = {g.path: g for g in self.goal_fields()}
        try:
            configured = parse_text(self.settings.goal or "{}")
        except MessageTextError:
            configured = {}
        if not isinstance(configured, dict):
            configured = {}
        for path, text in texts.items():
            field = fields.get(path)
            if field is not None and field.base in ("string", "wstring") and not field.is_array:
                value: Any = text
            elif not text.strip():
                if not _has_path(configured, path):
                    continue  # left empty: the server's default
                value = get_path(configured, path)
            else:
                try:  # YAML numbers as a person types them (1e5 too); an overflow to infinity is refused
                    value = parse_text(text)
                except MessageTextError as exc:
                    raise MessageTextError(path, exc.problem) from None
                if value == {}:
                    continue
            goal = set_path(goal, path, value)
        checked = self.types.from_text(self.part_type("goal"), json.dumps(goal, allow_nan=True))
        for path in self.missing(texts):  # after what was typed is checked: a typo is named first
            raise MessageTextError(path, "required: type a value (its default would be a real place)")
        # only the form's fields go out (checked and converted): the server fills in the rest, in its own
        # ROS version's shapes (a ROS 2 header has no seq)
        out: dict[str, Any] = {}
        for path in texts:
            if _has_path(goal, path):
                out = set_path(out, path, get_path(checked, path))
        return out

    # -- actions (any thread) ---------------------------------------------------------------------
    def send(self, texts: dict[str, str]) -> bool:
        """Send a goal from the form's texts (any thread). The texts are checked on the bridge thread (the
        GUI thread parses nothing): a bad one is named in ``state.error`` and nothing is sent. False when
        nothing can be sent at all (a preview, an incomplete binding)."""
        if self.dry_run:
            self.set_error("preview: nothing is sent to the robot")
            return False
        if self.binding.problems():
            self.set_error("; ".join(self.binding.problems()))
            return False
        texts = dict(texts)
        self._dispatch(lambda: self._check_and_send(texts))
        return True

    def _check_and_send(self, texts: dict[str, str]) -> None:
        try:
            goal = self.build_goal(texts)
        except (KeyError, ValueError) as exc:  # MessageTextError is a ValueError: it names the field
            # kept in the status, not as state.error: the next feedback would wipe that within 0.2 s
            self._show(attrs.evolve(self._status, problem=f"not sent: {exc}"))
            return
        self._send_now(goal)

    def cancel(self) -> None:
        self._dispatch(self._cancel_now)

    # -- loop thread ------------------------------------------------------------------------------
    def _show(self, status: ActionStatus) -> None:
        self._status = status
        self.set_value(status)

    def _send_now(self, goal: dict[str, Any]) -> None:
        if self._goal is not None and not self._goal.done:
            self._goal.cancel()  # one goal at a time from one widget
        self._first_remaining = None
        b = self.binding
        if self.state.link_down:  # a tap is the operator's intent now: never kept to reach the robot later
            self._show(ActionStatus(GoalPhase.FAILED, "not sent: the robot's link is down (a goal is not kept "
                                                      "to be sent when it comes back; send it again then)"))
            return
        try:
            handle = self.port.send_action_goal(b.name, b.type, goal, feedback=self._on_feedback)
        except Exception as exc:
            self._show(ActionStatus(GoalPhase.FAILED, f"not sent: {exc}"))
            return
        self._goal = handle
        self._show(ActionStatus(GoalPhase.ACTIVE, f"goal sent to {b.name}", started=time.monotonic()))
        self.spawn(self._wait(handle))

    def _cancel_now(self) -> None:
        goal = self._goal
        if goal is None or goal.done:
            return
        goal.cancel()
        self._show(attrs.evolve(self._status, phase=GoalPhase.CANCELING, text="cancel requested…"))

    def _on_feedback(self, values: Any) -> None:
        if self._goal is None:
            return
        progress, label, self._first_remaining = progress_of(values, self.settings.progress_field,
                                                             self._first_remaining)
        numeric = [(p, n) for p, v in _leaves(values) if (n := _number(v)) is not None and "header" not in p]
        top = [(p, n) for p, n in numeric if "." not in p]  # the feedback's own numbers before nested ones
        numbers = tuple(top or numeric)[:4]
        st = self._status
        self._show(attrs.evolve(st, feedback=values, feedback_count=st.feedback_count + 1, numbers=numbers,
                                progress=progress, progress_label=label))

    async def _wait(self, handle: Any) -> None:
        from rcon_core.bridge.errors import ActionNoAnswerError, ConnectionLostError

        try:
            result = await handle.result()
        except ConnectionLostError:
            self._end(handle, GoalPhase.UNKNOWN, "link lost while the goal ran: its fate is unknown "
                                         "(the robot may still be executing it)")
            return
        except ActionNoAnswerError as exc:
            self._end(handle, GoalPhase.UNKNOWN, exc.message)
            return
        except Exception as exc:
            self._end(handle, GoalPhase.FAILED, str(exc) or type(exc).__name__)
            return
        phase = STATUS_PHASE.get(handle.status, GoalPhase.UNKNOWN)
        text = "" if phase is not GoalPhase.UNKNOWN else f"ended with status {handle.status}: its fate is unknown"
        message = result.get("message") if isinstance(result, dict) else None
        if isinstance(message, str) and message and message.strip().lower().rstrip(".") not in (phase, "cancelled"):
            # the server's own words ("arrived within 1.9 m"), unless they only repeat the status
            text = f"{text}: {message}" if text else message
        self._end(handle, phase, text, result)

    def _end(self, handle: Any, phase: GoalPhase, text: str, result: Any = None) -> None:
        if handle is not self._goal:
            return
        st = self._status
        took = time.monotonic() - st.started if st.started else None
        self._show(attrs.evolve(st, phase=phase, text=text, result=result, seconds=took, problem="",
                                progress=1.0 if phase is GoalPhase.SUCCEEDED and st.progress is not None else st.progress))

    def on_stop(self) -> None:
        goal = self._goal
        if goal is not None and not goal.done:
            goal.cancel()
            left = attrs.evolve(self._status, phase=GoalPhase.CANCELED,
                                text="cancelled: the widget stopped (canvas switched away) while the goal ran")
            self._status = left
            if isinstance(self._key, str):
                with _LEFT_LOCK:
                    _LEFT_BEHIND[self._key] = left
            self.replace_value(left)
        self._goal = None


def _has_path(msg: dict[str, Any], path: str) -> bool:
    try:
        get_path(msg, path)
    except PathError:
        return False
    return True


def _text(value: Any) -> str:
    """A field's value as the form shows it (YAML flow style for lists)."""
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return value
    if isinstance(value, list | dict):
        return json.dumps(value)
    return str(value)
