"""``Requests``: what a Foxglove client asks the server and the answers it waits for -- service calls,
parameter reads and writes -- and the parameters it watches.  Part of the session (``session.requests``),
pure as the session is: frames out through the session's ``send``, answers in from its frame handlers,
each answer given to the ``done`` callback of its request (the async shell, ``client.py``, turns those into
futures and timeouts).

Decision: requests belong to the connection, watches do not
    A service call or a parameter request waiting when the link drops is answered at once with
    ``ConnectionLostError`` / forgotten (:meth:`Requests.detached`); a late answer to a call that timed out
    is dropped.  Parameter watches are kept across reconnects and subscribed again once ``serverInfo``
    says the server can (:meth:`Requests.restore`), as subscriptions are.

Decision: answers
    A ``serviceCallFailure`` answers its call with ``ServiceError`` carrying the server's text; a response
    is decoded with the service's response schema (raw bytes and their encoding when RCON has no decoder
    for it), and one that does not decode answers with ``ServiceError`` saying so.  A ``parameterValues``
    frame updates the values known (``params``), tells each watcher of its parameters, and answers the
    request whose id it carries.
"""

from __future__ import annotations

import itertools
import logging
from collections.abc import Callable
from typing import Any, Protocol

from rcon_core.bridge.errors import BridgeError, ConnectionLostError, ServiceError
from rcon_core.bridge.safety import bounded_repr, safe_text

from . import wire
from .codecs import Codecs, Decode
from .entries import Service
from .guard import FoxgloveGuard

log = logging.getLogger(__name__)

Done = Callable[[Any, BaseException | None], None]
ParamsDone = Callable[[list[dict[str, Any]]], None]


class Server(Protocol):
    """What the requests read of the session: the server's offer and the link's guard and codecs."""

    guard: FoxgloveGuard
    codecs: Codecs
    server: dict[str, Any] | None
    service_by_name: dict[str, Service]

    @property
    def capabilities(self) -> list[str]: ...

    @property
    def encodings(self) -> list[str]: ...


