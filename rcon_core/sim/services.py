"""The service half of the sim's rosbridge ops: calls into the graph and services clients provide.

``call_service`` runs a handler of the graph (the robot's, rosapi's) or forwards the request to the client
that advertised the service, and answers with ``service_response``; ``advertise_service``,
``unadvertise_service`` and ``service_response`` let a client provide a service. :meth:`ServiceOps.call`
is also what the server's own code (and tests) use to call a service of the graph.

Every call is answered, never silently dropped (the old send queue dropped answers beyond 800 queued: of
10,000 calls from one client, 5,700 to 7,000 got nothing). Answers are never dropped from a connection's
queue; a client with :data:`~rcon_core.sim.connection.REPLY_BACKLOG` answers unread is not read until it
reads them (``connection.py``). A call that cannot be served is answered at once with ``result: false``
and a text saying why, as rosbridge answers a call that fails: the client already has
:data:`MAX_CALLS_IN_FLIGHT` calls unanswered, or the client providing the service has half of
``REPLY_BACKLOG`` requests and answers unread in its queue (it does not keep up).
"""

from __future__ import annotations

import asyncio
import inspect
import logging
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from .connection import REPLY_BACKLOG
from .convert import ConversionError
from .encoding import bounded
from .graph import BRIDGE_NODE, Service, ServiceFailure
from .ops import OpError, field, send_frame

if TYPE_CHECKING:
    from .connection import Connection
    from .server import SimServer

log = logging.getLogger("rcon.sim")

#: calls of one client being served at once; more are answered with an error at once
MAX_CALLS_IN_FLIGHT = 1000


