"""The Foxglove link against a real peer: the foxglove-sdk server (``rcon_core/foxglove/testing.py``, the server core of
foxglove_bridge) on a free loopback port.  Library level: detection, the catalogue with schemas, binary
message data in each encoding, client publish, services, parameters, the graph, status, time, reconnect,
what the protocol cannot do."""

from __future__ import annotations

import asyncio
import base64
import hashlib
import json
import ssl
import time

import pytest

from rcon_core.bridge import (
    ActionError,
    BridgeClient,
    BridgeError,
    ConnectionLostError,
    ConnectionState,
    NotConnectedError,
    ServiceError,
)
from rcon_core.bridge.errors import HandshakeError, LinkSettingsError
from rcon_core.bridge.params import ParamNotFoundError, ParamRejectedError
from rcon_core.foxglove import CANNOT, FoxgloveClient, NotFoxgloveError
from rcon_core.foxglove.testing import FoxPeer
from rcon_core.link import RobotLink, detect, open_client
from rcon_core.msgs import TypeRegistry
from rcon_core.testing import until

pytestmark = pytest.mark.usefixtures("transport")  # every test runs on each WebSocket transport

REG = TypeRegistry.standard(ros2=True)


async def test_the_server_picks_the_sdk_subprotocol_and_says_what_it_is(fox, fox_client):
    assert await detect(fox.url) == "foxglove"
    info = fox_client.describe()
    assert info["protocol"] == "foxglove" and info["subprotocol"] == "foxglove.sdk.v1"
    assert info["server"] == "fox-peer"
    assert {"clientPublish", "parameters", "services", "connectionGraph", "time"} <= set(info["capabilities"])
    assert info["encodings"] == ["cdr", "json"]
    assert isinstance(fox_client, RobotLink) and fox_client.state is ConnectionState.CONNECTED


async def test_the_link_runs_on_the_chosen_transport(fox, fox_client, transport):
    """``RCON_TRANSPORT`` (the ``transport`` fixture) picks the WebSocket library, as for the rosbridge link; the
    ``transport=`` parameter overrides it; the server's pick of subprotocol is read on either."""
    assert fox_client.transport == transport and fox_client.link.name == transport
    assert fox_client.link.subprotocol == "foxglove.sdk.v1"
    assert await detect(fox.url, transport=transport) == "foxglove"
    other = "websockets" if transport == "picows" else transport
    forced = FoxgloveClient(fox.url, reconnect=False, transport=other)
    await forced.connect(timeout=10)
    try:
        assert forced.link.name == other and forced.subprotocol == "foxglove.sdk.v1"
    finally:
        await forced.close()
    with pytest.raises(LinkSettingsError, match="unknown transport"):
        FoxgloveClient(fox.url, transport="carrier-pigeon")


async def test_on_picows_binary_frames_go_to_the_session_straight_from_the_parser(fox, fox_client, transport):
    """The Foxglove link's hot path on picows: its Receiver's own frame callback is the listener's
    ``on_ws_frame`` (``FoxgloveReceiver.frame_callback``), not the listener's generic step; the messages this
    file's other tests receive go that way."""
    if transport == "picows":
        listener = fox_client.link.listener
        assert listener.on_ws_frame is listener.hot
        assert getattr(listener.hot, "__qualname__", "").startswith("FoxgloveReceiver.frame_callback")
    else:
        assert not hasattr(fox_client.link, "listener")  # websockets: frames come through Receiver.message


def _raw_server(picked: bytes, then: bytes = b""):
    """A bare WebSocket server that answers the handshake picking ``picked`` and writes ``then`` (server
    frames) in the same write as the answer, then waits for the client to go."""
    async def answer(reader, writer):
        head = (await reader.readuntil(b"\r\n\r\n")).decode()
        key = next(line.split(":", 1)[1].strip() for line in head.split("\r\n")
                   if line.lower().startswith("sec-websocket-key:"))
        accept = base64.b64encode(hashlib.sha1((key + "258EAFA5-E914-47DA-95CA-C5AB0DC85B11").encode()).digest())
        writer.write(b"HTTP/1.1 101 Switching Protocols\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                     b"Sec-WebSocket-Accept: " + accept + b"\r\nSec-WebSocket-Protocol: " + picked + b"\r\n\r\n"
                     + then)
        await writer.drain()
        await reader.read()
        writer.close()

    return asyncio.start_server(answer, "127.0.0.1", 0)