class Requests:
    """Service calls, parameter requests and parameter watches of one Foxglove client (see the module
    docstring)."""

    def __init__(self, server: Server, send: Callable[[str, str, str | bytes], bool],
                 notify: Callable[[str], None]) -> None:
        self.server = server
        self._send = send  # the session's: admitted by the guard, False while there is no connection
        self._notify = notify
        #: call id -> (service, ``done(values, error)``, the response decoder)
        self.calls: dict[int, tuple[Service, Done, Decode | None]] = {}
        #: request id -> ``done(parameters)``
        self.param_requests: dict[str, ParamsDone] = {}
        #: parameter name -> ``fn(name, value)`` (kept across reconnects)
        self.param_watch: dict[str, list[Callable[[str, Any], None]]] = {}
        self.params: dict[str, Any] = {}  # the latest value of each parameter the server told
        self._call_ids = itertools.count(1)
        self._req_ids = itertools.count(1)

    # ================================================================== the connection comes and goes

    def restore(self) -> None:
        """``serverInfo`` came: watch again the parameters watched before."""
        if self.param_watch and "parametersSubscribe" in self.server.capabilities:
            self._send("subscribeParameterUpdates", "", wire.subscribe_parameters_frame(sorted(self.param_watch)))

    def detached(self) -> None:
        """The connection is gone: the calls waiting fail, the parameter requests are forgotten."""
        calls = list(self.calls.values())
        self.calls.clear()
        self.param_requests.clear()
        for _srv, done, _decode in calls:
            done(None, ConnectionLostError("connection lost before the answer arrived"))

    # ================================================================== service calls

    def start_call(self, name: str, args: Any, done: Done) -> int:
        """Write one service call request; ``done(values, error)`` is called with the answer.  Raises
        ``BridgeError`` for a service the server does not advertise or whose encoding RCON cannot write."""
        server = self.server
        srv = server.service_by_name.get(name)
        if srv is None:
            raise BridgeError(f"the robot advertises no service {name} (Foxglove link)")
        server.guard.check(f"the call to {name}")
        encodings = server.encodings
        encoding, encode, _ = server.codecs.request_codec(srv.request, encodings[0] if encodings else "", "Request")
        _, _, decode = server.codecs.request_codec(srv.response, encoding, "Response")
        if encode is None:
            raise BridgeError(f"{name}: RCON cannot write {encoding!r} service requests")
        cid = next(self._call_ids)
        payload = encode(args if isinstance(args, dict) else {})
        self.calls[cid] = (srv, done, decode)
        if not self._send("call_service", name, wire.call_frame(srv.id, cid, encoding, payload)):
            del self.calls[cid]
            raise BridgeError(f"the call to {name} was not sent (no connection)")
        return cid

    def forget_call(self, cid: int) -> None:
        self.calls.pop(cid, None)

    def on_call_failure(self, m: dict[str, Any]) -> None:
        cid = m.get("callId")
        pending = self.calls.pop(cid, None) if isinstance(cid, int) else None
        if pending is None:
            return
        text = m.get("message")
        pending[1](None, ServiceError(text if isinstance(text, str) else bounded_repr(text, 200), pending[0].name))

    def on_response(self, cid: int, encoding: str, payload: Any) -> None:
        pending = self.calls.pop(cid, None)
        if pending is None:
            return  # a late answer to a call that timed out
        srv, done, answer = pending
        try:
            values = answer(payload) if answer is not None else {"raw": payload, "encoding": encoding}
        except Exception as exc:
            done(None, ServiceError(f"cannot read the answer ({safe_text(exc)})", srv.name))
            return
        done(values, None)

    # ================================================================== parameters

    def request_params(self, names: list[str], done: ParamsDone) -> str:
        rid = f"get:{next(self._req_ids)}"
        self.param_requests[rid] = done
        if not self._send("getParameters", "", wire.get_parameters_frame(names, rid)):
            del self.param_requests[rid]
            raise BridgeError("parameters were not asked for (no connection)")
        return rid

    def set_params(self, params: list[dict[str, Any]], done: ParamsDone) -> str:
        name = ", ".join(p["name"] for p in params)
        self.server.guard.check(f"setting parameter {name}")
        rid = f"set:{next(self._req_ids)}"
        self.param_requests[rid] = done
        if not self._send("setParameters", name, wire.set_parameters_frame(params, rid)):
            del self.param_requests[rid]
            raise BridgeError(f"setting parameter {name} was not sent (no connection)")
        return rid

    def watch_params(self, names: list[str], fn: Callable[[str, Any], None]) -> Callable[[], None]:
        """``fn(name, value)`` on each update of these parameters (kept across reconnects)."""
        new = [n for n in names if n not in self.param_watch]
        for n in names:
            self.param_watch.setdefault(n, []).append(fn)
        if new and self.server.server is not None and "parametersSubscribe" in self.server.capabilities:
            self._send("subscribeParameterUpdates", "", wire.subscribe_parameters_frame(new))

        def stop() -> None:
            gone = []
            for n in names:
                fns = self.param_watch.get(n, [])
                if fn in fns:
                    fns.remove(fn)
                if not fns and n in self.param_watch:
                    del self.param_watch[n]
                    gone.append(n)
            if gone:
                self._send("unsubscribeParameterUpdates", "", wire.subscribe_parameters_frame(gone, False))
        return stop

    def on_parameter_values(self, m: dict[str, Any]) -> None:
        params = [p for p in wire.items(m, "parameters") if isinstance(p, dict) and isinstance(p.get("name"), str)]
        for p in params:
            self.params[p["name"]] = p.get("value")
            for fn in list(self.param_watch.get(p["name"], [])):
                try:
                    fn(p["name"], p.get("value"))
                except Exception:
                    log.exception("parameter watcher raised")
        rid = m.get("id")
        done = self.param_requests.pop(rid, None) if isinstance(rid, str) else None
        if done is not None:
            done(params)
        self._notify("params")
