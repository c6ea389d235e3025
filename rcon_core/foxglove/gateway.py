"""Serve a rosbridge robot over the Foxglove WebSocket protocol, through the ``foxglove-sdk`` server.

``rcon sim --protocol foxglove`` and ``rcon --demo --protocol foxglove`` run the embedded simulated vessel
on a loopback-only rosbridge port and put this gateway in front of it: Foxglove, Lichtblick or RCON's own
Foxglove link open the gateway's URL and see the same vessel.

Decision: one channel per topic, in the robot's own encoding
    Every topic the robot lists becomes a channel with the robot's ``.msg`` text as its schema
    (``ros1msg`` with ``ros1`` encoding for a ROS 1 robot, ``ros2msg`` with ``cdr`` for ROS 2), the types
    learned from rosapi.  A channel is subscribed on the robot (``cbor-raw``: the robot's own ROS 1 or CDR
    bytes) while a Foxglove client subscribes to it, and each payload is logged to the channel as it came
    (serialized by RCON only when the robot sent it decoded).  Topics the robot lists later are not added
    (the sim's topics are fixed).

Decision: a recording as the robot
    ``rcon sim --play FILE --protocol foxglove`` puts the gateway in front of the player's bare sim
    (``sim/playback.py``): its topics are the recording's, each message's bytes the recorded ones (the
    player sends them unchanged to ``cbor-raw`` subscribers), and ``clock`` makes the server ``time`` the
    recording's time at the player's position.  What clients publish reaches the player, which absorbs it.

Decision: the rest of the protocol
    Client channels (``clientPublish``) are advertised on the robot with their schema's type and each
    message decoded and published; services with a known type are offered (``services``) and each call is
    forwarded with the link's timeout; parameters (``parameters``) are the robot's (``client.params``);
    the connection graph is rosapi's publishers and subscribers, sent once at start; the server ``time``
    is broadcast every second.  Foxglove's SDK calls the listener on its own threads: every call to the
    robot is handed to the gateway's bridge thread and waited for there.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from typing import Any

from rcon_core.bridge import BridgeClient
from rcon_core.bridge.threaded import BridgeThread
from rcon_core.bridge.topics import RawPayload
from rcon_core.msgs import TypeRegistry, names

log = logging.getLogger(__name__)
CALL_TIMEOUT = 10.0


class _Listener:
    """foxglove-sdk's ServerListener: runs on the SDK's threads, hands everything to the bridge thread."""

    def __init__(self, gateway: FoxgloveGateway) -> None:
        self.gw = gateway

    def on_subscribe(self, client: Any, channel: Any) -> None:
        self.gw.thread.call(self.gw.subscribe, channel.topic)

    def on_unsubscribe(self, client: Any, channel: Any) -> None:
        self.gw.thread.call(self.gw.unsubscribe, channel.topic)

    def on_client_advertise(self, client: Any, channel: Any) -> None:
        self.gw.thread.call(self.gw.advertise, client.id, channel.id, channel.topic, channel.encoding,
                            channel.schema_name)

    def on_client_unadvertise(self, client: Any, channel_id: int) -> None:
        self.gw.thread.call(self.gw.unadvertise, client.id, channel_id)

    def on_message_data(self, client: Any, channel_id: int, data: bytes) -> None:
        self.gw.thread.call(self.gw.publish, client.id, channel_id, bytes(data))

    def on_get_parameters(self, client: Any, names_: list[str], request_id: str | None = None) -> list[Any]:
        return self.gw.get_parameters(names_)

    def on_set_parameters(self, client: Any, params: list[Any], request_id: str | None = None) -> list[Any]:
        return self.gw.set_parameters(params)

    def on_parameters_subscribe(self, names_: list[str]) -> None:
        pass

    def on_parameters_unsubscribe(self, names_: list[str]) -> None:
        pass

    def on_connection_graph_subscribe(self) -> None:
        pass

    def on_connection_graph_unsubscribe(self) -> None:
        pass

    def on_playback_control_request(self, request: Any) -> None:
        return None  # a live robot: no playback


class FoxgloveGateway:
    """A Foxglove server in front of the rosbridge robot at ``source_url`` (see the module docstring)."""

    def __init__(self, source_url: str, *, host: str = "127.0.0.1", port: int = 0, name: str = "rcon-sim",
                 tls: tuple[bytes, bytes] | None = None, clock: Callable[[], int] | None = None) -> None:
        self.source_url = source_url
        self.host, self.port, self.name, self.tls = host, port, name, tls
        #: the server ``time`` broadcast every second, in ns (default the wall clock; a recording being
        #: played: the recording's time at the player's position)
        self.clock = clock or time.time_ns
        self.thread = BridgeThread("rcon-foxglove-gateway")
        self.client: BridgeClient | None = None
        self.ros2 = False
        self.reg: TypeRegistry | None = None
        self.channels: dict[str, Any] = {}
        self.types: dict[str, str] = {}
        self.subs: dict[str, Any] = {}
        self.pubs: dict[tuple[int, int], tuple[Any, str]] = {}
        self.server: Any = None
        self._stop = threading.Event()
        self._ticker: threading.Thread | None = None

    @property
    def url(self) -> str:
        return f"{'wss' if self.tls else 'ws'}://{self.host}:{self.port}"

    @property
    def encoding(self) -> str:
        return "cdr" if self.ros2 else "ros1"

    # ------------------------------------------------------------------------------------ start and stop
    def start(self) -> FoxgloveGateway:
        self.thread.start()
        self.thread.run(self._connect()).result(30)
        self._serve()
        return self

    async def _connect(self) -> None:
        client = self.client = BridgeClient(self.source_url, call_timeout=CALL_TIMEOUT)
        await client.connect(timeout=20)
        self.ros2 = (await client.detect_ros()).version == 2
        self.reg = TypeRegistry.standard(ros2=self.ros2)
        self.node = client.node("foxglove-gateway")
        for topic, type_name in (await client.rosapi.topics()).items():
            if await self._learn(type_name):
                self.types[topic] = type_name
        self.services: dict[str, str] = {}
        for service, type_name in (await client.rosapi.services_with_types()).items():
            if type_name and not service.startswith("/rosapi") and self._knows_service(type_name):
                self.services[service] = type_name
        self.graph: dict[str, tuple[list[str], list[str]]] = {}
        for topic in self.types:
            try:
                self.graph[topic] = (await client.rosapi.publishers(topic), await client.rosapi.subscribers(topic))
            except Exception:  # a graph the robot cannot tell is left out
                continue

    async def _learn(self, type_name: str) -> bool:
        assert self.reg is not None and self.client is not None
        if self.reg.has(type_name):
            return True
        try:
            self.reg.add_typedefs(await self.client.rosapi.message_details(type_name))
        except Exception as exc:
            log.warning("gateway: %s left out: its type %s is unknown (%s)", type_name, type_name, exc)
            return False
        return self.reg.has(type_name)

    def _knows_service(self, type_name: str) -> bool:
        assert self.reg is not None
        try:
            return self.reg.has_service(type_name)
        except ValueError:
            return False

    def _schema(self, type_name: str) -> Any:
        import foxglove

        assert self.reg is not None
        text = self.reg.definition_text(type_name, dependencies=True)
        spelled = names.to_ros2(type_name) if self.ros2 else names.to_ros1(type_name)
        return foxglove.Schema(name=spelled, encoding="ros2msg" if self.ros2 else "ros1msg", data=text.encode())

    def _serve(self) -> None:
        import foxglove
        from foxglove.websocket import Capability, ConnectionGraph, MessageSchema, Service, ServiceSchema

        ctx = self.ctx = foxglove.Context()
        services = []
        assert self.reg is not None
        for service, type_name in sorted(self.services.items()):
            parts = {}
            for part in ("request", "response"):
                part_name = self.reg.service_part_name(type_name, part)
                parts[part] = MessageSchema(encoding=self.encoding, schema=self._schema(part_name))
            schema = ServiceSchema(names.to_ros2(type_name) if self.ros2 else names.to_ros1(type_name),
                                   request=parts["request"], response=parts["response"])
            services.append(Service(service, schema=schema, handler=self._handler(service, type_name)))
        kwargs: dict[str, Any] = {}
        if self.tls is not None:
            kwargs.update(tls_cert=self.tls[0], tls_key=self.tls[1])
        self.server = foxglove.start_server(
            name=self.name, host=self.host, port=self.port, context=ctx, server_listener=_Listener(self),
            capabilities=[Capability.ClientPublish, Capability.Services, Capability.Parameters,
                          Capability.ConnectionGraph, Capability.Time],
            supported_encodings=[self.encoding], services=services, **kwargs)
        self.port = self.server.port
        for topic, type_name in sorted(self.types.items()):
            self.channels[topic] = foxglove.Channel(topic, message_encoding=self.encoding,
                                                    schema=self._schema(type_name), context=ctx)
        graph = ConnectionGraph()
        for topic, (pubs, subs) in self.graph.items():
            if pubs:
                graph.set_published_topic(topic, pubs)
            if subs:
                graph.set_subscribed_topic(topic, subs)
        self.server.publish_connection_graph(graph)
        self._ticker = threading.Thread(target=self._tick, name="rcon-foxglove-time", daemon=True)
        self._ticker.start()

    def _tick(self) -> None:
        while not self._stop.wait(1.0):
            try:
                self.server.broadcast_time(self.clock())
            except Exception:  # stopped meanwhile
                return

    def stop(self) -> None:
        self._stop.set()
        if self.server is not None:
            self.server.stop()
        if self.client is not None:
            try:
                self.thread.run(self.client.close()).result(10)
            except Exception:
                log.debug("gateway: closing the robot link failed", exc_info=True)
        self.thread.stop()

    def __enter__(self) -> FoxgloveGateway:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    # ------------------------------------------------------------------------------------ on the bridge thread
    def _serialize(self, type_name: str, msg: dict[str, Any]) -> bytes:
        assert self.reg is not None
        full = self.reg.complete(type_name, msg)
        return self.reg.serialize_cdr(type_name, full) if self.ros2 else self.reg.serialize_ros1(type_name, full)

    def _deserialize(self, type_name: str, data: bytes) -> dict[str, Any]:
        assert self.reg is not None
        return self.reg.deserialize_cdr(type_name, data) if self.ros2 else self.reg.deserialize_ros1(type_name, data)

    def subscribe(self, topic: str) -> None:
        if topic in self.subs or topic not in self.types:
            return
        type_name, channel = self.types[topic], self.channels[topic]

        def forward(msg: Any) -> None:
            try:
                channel.log(msg.data if msg.__class__ is RawPayload else self._serialize(type_name, msg))
            except Exception as exc:  # one message that does not fit its type is dropped, in the log
                log.warning("gateway: a %s message on %s was not forwarded: %s", type_name, topic, exc)

        self.subs[topic] = self.node.subscribe(topic, forward, type=type_name, raw=True)

    def unsubscribe(self, topic: str) -> None:
        sub = self.subs.pop(topic, None)
        if sub is not None:
            sub.unsubscribe()

    def advertise(self, client_id: int, channel_id: int, topic: str, encoding: str, schema_name: str) -> None:
        if encoding != self.encoding or not schema_name:
            log.warning("gateway: client channel %s (%s, %s) refused: this robot takes %s", topic, encoding,
                        schema_name, self.encoding)
            return
        type_name = names.normalize(schema_name)
        self.pubs[(client_id, channel_id)] = (self.node.advertise(topic, names.to_ros2(type_name) if self.ros2
                                                                  else names.to_ros1(type_name)), type_name)

    def unadvertise(self, client_id: int, channel_id: int) -> None:
        found = self.pubs.pop((client_id, channel_id), None)
        if found is not None:
            found[0].unadvertise()

    def publish(self, client_id: int, channel_id: int, data: bytes) -> None:
        found = self.pubs.get((client_id, channel_id))
        if found is None:
            return
        pub, type_name = found
        try:
            pub.publish(self._deserialize(type_name, data))
        except Exception as exc:
            log.warning("gateway: a message on %s was not published: %s", pub.topic, exc)

    # ------------------------------------------------------------------------------------ SDK threads
    def _handler(self, service: str, type_name: str) -> Any:
        def handle(request: Any) -> bytes:
            assert self.reg is not None and self.client is not None
            req_type = self.reg.service_part_name(type_name, "request")
            res_type = self.reg.service_part_name(type_name, "response")
            args = self._deserialize(req_type, bytes(request.payload))
            values = self.thread.run(self.client.call_service(service, args)).result(CALL_TIMEOUT + 1)
            return self._serialize(res_type, values)
        return handle

    def get_parameters(self, wanted: list[str]) -> list[Any]:
        from foxglove.websocket import Parameter

        async def read() -> list[Any]:
            assert self.client is not None
            params = self.client.params
            chosen = wanted or await params.names()
            out = []
            for name in chosen:
                value = await params.get(name, default=None)
                if value is not None and not isinstance(value, dict):
                    out.append(Parameter(name, value=value))
            return out

        try:
            return self.thread.run(read()).result(CALL_TIMEOUT)
        except Exception as exc:
            log.warning("gateway: parameters not read: %s", exc)
            return []

    def set_parameters(self, params: list[Any]) -> list[Any]:
        async def write() -> None:
            assert self.client is not None
            for p in params:
                try:
                    await self.client.params.set(p.name, p.get_value(), verify=False)
                except Exception as exc:  # the robot's answer comes back as its value, unchanged
                    log.info("gateway: parameter %s not set: %s", p.name, exc)

        try:
            self.thread.run(write()).result(CALL_TIMEOUT)
        except Exception as exc:
            log.warning("gateway: parameters not set: %s", exc)
        return self.get_parameters([p.name for p in params])