class ServiceOps:
    """The service ops of one :class:`~rcon_core.sim.server.SimServer` (its ``services`` table)."""

    def __init__(self, server: SimServer) -> None:
        self.server = server

    def ops(self) -> dict[str, Callable[[Connection, dict[str, Any]], Any]]:
        """The op handlers, by op name."""
        return {"call_service": self.op_call_service, "advertise_service": self.op_advertise_service,
                "unadvertise_service": self.op_unadvertise_service, "service_response": self.op_service_response}

    def connection_closed(self, conn: Connection) -> None:
        """The services ``conn`` provided are gone; calls waiting for them fail."""
        for svc in [s for s in self.server.services.values() if s.provider is conn]:
            self.remove_client_service(svc, "the providing client disconnected")

    def op_call_service(self, conn: Connection, msg: dict[str, Any]) -> None:
        service = field(msg, "service", str)
        if conn.calls_in_flight >= MAX_CALLS_IN_FLIGHT:
            self._answer(conn, msg, service, False, f"too many calls in flight on this connection "
                         f"({conn.calls_in_flight}); call again when some are answered")
            return
        conn.calls_in_flight += 1
        self.server.spawn(self._call_service(conn, msg, service))

    async def _call_service(self, conn: Connection, msg: dict[str, Any], service: str) -> None:
        name = service
        if "#" in service and "id" not in msg:
            name = service.split("#", 1)[0]
        try:
            ok, values = await self.call(name, msg.get("args"))
        except Exception as exc:  # noqa: BLE001 - answered, never silence
            ok, values = False, f"service [{name}] could not be called: {type(exc).__name__}: {exc}"[:500]
        finally:
            conn.calls_in_flight -= 1
        self._answer(conn, msg, service, ok, values)

    @staticmethod
    def _answer(conn: Connection, msg: dict[str, Any], service: str, ok: bool, values: Any) -> None:
        call_id = msg.get("id")
        has_id = "id" in msg
        if "#" in service and not has_id:
            call_id = service.split("#", 1)[1]
            has_id = True
        frame: dict[str, Any] = {"op": "service_response", "service": service, "values": values, "result": ok}
        if has_id:
            frame["id"] = call_id
        send_frame(conn, frame)

    async def call(self, name: str, args: Any = None) -> tuple[bool, Any]:
        """Call a service of the graph: ``(True, values)`` or ``(False, error text)``."""
        svc = self.server.services.get(name)
        if svc is None:
            return False, f"Service {name} does not exist"
        request = self.server.types.converter(svc.type, "request")
        if request is not None:
            try:
                args = request.from_args(args)
            except ConversionError as exc:
                return False, str(exc)
        elif args is None:
            args = {}
        try:
            if svc.provider is not None:
                values = await self._call_client_service(svc, args)
            else:
                assert svc.handler is not None
                result = svc.handler(args)
                values = await result if inspect.isawaitable(result) else result
        except ServiceFailure as exc:
            return False, f"service [{name}] responded with an error: b'{exc}'"
        except Exception as exc:  # noqa: BLE001 - a handler bug is reported like a ROS handler exception
            log.error("service %s failed: %s: %s", name, type(exc).__name__, bounded(str(exc)))
            return False, f"service [{name}] responded with an error: b'error processing request: {exc}'"
        response = self.server.types.converter(svc.type, "response")
        if response is not None and isinstance(values, dict):
            try:
                values = response.convert(values)
            except ConversionError as exc:
                return False, f"service [{name}] responded with an error: b'error processing request: {exc}'"
        return True, values

    async def _call_client_service(self, svc: Service, args: dict[str, Any]) -> dict[str, Any]:
        assert svc.provider is not None and self.server.loop is not None
        if svc.provider.replies_queued >= REPLY_BACKLOG // 2:
            raise ServiceFailure(f"service cannot process request: the client providing it has "
                                 f"{svc.provider.replies_queued} requests unread")
        svc.counter += 1
        request_id = f"service_request:{svc.name}:{svc.counter}"
        future: asyncio.Future[dict[str, Any]] = self.server.loop.create_future()
        svc.pending[request_id] = future
        send_frame(svc.provider, {"op": "call_service", "id": request_id, "service": svc.name, "args": args})
        try:
            return await future
        finally:
            svc.pending.pop(request_id, None)

    def op_advertise_service(self, conn: Connection, msg: dict[str, Any]) -> None:
        name = field(msg, "service", str)
        type_name = field(msg, "type", str)
        old = self.server.services.get(name)
        if old is not None:
            if old.provider is None:
                raise OpError(f"Service {name} is already provided by {old.node}")
            self.remove_client_service(old, "the service was advertised again")
        self.server.services[name] = Service(name, self.server.flavour.wire(type_name, "srv"), BRIDGE_NODE, provider=conn)
        log.info("%s Advertised service %s.", conn.label, name)

    def op_unadvertise_service(self, conn: Connection, msg: dict[str, Any]) -> None:
        name = field(msg, "service", str)
        svc = self.server.services.get(name)
        if svc is None or svc.provider is None:
            raise OpError(f"Service {name} has not been advertised via rosbridge, can't unadvertise.")
        self.remove_client_service(svc, "service handler returned None")
        log.warning("%s Service %s was unadvertised", conn.label, name)

    def remove_client_service(self, svc: Service, reason: str) -> None:
        if self.server.services.get(svc.name) is svc:
            del self.server.services[svc.name]
        for future in list(svc.pending.values()):
            if not future.done():
                future.set_exception(ServiceFailure(f"service cannot process request: {reason}"))
        svc.pending.clear()

    def op_service_response(self, conn: Connection, msg: dict[str, Any]) -> None:
        name = field(msg, "service", str)
        svc = self.server.services.get(name)
        if svc is None or svc.provider is not conn:
            raise OpError(f"Service {name} has not been advertised via rosbridge.")
        values = msg.get("values", {})
        if not isinstance(values, dict):
            raise OpError(f"Expected field values to be one of (<class 'dict'>,). Invalid value: {values}")
        future = svc.pending.get(msg.get("id"))  # type: ignore[arg-type]
        if future is None:
            raise OpError(f"no pending request with id {msg.get('id')!r} for {name}")
        if not future.done():
            future.set_result(values)