async def test_a_subprotocol_that_was_not_offered_fails_the_handshake(transport):
    """A server that answers with a subprotocol RCON did not offer is refused (RFC 6455), on both transports."""
    server = await _raw_server(b"something.else")
    try:
        client = FoxgloveClient(f"ws://127.0.0.1:{server.sockets[0].getsockname()[1]}", reconnect=False)
        with pytest.raises(HandshakeError):
            await client.connect(timeout=10)
    finally:
        server.close()


async def test_server_info_in_the_same_read_as_the_handshake_answer_is_not_lost(transport):
    """picows hands over the frames that came in the read that brought the handshake's answer before the
    connection is handed to the client: they are held until the session is attached, then delivered."""
    info = json.dumps({"op": "serverInfo", "name": "eager", "capabilities": []}).encode()
    status = json.dumps({"op": "status", "level": 1, "message": "hello", "id": "s1"}).encode()
    frames = b"".join(bytes([0x81, len(p)]) + p for p in (info, status))
    server = await _raw_server(b"foxglove.sdk.v1", frames)
    try:
        client = FoxgloveClient(f"ws://127.0.0.1:{server.sockets[0].getsockname()[1]}", reconnect=False)
        await client.connect(timeout=10)
        try:
            assert client.describe()["server"] == "eager"
            await until(lambda: "s1" in client.session.statuses, what="the status after serverInfo")
        finally:
            await client.close()
    finally:
        server.close()


async def test_a_rosbridge_server_is_detected_as_rosbridge_and_refused_by_a_forced_foxglove_client(sim):
    assert await detect(sim.url) == "rosbridge"
    client = await open_client(sim.url, reconnect=False)
    assert isinstance(client, BridgeClient)
    forced = FoxgloveClient(sim.url, reconnect=False)
    with pytest.raises(NotFoxgloveError, match="not a Foxglove server"):
        await forced.connect(timeout=5)
    assert forced.failure is not None and forced.failure.fatal


async def test_the_catalogue_lists_topics_with_their_schemas_types(fox_client):
    topics = await until(lambda: fox_client.session.by_topic if len(fox_client.session.by_topic) >= 5 else None)
    assert topics  # all five advertised
    listed = await fox_client.catalog.topics()
    assert listed["/rosout_str"] == "std_msgs/msg/String"
    assert listed["/pose"] == "geometry_msgs/msg/Pose"
    assert listed["/camera/compressed"] == "foxglove.CompressedImage"
    assert listed["/gps"] == "foxglove.LocationFix"
    assert "/chatter" in listed
    services = await fox_client.catalog.services_with_types()
    assert services["/reset"] == "std_srvs/srv/Trigger"
    details = await fox_client.catalog.message_details("geometry_msgs/msg/Pose")
    assert details[0]["fieldnames"] == ["position", "orientation"]


async def test_binary_message_data_is_decoded_by_encoding(fox, fox_client):
    got: dict[str, list] = {}
    node = fox_client.node("test")
    for topic in ("/chatter", "/rosout_str", "/pose", "/camera/compressed", "/gps"):
        node.subscribe(topic, lambda m, t=topic: got.setdefault(t, []).append(m))
    await until(lambda: len(fox.subscribed) == 5, what="the peer saw five subscriptions")
    fox.say("hello json")
    fox.log_string("hello cdr")
    fox.log_pose(1.5)
    fox.log_image(b"\xff\xd8\xff\xe0jpeg")
    fox.log_fix(57.1, 11.9)
    await until(lambda: len(got) == 5, what="one message on each topic")
    assert got["/chatter"][0] == {"data": "hello json"}
    assert got["/rosout_str"][0] == {"data": "hello cdr"}
    assert got["/pose"][0]["position"] == {"x": 1.5, "y": 2.0, "z": 0.0}
    assert got["/camera/compressed"][0]["format"] == "jpeg"
    assert got["/camera/compressed"][0]["data"] == b"\xff\xd8\xff\xe0jpeg"
    assert got["/gps"][0]["latitude"] == 57.1 and got["/gps"][0]["longitude"] == 11.9
    node.close()
    await until(lambda: not fox.subscribed, what="the last consumer unsubscribed")
    assert fox_client.stats["bad_frames"] == 0


