"""A real Foxglove WebSocket server for tests: the ``foxglove-sdk`` package's server (the same core as
``foxglove_bridge``) on a free loopback port, with its own SDK context (channels of one peer never leak
into another's).  The fixtures ``fox`` (a :class:`FoxPeer`) and ``fox_client`` (a connected
``FoxgloveClient``) are loaded by the root conftest, as ``rcon_core.testing``'s are.

Channels: ``/chatter`` (jsonschema/json), ``/rosout_str`` (ros2msg/cdr ``std_msgs/msg/String``),
``/pose`` (ros2msg/cdr ``geometry_msgs/msg/Pose``), ``/camera/compressed`` and ``/gps`` (protobuf, Foxglove's
own ``foxglove.CompressedImage``/``foxglove.LocationFix``).  Services: ``/reset`` (ros2msg/cdr
``std_srvs/srv/Trigger``), ``/add`` (json), ``/fail`` (a handler that raises), ``/slow`` (answers once ``peer.release`` is set).  Parameters: ``/boat.max_speed``
(float), ``/boat.name`` (string), ``/boat.enabled`` (bool).  Capabilities: clientPublish, parameters,
services, connectionGraph, time.  What clients publish is kept in ``peer.received`` (topic, bytes).
"""

from __future__ import annotations

import threading
from typing import Any

import foxglove
import orjson
import pytest
from foxglove import Channel, Schema
from foxglove.websocket import (
    Capability,
    ConnectionGraph,
    MessageSchema,
    Parameter,
    Service,
    ServiceSchema,
)

from rcon_core.msgs import TypeRegistry

REG = TypeRegistry.standard(ros2=True)
TRIGGER_REQ = ""
TRIGGER_RES = "bool success\nstring message\n"


class Listener:
    def __init__(self, peer: FoxPeer) -> None:
        self.peer = peer

    def on_subscribe(self, client: Any, channel: Any) -> None:
        with self.peer.lock:
            self.peer.subscribed.add(channel.topic)
            self.peer.subscribers[channel.topic] = self.peer.subscribers.get(channel.topic, 0) + 1

    def on_unsubscribe(self, client: Any, channel: Any) -> None:
        with self.peer.lock:
            self.peer.subscribed.discard(channel.topic)
            self.peer.subscribers[channel.topic] = self.peer.subscribers.get(channel.topic, 1) - 1

    def on_client_advertise(self, client: Any, channel: Any) -> None:
        with self.peer.lock:
            self.peer.client_channels[channel.id] = channel
            self.peer.advertised.append((channel.topic, channel.encoding, channel.schema_name))

    def on_client_unadvertise(self, client: Any, channel_id: int) -> None:
        with self.peer.lock:
            ch = self.peer.client_channels.pop(channel_id, None)
            if ch is not None:
                self.peer.unadvertised.append(ch.topic)

    def on_message_data(self, client: Any, channel_id: int, data: bytes) -> None:
        with self.peer.lock:
            ch = self.peer.client_channels.get(channel_id)
            self.peer.received.append((ch.topic if ch else "?", ch.encoding if ch else "?", bytes(data)))

    def on_get_parameters(self, client: Any, names: list[str], request_id: str | None = None) -> list[Any]:
        with self.peer.lock:
            return [p for n, p in self.peer.params.items() if not names or n in names]

    def on_set_parameters(self, client: Any, params: list[Any], request_id: str | None = None) -> list[Any]:
        with self.peer.lock:
            for p in params:
                if p.name in self.peer.params and p.name not in self.peer.read_only:
                    self.peer.params[p.name] = p
            out = list(self.peer.params.values())
        return out

    def on_parameters_subscribe(self, names: list[str]) -> None:
        self.peer.param_subscribed.update(names)

    def on_parameters_unsubscribe(self, names: list[str]) -> None:
        self.peer.param_subscribed.difference_update(names)

    def on_connection_graph_subscribe(self) -> None:
        self.peer.graph_subscribed = True

    def on_connection_graph_unsubscribe(self) -> None:
        self.peer.graph_subscribed = False

    def on_playback_control_request(self, request: Any) -> None:
        return None


