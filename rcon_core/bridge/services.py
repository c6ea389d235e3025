"""Services this client provides (``node.advertise_service``): the session's table and the answers.

Decision: a failed handler is answered with an object
    A handler that raises or returns a non-dict is logged and answered with ``result: false`` and an
    *object*: the response type's default message (from the registry, else the server's
    ``/rosapi/service_response_details``, cached; ``{}`` when neither knows it), the error text in its
    ``message`` string field when it has one.  rosbridge 0.11 ignores ``result`` and rejects a
    non-object ``values``, which would leave the ROS caller waiting forever (``client_service.jsonl:7``), so the
    error string alone would never reach anybody.  A call for a service this client does not provide is
    answered with ``{}`` for the same reason.
"""

from __future__ import annotations

import copy
import inspect
import logging
from collections.abc import Awaitable, Callable
from typing import Any

from rcon_core.msgs import names

from .defaults import Default, default_from_typedefs, default_of
from .errors import BridgeError
from .nodes import ServiceServer

log = logging.getLogger(__name__)

def _error_values(default: Default, text: str) -> dict[str, Any]:
    """A copy of a default response with ``text`` in its ``message`` string field when it has one."""
    values = copy.deepcopy(default[0])
    if "message" in default[1]:
        values["message"] = text
    return values


class ProvidedServices:
    """Advertised services: frames out through ``send``, the server's ``call_service`` frames in."""

    def __init__(self, send: Callable[[dict[str, Any]], bool], spawn: Callable[[Awaitable[Any]], Any],
                 host: Any) -> None:
        self._send = send
        self._spawn = spawn
        self._host = host  # registry, rosapi, call_timeout (see session.Host)
        self.servers: dict[str, ServiceServer] = {}
        self._defaults: dict[str, Default] = {}

    def add(self, srv: ServiceServer) -> None:
        if srv.service in self.servers:
            other = self.servers[srv.service]
            raise BridgeError(f"service {srv.service} is already advertised by node {other.node.id}")
        self.servers[srv.service] = srv
        self._send(self._advertise_op(srv))

    def remove(self, srv: ServiceServer) -> None:
        if self.servers.get(srv.service) is srv:
            del self.servers[srv.service]
            self._send({"op": "unadvertise_service", "service": srv.service})

    def restore(self) -> None:
        """Advertise every service again on a fresh connection."""
        for srv in self.servers.values():
            self._send(self._advertise_op(srv))

    @staticmethod
    def _advertise_op(srv: ServiceServer) -> dict[str, Any]:
        return {"op": "advertise_service", "service": srv.service, "type": srv.type}

    # -- frames from the server -------------------------------------------------------------------

    def on_call(self, m: dict[str, Any]) -> None:
        name = m["service"]
        if not isinstance(name, str):
            raise TypeError(f"'service' must be a string, got {type(name).__name__}")
        srv = self.servers.get(name)
        if srv is None:
            log.warning("server called %s, which this client does not provide; answered with an empty message",
                        name)
            self._respond(m, {}, False)  # an object, so the ROS caller is answered rather than left waiting
            return
        args = m.get("args")
        if args is None:
            args = {}
        srv.calls += 1
        try:
            result = srv.handler(args)
        except Exception as exc:
            self._handler_failed(m, srv, exc)
            return
        if inspect.isawaitable(result):
            self._spawn(self._finish_call(m, srv, result))
        else:
            self._answer(m, srv, result)

    async def _finish_call(self, m: dict[str, Any], srv: ServiceServer, pending: Awaitable[Any]) -> None:
        try:
            result = await pending
        except Exception as exc:
            self._handler_failed(m, srv, exc)
            return
        self._answer(m, srv, result)

    def _answer(self, m: dict[str, Any], srv: ServiceServer, result: Any) -> None:
        if result is None:
            result = {}
        if not isinstance(result, dict):
            self._handler_failed(m, srv, TypeError(f"handler returned {type(result).__name__}, expected a dict"))
            return
        self._respond(m, result, True)

    def _handler_failed(self, m: dict[str, Any], srv: ServiceServer, exc: BaseException) -> None:
        srv.failures += 1
        text = f"{type(exc).__name__}: {exc}"
        log.error("handler of %s (node %s) failed: %s", srv.service, srv.node.id, text, exc_info=exc)
        cached = self._defaults.get(names.pkg_type(srv.type))
        if cached is not None:
            self._respond(m, _error_values(cached, text), False)
        else:
            self._spawn(self._answer_failure(m, srv, text))

    async def _answer_failure(self, m: dict[str, Any], srv: ServiceServer, text: str) -> None:
        self._respond(m, _error_values(await self.response_default(srv.type), text), False)

    async def response_default(self, srv_type: str) -> Default:
        """The default response of a service type and its string field names: from the registry when it
        knows the type, else from ``/rosapi/service_response_details`` (cached), else ``({}, set())``."""
        key = names.pkg_type(srv_type)
        cached = self._defaults.get(key)
        if cached is not None:
            return cached
        found: Default | None = None
        reg = self._host.registry
        if reg is not None and hasattr(reg, "has_service"):
            try:
                if reg.has_service(srv_type):
                    found = default_of(reg, reg.service_part_name(srv_type, "response"))
            except Exception as exc:
                log.debug("registry has no default response for %s: %s", srv_type, exc)
        if found is None:
            host = self._host
            try:
                typedefs = await host.rosapi.service_response_details(srv_type, timeout=min(host.call_timeout, 2.0))
            except BridgeError as exc:
                log.warning("cannot learn the response type of %s (%s); answering the failed call with {}",
                            srv_type, exc)
                return {}, set()
            found = default_from_typedefs(typedefs)
        self._defaults[key] = found
        return found

    def _respond(self, m: dict[str, Any], values: Any, result: bool) -> None:
        resp: dict[str, Any] = {"op": "service_response", "service": m.get("service"), "values": values,
                                "result": result}
        if "id" in m:
            resp["id"] = m["id"]
        self._send(resp)