async def test_client_publish_advertises_with_cdr_and_sends_binary_messages(fox, fox_client):
    node = fox_client.node("teleop")
    pub = node.advertise("/cmd_vel", "geometry_msgs/msg/Twist")
    await until(lambda: fox.advertised, what="the client advertisement")
    assert fox.advertised[0] == ("/cmd_vel", "cdr", "geometry_msgs/msg/Twist")
    assert pub.publish({"linear": {"x": 0.5}, "angular": {"z": -0.25}})
    await until(lambda: fox.received, what="the message")
    topic, encoding, data = fox.received[0]
    assert (topic, encoding) == ("/cmd_vel", "cdr")
    twist = REG.deserialize_cdr("geometry_msgs/msg/Twist", data)
    assert twist["linear"]["x"] == 0.5 and twist["angular"]["z"] == -0.25
    node.close()
    await until(lambda: fox.unadvertised == ["/cmd_vel"], what="the unadvertise")


async def test_services_cdr_and_json_and_the_servers_failure_text(fox, fox_client):
    assert await fox_client.call_service("/reset", {}) == {"success": True, "message": "reset done"}
    assert await fox_client.call_service("/add", {"a": 2, "b": 3}) == {"sum": 5}
    with pytest.raises(ServiceError, match="the pump is jammed"):
        await fox_client.call_service("/fail", {"a": 1, "b": 1})
    with pytest.raises(ServiceError, match="advertises no service /nope"):
        await fox_client.call_service("/nope", {})
    node = fox_client.node("caller")
    assert (await node.call_service("/add", {"a": 1, "b": 1})) == {"sum": 2}


async def test_parameters_get_set_refused_and_updates(fox, fox_client):
    params = fox_client.params
    assert await params.by_owner() == {"/boat": ["/boat.enabled", "/boat.max_speed", "/boat.name"]}
    assert await params.get("/boat.max_speed") == 2.5
    await params.set("/boat.max_speed", 3.0)
    assert await params.get("/boat.max_speed") == 3.0
    with pytest.raises(ParamRejectedError, match="kingfisher"):
        await params.set("/boat.name", "heron")
    with pytest.raises(ParamNotFoundError):
        await params.get("/boat.nope")
    with pytest.raises(BridgeError, match="cannot delete"):
        await params.delete("/boat.max_speed")
    seen: list = []
    params.watch(["/boat.max_speed"], lambda name, value: seen.append((name, value)))
    await until(lambda: "/boat.max_speed" in fox.param_subscribed, what="the parameter subscription")
    fox.set_param("/boat.max_speed", 4.5)
    await until(lambda: ("/boat.max_speed", 4.5) in seen, what="the update")


async def test_the_connection_graph_feeds_discovery(fox_client):
    catalog = fox_client.catalog
    await until(lambda: fox_client.session.graph["published"], what="the graph")
    assert await catalog.publishers("/pose") == ["/boat"]
    assert await catalog.subscribers("/cmd_vel") == ["/boat"]
    assert await catalog.nodes() == ["/boat", "/talker"]
    assert (await catalog.node_details("/boat"))["services"] == ["/reset"]


async def test_status_messages_reach_the_status_listeners_and_time_is_kept(fox, fox_client):
    from foxglove.websocket import StatusLevel

    notes: list = []
    fox_client.add_status_listener(notes.append)
    fox.server.publish_status("battery low", StatusLevel.Warning, id="bat")
    await until(lambda: notes, what="the status")
    assert notes[0]["level"] == "warning" and notes[0]["msg"] == "battery low"
    fox.server.broadcast_time(1_700_000_000_123_456_789)
    await until(lambda: fox_client.server_time == 1_700_000_000_123_456_789, what="the time")
    assert await fox_client.catalog.get_time() == {"sec": 1_700_000_000, "nanosec": 123_456_789}


async def test_actions_and_rosauth_are_said_in_words(fox, fox_client):
    node = fox_client.node("nav")
    with pytest.raises(ActionError, match="no actions"):
        node.send_action_goal("/navigate", "nav2_msgs/action/NavigateToPose", {})
    with pytest.raises(BridgeError, match="call services, not provide them"):
        node.advertise_service("/mine", "std_srvs/srv/Trigger", lambda req: {})
    assert await fox_client.catalog.action_servers() == []
    with_auth = FoxgloveClient(fox.url, auth={"secret": "x"})
    assert CANNOT["rosauth"] in with_auth.describe()["cannot"]
    assert CANNOT["actions"] in fox_client.describe()["cannot"]