class FoxPeer:
    """One foxglove-sdk server (see the module docstring); ``stop()`` ends it."""

    def __init__(self, port: int = 0, name: str = "fox-peer", tls: tuple[bytes, bytes] | None = None) -> None:
        self.lock = threading.Lock()
        self.received: list[tuple[str, str, bytes]] = []
        self.advertised: list[tuple[str, str, str]] = []
        self.unadvertised: list[str] = []
        self.client_channels: dict[int, Any] = {}
        self.subscribed: set[str] = set()
        self.subscribers: dict[str, int] = {}  # topic -> how many clients subscribe to it now
        self.param_subscribed: set[str] = set()
        self.graph_subscribed = False
        self.read_only = {"/boat.name"}
        self.calls: list[tuple[str, bytes]] = []
        self.release = threading.Event()  # ``/slow`` answers once this is set
        self.params = {"/boat.max_speed": Parameter("/boat.max_speed", value=2.5),
                       "/boat.name": Parameter("/boat.name", value="kingfisher"),
                       "/boat.enabled": Parameter("/boat.enabled", value=True)}
        self.ctx = foxglove.Context()
        trigger = ServiceSchema("std_srvs/srv/Trigger",
                                request=MessageSchema(encoding="cdr", schema=Schema(
                                    name="std_srvs/srv/Trigger_Request", encoding="ros2msg", data=TRIGGER_REQ.encode())),
                                response=MessageSchema(encoding="cdr", schema=Schema(
                                    name="std_srvs/srv/Trigger_Response", encoding="ros2msg",
                                    data=TRIGGER_RES.encode())))
        add = ServiceSchema("example/Add", request=MessageSchema(encoding="json", schema=Schema(
            name="AddRequest", encoding="jsonschema", data=b'{"type":"object"}')))
        services = [Service("/reset", schema=trigger, handler=self._reset),
                    Service("/add", schema=add, handler=self._add),
                    Service("/fail", schema=add, handler=self._fail),
                    Service("/slow", schema=add, handler=self._slow)]
        kwargs: dict[str, Any] = {}
        if tls is not None:
            kwargs.update(tls_cert=tls[0], tls_key=tls[1])
        self.server = foxglove.start_server(
            name=name, host="127.0.0.1", port=port, context=self.ctx, server_listener=Listener(self),
            capabilities=[Capability.ClientPublish, Capability.Parameters, Capability.Services,
                          Capability.ConnectionGraph, Capability.Time],
            supported_encodings=["cdr", "json"], services=services, **kwargs)
        self.port = self.server.port
        self.url = f"{'wss' if tls else 'ws'}://127.0.0.1:{self.port}"
        self.chatter = Channel("/chatter", schema={"type": "object", "properties": {"data": {"type": "string"}}},
                               context=self.ctx)
        self.text = Channel("/rosout_str", message_encoding="cdr", context=self.ctx, schema=Schema(
            name="std_msgs/msg/String", encoding="ros2msg", data=b"string data\n"))
        pose_text = REG.definition_text("geometry_msgs/msg/Pose", dependencies=True)
        self.pose = Channel("/pose", message_encoding="cdr", context=self.ctx, schema=Schema(
            name="geometry_msgs/msg/Pose", encoding="ros2msg", data=pose_text.encode()))
        from foxglove.channels import CompressedImageChannel, LocationFixChannel

        self.image = CompressedImageChannel("/camera/compressed", context=self.ctx)
        self.gps = LocationFixChannel("/gps", context=self.ctx)
        graph = ConnectionGraph()
        graph.set_published_topic("/chatter", ["/talker"])
        graph.set_published_topic("/pose", ["/boat"])
        graph.set_subscribed_topic("/cmd_vel", ["/boat"])
        graph.set_advertised_service("/reset", ["/boat"])
        self.server.publish_connection_graph(graph)

    # ------------------------------------------------------------------ services
    def _reset(self, req: Any) -> bytes:
        self.calls.append(("/reset", bytes(req.payload)))
        return REG.serialize_cdr("std_srvs/srv/Trigger_Response", {"success": True, "message": "reset done"})

    def _add(self, req: Any) -> bytes:
        self.calls.append(("/add", bytes(req.payload)))
        args = orjson.loads(req.payload)
        return orjson.dumps({"sum": args["a"] + args["b"]})

    def _slow(self, req: Any) -> bytes:
        self.calls.append(("/slow", bytes(req.payload)))
        self.release.wait(10)
        return b"{}"

    def _fail(self, req: Any) -> bytes:
        raise RuntimeError("the pump is jammed")

    # ------------------------------------------------------------------ data
    def say(self, text: str) -> None:
        self.chatter.log({"data": text})

    def log_string(self, text: str) -> None:
        self.text.log(REG.serialize_cdr("std_msgs/msg/String", {"data": text}))

    def log_pose(self, x: float) -> None:
        self.pose.log(REG.serialize_cdr("geometry_msgs/msg/Pose", REG.complete("geometry_msgs/msg/Pose", {
            "position": {"x": x, "y": 2.0, "z": 0.0}})))

    def log_image(self, data: bytes) -> None:
        from foxglove.messages import CompressedImage

        self.image.log(CompressedImage(format="jpeg", data=data, frame_id="cam"))

    def log_fix(self, lat: float, lon: float) -> None:
        from foxglove.messages import LocationFix

        self.gps.log(LocationFix(latitude=lat, longitude=lon, altitude=1.0))

    def start_talking(self, period: float = 0.05) -> None:
        """Log on every channel every ``period`` s from a thread (a live robot), until :meth:`stop`."""
        import cv2
        import numpy as np

        frame = np.zeros((48, 64, 3), np.uint8)
        frame[:, :32] = (0, 0, 255)
        jpeg = cv2.imencode(".jpg", frame)[1].tobytes()
        self._talking = threading.Event()

        def talk() -> None:
            n = 0
            while not self._talking.wait(period):
                n += 1
                self.say(f"hello {n}")
                self.log_string(f"string {n}")
                self.log_pose(float(n))
                self.log_image(jpeg)
                self.log_fix(57.70 + n * 1e-6, 11.97)

        self._talker = threading.Thread(target=talk, daemon=True)
        self._talker.start()

    def set_param(self, name: str, value: Any) -> None:
        with self.lock:
            self.params[name] = Parameter(name, value=value)
            p = self.params[name]
        self.server.publish_parameter_values([p])

    def stop(self) -> None:
        talking = getattr(self, "_talking", None)
        if talking is not None:
            talking.set()
            self._talker.join()
        self.server.stop()


# ------------------------------------------------------------------------------ fixtures


@pytest.fixture
def fox():
    peer = FoxPeer()
    yield peer
    peer.stop()


@pytest.fixture
async def fox_client(fox):
    from rcon_core.foxglove import FoxgloveClient

    client = FoxgloveClient(fox.url, backoff_min=0.05, backoff_max=0.3, call_timeout=5)
    await client.connect(timeout=10)
    yield client
    await client.close()
