"""Compound: child widgets, each bound to one field of a single message, service request or service
response, of any type (also types learned from the robot's typedefs).

Roles and what the children do:

* PUBLISH: every child is an input; their values are set into one message (the type's default to
  start with) and :meth:`CompoundModel.send` publishes it (or every change, with ``auto_send``).
  E.g. sliders on ``linear_acceleration.x``/``angular_velocity.z`` and a text field on ``orientation``
  composing one ``sensor_msgs/Imu``.
* CALL: children on ``request.*`` are inputs composing the request; children on ``response.*`` show
  the answer. :meth:`send` calls the service.
* SERVE: the compound answers the service. Children on ``response.*`` compose the response; children
  on ``request.*`` show the last request.

Child composition lives in the model: ``settings.children`` is a list of (kind, field_path, settings).

Children from other packages. A child is an ordinary widget model, built by the runtime's context
(``context.build_child(kind, binding, port=..., parent=self)``) exactly as the app builds any widget, so the
runtime tells it focus loss and link state and the app its preview flag, but given a *child port*: an input
child is
bound with role PUBLISH to the compound's (part) type and its field path, and what it publishes through
the port is captured, not sent: the compound takes the value at the child's path out of it. A display
child is bound with role SUBSCRIBE and receives the response (CALL) or request (SERVE) through the
callback it subscribed with. So any widget whose model publishes through its port (``publish`` /
``publish_value``) provides a value and can be a child, whichever package it comes from; its kind is
found in the context's catalog (the app's plugin manager) like any widget. A child's state changes wake the
front end through its port like any widget's (the compound's ``seq`` moves, its view repaints the children
whose own ``seq`` moved): no clock of the compound's own.

What the Compound sends is what its children show, decided. Just before sending, the compound asks every
input child that defines ``shown_message()`` (loop thread) for a message of the child's bound type holding
the value the child shows: the Slider and Stepper their shown number (also before they were touched), the
Text Field the operator's typed text, parsed. A child that cannot say (text unsent-and-invalid, or
nothing typed) raises ``ValueError`` (``MessageTextError`` is one) with the problem: the send is blocked
and the status names the child (``not published: child 2 (Text Field) on angular: angular.z: expected a
number, got 'fast'``); no type default is ever sent in a child's place. A child whose ``shown_message``
is the base class's (None) gives what it last published through its port. A child can tell it is inside a
compound from its port's ``composes`` (True on :class:`ChildPort`): nothing it publishes reaches the robot
until the compound sends, so it should say what *will* be sent, not what was.

The settings' checks need the other installed kinds (each child's own settings): :class:`CompoundSettings`
is a ``CatalogSettings``, so the app passes its catalog in (``problems(catalog)``); without one it knows
this package's own kinds only and claims nothing about others.
"""

from __future__ import annotations

import copy
import time
from typing import Any

import attrs

from rcon_core.msgs import MessageTextError
from rcon_core.plugins import (
    ActionGoal,
    Binding,
    CallPhase,
    CatalogSettings,
    Role,
    WidgetCatalog,
    WidgetModel,
    WidgetSpec,
    settings_commands,
)
from rcon_core.plugins.children import child_name, child_problems, child_role, role_problem
from rcon_core.plugins.paths import PathError, get_path, parse_path, set_path, split_service_path

from .base import StdModel
from .button import CallStatus, describe_response
from .common import RateLimiter, copy_message, field_at, held_to_envelope

__all__ = ["ChildSpec", "CompoundSettings", "CompoundModel", "Child", "CompoundValue", "find_spec"]


@attrs.define
class ChildSpec:
    """One child: its widget kind, the field it is bound to, its own settings (a stored dict)."""

    kind: str
    field_path: str = ""
    settings: dict[str, Any] = attrs.field(factory=dict)
    title: str = ""