async def test_reconnect_restores_subscriptions_advertisements_and_parameter_subscriptions():
    peer = FoxPeer()
    port = peer.port
    client = FoxgloveClient(peer.url, backoff_min=0.05, backoff_max=0.2, call_timeout=5)
    try:
        await client.connect(timeout=10)
        got: list = []
        node = client.node("keep")
        node.subscribe("/chatter", got.append)
        pub = node.advertise("/note", "std_msgs/msg/String")
        updates: list = []
        client.params.watch(["/boat.max_speed"], lambda n, v: updates.append(v))
        await until(lambda: peer.subscribed and peer.advertised and peer.param_subscribed)
        peer.stop()
        await until(lambda: client.state is not ConnectionState.CONNECTED, what="the link noticed")
        peer = FoxPeer(port=port)  # the robot comes back on the same port, a new server session
        await until(lambda: client.state is ConnectionState.CONNECTED, 15, what="reconnected")
        await until(lambda: "/chatter" in peer.subscribed and peer.advertised and peer.param_subscribed, 10,
                    what="everything restored on the new server")
        peer.say("after")
        await until(lambda: got and got[-1] == {"data": "after"}, what="a message after the reconnect")
        assert pub.publish({"data": "again"})
        await until(lambda: peer.received, what="a publish after the reconnect")
        peer.set_param("/boat.max_speed", 7.0)
        await until(lambda: 7.0 in updates, what="a parameter update after the reconnect")
        assert client.stats["connects"] == 2
    finally:
        await client.close()
        peer.stop()


async def test_publishing_while_down_is_dropped_and_counted_except_a_latched_value(fox):
    client = FoxgloveClient(fox.url, backoff_min=0.05, call_timeout=5)
    node = client.node("early")
    pub = node.advertise("/note", "std_msgs/msg/String")
    assert pub.publish({"data": "nobody"}) is False and pub.dropped == 1
    latched = node.advertise("/state", "std_msgs/msg/String", latch=True)
    assert latched.publish({"data": "kept"}) is True
    await client.connect(timeout=10)
    try:
        await until(lambda: any(t == "/state" for t, _e, _d in fox.received), what="the latched value")
        assert client.stats["dropped_while_down"] == 1
    finally:
        await client.close()


async def test_a_wss_link_with_ca_file(tmp_path):
    from tls_certs import make_pki

    pki = make_pki(tmp_path)
    peer = FoxPeer(tls=(pki.server.cert.read_bytes(), pki.server.key.read_bytes()))
    try:
        client = FoxgloveClient(peer.url, ca_file=str(pki.ca), reconnect=False)
        await client.connect(timeout=10)
        assert client.describe()["server"] == "fox-peer"
        await client.close()
        untrusted = FoxgloveClient(peer.url, reconnect=False)
        with pytest.raises(ssl.SSLError):
            await untrusted.connect(timeout=10)
        assert untrusted.failure is not None and untrusted.failure.fatal
        assert "certificate" in untrusted.failure.reason
    finally:
        peer.stop()


async def test_calls_waiting_when_the_link_drops_fail_at_once(fox):
    client = FoxgloveClient(fox.url, reconnect=False, call_timeout=30)
    await client.connect(timeout=10)
    try:
        waiting = asyncio.ensure_future(client.call_service("/slow", {}))
        await until(lambda: any(name == "/slow" for name, _ in fox.calls), what="the call reached the robot")
        await client.link.close()  # the robot has not answered yet (it answers once released)
        with pytest.raises(ConnectionLostError):
            await asyncio.wait_for(waiting, 5)
        fox.release.set()
        with pytest.raises(NotConnectedError):
            await client.call_service("/add", {"a": 1, "b": 1})
    finally:
        await client.close()


async def test_the_safety_envelope_holds_motion_commands_on_this_link_too(fox, fox_client):
    from rcon_core.bridge.envelope import Envelope, EnvelopeRefused

    fox_client.envelope = Envelope(max_linear=0.5, max_angular=0.2)
    pub = fox_client.node("pad").advertise("/cmd_vel", "geometry_msgs/msg/Twist")
    await until(lambda: fox.advertised, what="the advertisement")
    assert pub.publish({"linear": {"x": 3.0}, "angular": {"z": -1.0}})
    await until(lambda: fox.received, what="the clamped command")
    twist = REG.deserialize_cdr("geometry_msgs/msg/Twist", fox.received[0][2])
    assert twist["linear"]["x"] == 0.5 and twist["angular"]["z"] == -0.2
    with pytest.raises(EnvelopeRefused):
        pub.publish({"linear": {"x": float("nan")}})
    assert fox_client.stats["envelope_clamped"] == 1 and fox_client.stats["envelope_refused"] == 1


