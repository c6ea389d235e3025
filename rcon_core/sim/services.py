"""The service half of the sim's rosbridge ops: calls into the graph and services clients provide.

``call_service`` runs a handler of the graph (the robot's, rosapi's) or forwards the request to the client
that advertised the service, and answers with ``service_response``; ``advertise_service``,
``unadvertise_service`` and ``service_response`` let a client provide a service. :meth:`ServiceOps.call`
is also what the server's own code (and tests) use to call a service of the graph.
"""

from __future__ import annotations

import asyncio
import inspect
import logging
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from .convert import ConversionError
from .graph import BRIDGE_NODE, Service, ServiceFailure
from .ops import OpError, field, send_frame

if TYPE_CHECKING:
    from .connection import Connection
    from .server import SimServer

log = logging.getLogger("rcon.sim")


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
        self.server.spawn(self._call_service(conn, msg, service))

    async def _call_service(self, conn: Connection, msg: dict[str, Any], service: str) -> None:
        call_id = msg.get("id")
        has_id = "id" in msg
        name = service
        if "#" in service and not has_id:
            name, call_id = service.split("#", 1)
            has_id = True
        ok, values = await self.call(name, msg.get("args"))
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
            log.exception("service %s failed", name)
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