@attrs.define
class CompoundSettings(CatalogSettings):
    #: a children field: the app's settings form edits it with its children editor (field, fitting
    #: widget, the child's own settings); stored as a list of {kind, field_path, settings, title}
    children: list[ChildSpec] = attrs.field(factory=list, metadata={
        "label": "Children", "exclude_kinds": ["std.compound"]})
    send_text: str = attrs.field(default="", metadata={"label": "Button text", "help": "default: Publish / Call"})
    auto_send: bool = attrs.field(default=False, metadata={
        "label": "Send on every change", "help": "publish (or call) whenever a child changes, rate-limited"})
    rate_hz: float = attrs.field(default=5.0, metadata={"label": "Update rate (Hz)", "min": 0.1, "max": 50.0})
    columns: int = attrs.field(default=1, metadata={"label": "Columns", "min": 1, "max": 6})

    def problems(self, catalog: WidgetCatalog | None = None) -> list[str]:
        out = []
        if not self.children:
            out.append("add at least one child widget")
        for i, c in enumerate(self.children, 1):
            if not c.kind:
                out.append(f"child {i}: no widget kind")
            if c.kind == "std.compound":
                out.append(f"child {i}: a compound cannot contain a compound")
            try:
                parse_path(c.field_path)
            except PathError as exc:
                out.append(f"child {i}: {exc}")
            if c.kind and c.kind != "std.compound":
                out += _child_settings_problems(i, c, catalog)
        if not self.rate_hz > 0:
            out.append("update rate must be more than 0 Hz")
        if not 1 <= self.columns <= 6:
            out.append("columns must be between 1 and 6")
        return out

    def commands(self, binding: Binding, catalog: WidgetCatalog | None = None) -> list[tuple[str, float]]:
        """What the input children may send, each at its path in the compound's message (a slider child on
        ``linear.x`` up to 5: ``("linear.x", 5.0)``): checked against the robot's safety envelope."""
        if binding.role is not Role.PUBLISH:
            return []
        out: list[tuple[str, float]] = []
        for c in self.children:
            spec = _spec_or_none(c.kind, catalog)
            if spec is None:
                continue
            try:
                settings = spec.make_settings(c.settings)
            except Exception:  # a child's bad settings are its own problem, said elsewhere
                continue
            out += settings_commands(settings, Binding(binding.name, binding.type, Role.PUBLISH, (c.field_path,)),
                                     catalog)
        return out

    def preferred_size(self, catalog: WidgetCatalog | None = None) -> tuple[float, float]:
        """The size (w, h) a new Compound with these children should be placed at, so that no child is
        squeezed: the children in ``columns`` columns, each as large as its own kind's default size (a
        box title above it), the button and the status line below. No Qt: computed from the children's
        specs, for the app to use instead of the kind's fixed ``default_size`` (the view's
        ``sizeHint()`` says the same once it is built)."""
        cols = max(1, min(6, int(self.columns)))
        sizes = []
        for c in self.children:
            spec = _spec_or_none(c.kind, catalog)
            w, h = spec.default_size if spec is not None else (160.0, 80.0)
            sizes.append((max(float(w), CHILD_MIN[0]) + CHILD_PAD, max(float(h), CHILD_MIN[1]) + CHILD_TITLE))
        if not sizes:
            return DEFAULT_SIZE
        rows = [sizes[i:i + cols] for i in range(0, len(sizes), cols)]
        width = max(sum(w for w, _ in row) + CHILD_GAP * (len(row) - 1) for row in rows)
        height = sum(max(h for _, h in row) for row in rows) + CHILD_GAP * (len(rows) - 1)
        return (max(DEFAULT_SIZE[0], _grid_up(width + CHROME[0])), max(DEFAULT_SIZE[1], _grid_up(height + CHROME[1])))