async def test_a_silent_stall_is_degraded_and_a_command_is_never_delivered_late(fox):
    """The rosbridge link's stall rules on this link (``bridge/freshness.py``): a stall with no FIN or RST
    is DEGRADED within 1.5 s, a command published meanwhile is dropped (counted), the link recovers on the
    same connection."""
    import time

    from rcon_core.loopback import StallProxy

    async with StallProxy("127.0.0.1", fox.port) as proxy:
        client = FoxgloveClient(proxy.url, backoff_min=0.05, backoff_max=0.2, call_timeout=5)
        states: list = []
        client.add_state_listener(lambda st: states.append((time.monotonic(), st)))
        await client.connect(timeout=10)
        try:
            pub = client.node("pad").advertise("/cmd_vel", "geometry_msgs/msg/Twist")
            await until(lambda: fox.advertised, what="the advertisement")
            await asyncio.sleep(0.3)
            stalled_at = time.monotonic()
            proxy.stall()
            await until(lambda: client.state is ConnectionState.DEGRADED, 3, what="DEGRADED")
            degraded_at = next(t for t, st in states if st is ConnectionState.DEGRADED)
            assert degraded_at - stalled_at <= 1.5 and client.connected
            assert pub.publish({"linear": {"x": 1.0}}) is False and pub.dropped == 1
            assert client.stats["stale_dropped"] == 1
            proxy.resume()
            await until(lambda: client.state is ConnectionState.CONNECTED, 3, what="recovered")
            assert client.stats["connects"] == 1 and client.stats["degraded"] == 1
            assert pub.publish({"linear": {"x": 0.25}})  # a command after the stall, on the same connection...
            await until(lambda: fox.received, what="the command sent after the stall")
            [(topic, _encoding, data)] = fox.received  # ...arrives, alone: the stall's never reached the robot
            assert REG.deserialize_cdr("geometry_msgs/msg/Twist", data)["linear"]["x"] == 0.25
        finally:
            await client.close()


async def test_text_and_binary_frames_keep_their_kind_and_order_through_the_writers_queue(transport):
    """The Foxglove link writes text (JSON ops) and binary frames (client messages, service calls) through the
    bridge's adapters: written at once, or -- while the transport is above its high-water mark -- queued and
    drained by the writer in order, each still of its own kind (a queued binary command too)."""
    import websockets

    from rcon_core.foxglove.ws import FoxgloveReceiver, open_connection

    got: list = []
    done = asyncio.Event()

    async def serve(ws):
        async for m in ws:
            got.append(m)
            if len(got) == 6:
                done.set()

    async with websockets.serve(serve, "127.0.0.1", 0, subprotocols=["foxglove.sdk.v1"]) as server:
        url = f"ws://127.0.0.1:{server.sockets[0].getsockname()[1]}"
        receiver = FoxgloveReceiver(got.append, got.append, got.append)
        link = await open_connection(transport, url, ["foxglove.sdk.v1"], receiver, got.append, ssl_context=None,
                                     open_timeout=10, max_size=1 << 20)
        writer = asyncio.create_task(link.run_writer())
        try:
            assert link.subprotocol == "foxglove.sdk.v1"
            link.write(b'{"op":"a"}')
            link.write_binary(b"\x01now")
            link.drain.pause()  # as the transport says when its buffer is above the high-water mark
            link.write(b'{"op":"b"}')
            link.write_binary(b"\x01queued")
            assert link.send_by(b"\x01command", None, time.monotonic() + 5.0, binary=True)
            link.write(b'{"op":"c"}')
            assert link.queued == 4
            link.drain.resume()
            link.event.set()
            await asyncio.wait_for(done.wait(), 10)
            assert got == ['{"op":"a"}', b"\x01now", '{"op":"b"}', b"\x01queued", b"\x01command", '{"op":"c"}']
        finally:
            writer.cancel()
            await link.close()
            link.release()