def _grid_up(v: float, grid: int = 16) -> float:
    """``v`` rounded up to the canvas grid (the app snaps geometry to 16 px)."""
    return float(-(-int(v) // grid) * grid)


#: a new Compound's size without children, and what its frame and view add around the children: the
#: frame's title bar and margins, the view's margins, the Publish/Call button and the status line
DEFAULT_SIZE = (320.0, 360.0)
CHROME = (64.0, 150.0)
#: each child's box: its title above the child and its side margins, the gap between boxes, the least
#: a child gets
CHILD_TITLE = 28.0
CHILD_PAD = 40.0
CHILD_GAP = 6.0
CHILD_MIN = (160.0, 96.0)


def _spec_or_none(kind: str, catalog: WidgetCatalog | None) -> WidgetSpec | None:
    try:
        return find_spec(kind, catalog)
    except KeyError:
        return None


def _child_settings_problems(number: int, child: ChildSpec, catalog: WidgetCatalog | None) -> list[str]:
    """The child's kind and own settings problems, the child named (``child 2 (Slider) on linear.x: …``).
    Without a catalog, a kind of another package cannot be judged: nothing is claimed about it."""
    spec = _spec_or_none(child.kind, catalog)
    if spec is None and catalog is None:
        return []
    return [f"{child_name(number, child, spec)}: {p}" for p in child_problems(child, spec)]


def find_spec(kind: str, catalog: WidgetCatalog | None = None) -> WidgetSpec:
    """The spec of a child kind where no model's context is at hand (settings checks, sizes): from
    ``catalog`` (the app's plugin manager: a disabled plugin's kind is unknown there), or, without one, this
    package's own kinds only. A model asks its context instead (:meth:`CompoundModel.find_spec`). Raises
    KeyError (UnknownWidget) when nobody offers it."""
    if catalog is not None:
        return catalog.widget(kind)
    from .plugin import specs

    for spec in specs():
        if spec.kind == kind:
            return spec
    raise KeyError(f"{kind!r} is not a standard widget (no catalog to look further)")


@attrs.frozen
class CompoundValue:
    message: dict[str, Any]  #: the composed message; for services ``{"request": ..., "response": ...}``
    status: CallStatus | None = None  #: the last call (CALL) or the last request answered (SERVE)
    served: int = 0


class Child:
    """A built child: its spec, model and where it sits."""

    def __init__(self, index: int, spec: WidgetSpec, model: WidgetModel, cfg: ChildSpec, is_input: bool,
                 part: str) -> None:
        self.index = index
        self.spec = spec
        self.model = model
        self.cfg = cfg
        self.is_input = is_input
        self.part = part  #: "" for topics, "request"/"response" for services
        self.feed: Any = None  #: the display child's subscription callback

    @property
    def title(self) -> str:
        return self.cfg.title or self.cfg.field_path or "(whole message)"


class _Captured:
    """The publisher a child gets: what it publishes goes to the compound."""

    def __init__(self, compound: CompoundModel, index: int) -> None:
        self.compound, self.index = compound, index

    def publish(self, msg: dict[str, Any]) -> bool:
        self.compound.child_published(self.index, msg)
        return True

    def unadvertise(self) -> None:
        pass


class _Feed:
    def __init__(self, child: Child) -> None:
        self.child = child

    def unsubscribe(self) -> None:
        self.child.feed = None


class ChildPort:
    """The port a child model gets (see the module docstring): a complete ``Port``. Service calls go to the
    real robot; what the child publishes is composed; its changes wake the front end through the compound."""

    #: what a child publishes goes into the compound's message, not to the robot (until the compound sends)
    composes = True

    def __init__(self, compound: CompoundModel, child: Child | None = None, number: int = 0) -> None:
        self.compound = compound
        self.child = child
        self.number = number  #: the child's number (from 1)

    @property
    def envelope(self) -> Any:
        """The robot's safety envelope, as the compound's own port tells it (a child's range follows it)."""
        return self.compound.port.envelope

    @property
    def view_only(self) -> str | None:
        """The compound's: a child of a view-only compound sends nothing either."""
        return self.compound.port.view_only

    @property
    def link(self) -> Any:
        return self.compound.port.link

    @property
    def widget_id(self) -> str | None:
        """The compound's id and the child's number (``w-3#2``): the same across rebuilds."""
        wid = self.compound.port.widget_id
        return f"{wid}#{self.number}" if wid is not None else None

    def changed(self) -> None:
        """The child has something new to show: the compound's view repaints it (the compound's ``seq``
        moves, its port wakes the front end like any widget's)."""
        self.compound.touch()

    def send_action_goal(self, action: str, action_type: str, args: Any = None, feedback: Any = None,
                         **options: Any) -> ActionGoal:
        raise RuntimeError("a child widget cannot send action goals; bind an Action widget on its own")

    def advertise(self, topic: str, type: str, **options: Any) -> _Captured:
        assert self.child is not None
        return _Captured(self.compound, self.child.index)

    def subscribe(self, topic: str, callback: Any, **options: Any) -> _Feed:
        assert self.child is not None
        self.child.feed = callback
        return _Feed(self.child)

    def call_service(self, name: str, args: Any = None, timeout: float | None = None) -> Any:
        return self.compound.port.call_service(name, args, timeout=timeout)

    def advertise_service(self, name: str, type: str, handler: Any) -> Any:
        raise RuntimeError("a child widget cannot serve a service; bind the compound with role serve")

    def close(self) -> None:
        pass


class CompoundModel(StdModel):
    stale_after = None

    def __init__(self, settings: CompoundSettings | None, *args: Any, **kwargs: Any) -> None:
        super().__init__(settings if settings is not None else CompoundSettings(), *args, **kwargs)
        self.children: list[Child] = []
        #: bumps when children are (re)built, so the view rebuilds its child views
        self.children_version = 0
        self._composed: dict[str, Any] = {}
        self._build_problems: list[str] = []
        self._served = 0
        self._status: CallStatus | None = None
        self._limiter = RateLimiter(lambda _v: self._send_now(), self.settings.rate_hz, clock=self._clock)

    # -- building ------------------------------------------------------------------------------------
    @property
    def is_service(self) -> bool:
        return self.binding.role.is_service

    def _part_type(self, part: str) -> str:
        return self.types.service_part_name(self.binding.type, part) if part else self.types.resolve(self.binding.type)

    def default_message(self) -> dict[str, Any]:
        if self.is_service:
            return {p: self.types.default(self._part_type(p)) for p in ("request", "response")}
        return self.types.default(self.binding.type)

    def _split(self, path: str) -> tuple[str, str]:
        if self.is_service:
            return split_service_path(path)
        return "", path

    def find_spec(self, kind: str) -> WidgetSpec:
        """A child kind's spec through the runtime's context: a kind of a disabled plugin is unknown here
        (KeyError), as it is everywhere in the app."""
        return self.context.spec(kind)

    def _child_role(self, part: str) -> Role:
        return child_role(self.binding.role, part)

    def on_types_ready(self) -> None:
        self.build_children()
        for child in self.children:
            try:
                child.model.start()
            except Exception as exc:
                self._build_problems.append(f"child {child.index + 1} ({child.cfg.kind}): {exc}")
        self._show_state()

    def build_children(self) -> None:
        """Build every child's model (loop thread, once the type is known)."""
        self._stop_children()
        self._composed = self.default_message()
        built: list[Child] = []
        problems: list[str] = []
        for i, cfg in enumerate(self.settings.children):
            try:
                built.append(self._build_child(i, cfg))
            except Exception as exc:
                problems.append(f"child {i + 1} ({cfg.kind or '?'}): {exc}")
        self.children = built
        self._build_problems = problems
        self.children_version += 1

    def _build_child(self, index: int, cfg: ChildSpec) -> Child:
        spec = self.find_spec(cfg.kind)
        part, rest = self._split(cfg.field_path)
        role = self._child_role(part)
        if role not in spec.roles:
            raise ValueError(f"{role_problem(spec, role)} (it offers {', '.join(sorted(spec.roles))})")
        field_at(self.types, self._part_type(part), rest)  # PathError naming the missing part
        binding = Binding(f"{self.binding.name}#{index + 1}", self._part_type(part), role, (rest,) if rest else ())
        port = ChildPort(self, number=index + 1)
        model = self.context.build_child(cfg.kind, binding, port=port, parent=self, settings=cfg.settings)
        child = Child(index, spec, model, cfg, role is Role.PUBLISH, part)
        port.child = child
        return child

    def _stop_children(self) -> None:
        for child in self.children:
            try:
                child.model.stop()
            except Exception as exc:  # a child that fails to stop must not keep the others running
                self.set_error(f"child {child.index + 1}: {exc}")
        self.context.drop_children()

    def on_stop(self) -> None:
        self._limiter.cancel()
        self._stop_children()

    def problems(self) -> list[str]:
        out = super().problems()
        if self.binding.problems() or out:
            return out
        if not self.children and self.types_ready:
            try:  # not started yet: check what building would say, without starting anything
                for i, cfg in enumerate(self.settings.children):
                    try:
                        try:  # through the context: a disabled plugin's kind is unknown here
                            spec: WidgetSpec | None = self.find_spec(cfg.kind)
                        except KeyError:
                            spec = None
                        part, rest = self._split(cfg.field_path)
                        field_at(self.types, self._part_type(part), rest)
                        out += [f"child {i + 1} ({cfg.kind}): {p}"
                                for p in child_problems(cfg, spec, self._child_role(part))]
                    except Exception as exc:
                        out.append(f"child {i + 1} ({cfg.kind or '?'}): {exc}")
            except Exception as exc:
                out.append(str(exc))
            return out
        out += self._build_problems
        for child in self.children:
            out += [f"child {child.index + 1} ({child.cfg.kind}): {p}" for p in child.model.problems()]
        return out

    # -- composing -----------------------------------------------------------------------------------
    def child_published(self, index: int, msg: dict[str, Any]) -> None:
        """What input child ``index`` published through its port: its value goes into the composed message."""
        child = self.children[index]
        path = child.cfg.field_path
        _part, rest = self._split(path)
        try:
            value = get_path(msg, rest) if rest else msg
            with self._lock:
                if path:
                    set_path(self._composed, path, copy.deepcopy(value))
                else:
                    self._composed = copy.deepcopy(value)
        except PathError as exc:
            self.set_error(f"child {index + 1}: {exc}")
            return
        self._show_state()
        if self.settings.auto_send and self.binding.role is not Role.SERVE:
            self._limiter.offer(None)

    def composed(self) -> dict[str, Any]:
        """A copy of the composed message (services: ``{"request", "response"}``)."""
        with self._lock:
            return copy_message(self._composed)

    def _show_state(self) -> None:
        """Set the value the views show (composed message, status); sends nothing (:meth:`send` does).
        One copy serves as both (the state is read, never changed)."""
        composed = self.composed()
        self.set_value(CompoundValue(composed, self._status, self._served), message=composed)

    # -- sending -------------------------------------------------------------------------------------
    def send(self) -> None:
        """Publish the composed message, or call the service with the composed request (any thread)."""
        self._dispatch(self._send_now)

    def _take_shown(self) -> list[str]:
        """Set what each input child shows into the composed message (see the module docstring); the
        problems of the children that cannot say, each child named. Loop thread."""
        problems: list[str] = []
        for child in self.children:
            if not child.is_input:
                continue
            path = child.cfg.field_path
            _part, rest = self._split(path)
            try:
                msg = child.model.shown_message()
                if msg is None:
                    continue
                value = copy.deepcopy(get_path(msg, rest) if rest else msg)
            except (ValueError, PathError) as exc:
                problems.append(f"{self.child_name(child)}: {exc}")
                continue
            except Exception as exc:  # a child package's bug blocks this send only, named
                problems.append(f"{self.child_name(child)}: {type(exc).__name__}: {exc}")
                continue
            with self._lock:
                if path:
                    set_path(self._composed, path, value)
                else:
                    self._composed = value
        return problems

    def child_name(self, child: Child) -> str:
        """``child 2 (Text Field) on angular``: how problems name a child."""
        return child_name(child.index + 1, child.cfg, child.spec)

    def _send_now(self) -> None:
        role = self.binding.role
        if not self.types_ready:
            self.set_error(f"the type {self.binding.type} is not known yet")
            return
        if role is not Role.SERVE:
            blocked = self._take_shown()
            if blocked:
                verb = "published" if role is Role.PUBLISH else "called"
                self.set_error(f"not {verb}: " + "; ".join(blocked))
                return
        if role is Role.PUBLISH:
            msg, note = held_to_envelope(self.port, self.binding.type, self.composed())
            if msg is None:  # NaN or infinity in a motion command: never sent
                self.set_error(note)
                return
            if self.publish(msg):
                self._status = CallStatus(CallPhase.OK, self.binding.name, f"published, {note}" if note else "published",
                                          time.time(), 0.0)
                self._show_state()
        elif role is Role.CALL:
            self._status = CallStatus(CallPhase.BUSY, self.binding.name, "", time.time())
            self._show_state()
            self.spawn(self._call(self.composed()["request"]))
        else:
            self.set_error("a serving compound answers requests; it does not send")

    async def _call(self, request: dict[str, Any]) -> None:
        t0 = self._clock()
        started = self._status.started if self._status else time.time()
        try:
            response = await self.port.call_service(self.binding.name, request, timeout=self.call_timeout)
        except Exception as exc:
            self._status = CallStatus(CallPhase.FAILED, self.binding.name, str(exc), started, self._clock() - t0)
            self._show_state()
            self.set_error(f"{self.binding.name}: {exc}")
            return
        ok = not (isinstance(response, dict) and response.get("success") is False)
        text = describe_response(response) if ok else str(response.get("message") or "success: false")
        self._status = CallStatus(CallPhase.OK if ok else CallPhase.FAILED, self.binding.name, text, started, self._clock() - t0)
        with self._lock:
            self._composed["response"] = copy.deepcopy(response)
        self._feed_display("response", response)
        self._show_state()
        if not ok:
            self.set_error(f"{self.binding.name}: {text}")

    def _feed_display(self, part: str, msg: dict[str, Any]) -> None:
        """One copy of ``msg`` for every display child (they share it, as the consumers of one topic share
        a message), not one per child."""
        shared = None
        for child in self.children:
            if not child.is_input and child.part == part and child.feed is not None:
                if shared is None:
                    shared = copy_message(msg)
                child.feed(shared)

    # -- serving -------------------------------------------------------------------------------------
    def handle_request(self, request: dict[str, Any]) -> dict[str, Any]:
        """Answer with the response the children show; display children show the request. A child that
        cannot say what it shows fails the call (ValueError), the child named."""
        self._feed_display("request", request)
        blocked = self._take_shown()
        if blocked:  # the caller gets a failed call, never a default in a child's place
            problem = "; ".join(blocked)
            self._status = CallStatus(CallPhase.FAILED, self.binding.name, f"not answered: {problem}", time.time(), 0.0)
            self._show_state()
            self.set_error(f"not answered: {problem}")
            raise ValueError(problem)
        with self._lock:
            self._composed["request"] = copy_message(request)
            response = copy.deepcopy(self._composed.get("response", {}))
            self._served += 1
        try:
            response = self.types.complete(self._part_type("response"), response)
        except MessageTextError as exc:
            self.set_error(f"response: {exc}")
        self._status = CallStatus(CallPhase.OK, self.binding.name, f"answered request {self._served}", time.time(), 0.0)
        self._show_state()
        return response
