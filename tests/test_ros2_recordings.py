"""Every frame of the rosbridge 2.1.0 (ROS 2 Jazzy) recordings: understood by the client, or ignored on purpose.

The recordings (``tests/recordings/rosbridge-ros2-2.1.0``) are ground truth.  A frame the server sent goes
through the client's own decoders and its session, exactly as the read loop hands it over, and must leave
no bad frame behind -- unless it is listed in ``IGNORED_FRAMES`` with the reason.  A line where nothing
came back is one of rosbridge's silences; each kind is named in ``SILENCES`` with what RCON does about it,
and a silence no rule explains fails the test (so a new recording cannot slip in unread).
"""

from __future__ import annotations

import base64
import math
from pathlib import Path
from typing import Any

import orjson
import pytest
from replay_server import ROS2, load

from rcon_core.bridge import BridgeClient
from rcon_core.bridge.protocol import FragmentAssembler, decode_binary, loads_text
from rcon_core.msgs.values import as_bytes

pytestmark = pytest.mark.recordings

FILES = sorted(p.name for p in (Path(__file__).parent / "recordings" / ROS2).glob("*.jsonl"))

#: frames the server sent that the client does not take in, and why
IGNORED_FRAMES = {
    ("malformed.jsonl", 49): "the 1 MiB id frame is stored shortened (no received_text to replay); RCON's ids "
                             "are short, and a frame that size is decoded off the loop (offload.py)",
}

#: ops the client's session takes from a server (``session.Session._ops``, plus the inbound wrappers)
UNDERSTOOD_OPS = {"publish", "service_response", "call_service", "action_feedback", "action_result",
                  "send_action_goal", "cancel_action_goal", "fragment", "png", "status"}

#: (file, first line, last line, reason): the lines where nothing came back, and what RCON does about it
SILENCES: list[tuple[str, int, int, str]] = [
    ("rosapi.jsonl", 64, 77, "calls that kill or deadlock rosapi 2.1.0: RCON never sends them to a 2.x server "
                             "not known to be fixed (bridge/rosapi_guard.py; test_ros2_quirks.py)"),
    ("services.jsonl", 19, 19, "advertise_service is never acknowledged (quirk 7)"),
    ("services.jsonl", 20, 23, "one unanswered call holds up every later frame of the connection: every "
                               "RCON call has its own timeout and names what it waited for (session.py)"),
    ("actions.jsonl", 14, 17, "a rejected goal and a goal to a missing action get no answer: RCON's goals "
                              "say 'no answer from the action server (rejected?)' after a bounded time "
                              "(goals.py)"),
    ("actions.jsonl", 22, 23, "a goal without action_type gets no answer: RCON always sends action_type "
                              "(nodes.send_action_goal refuses a goal without one)"),
    ("publish_png.jsonl", 1, 4, "png sends nothing on 2.1.0: RCON never asks a ROS 2 server for png "
                                "(subscribe.py)"),
    ("publish_png.jsonl", 8, 8, "a png id silences a plain id on the same topic: RCON has one "
                                "subscription per topic and never png on ROS 2"),
    ("publish_cbor.jsonl", 46, 46, "cbor sends nothing for an Imu (fixed-size arrays): RCON asks cbor-raw "
                                   "for such types (subscribe.py)"),
    ("subscribe_options.jsonl", 29, 29, "the answer comes in fragments on the next lines (sticky fragment_size)"),
    ("subscribe_options.jsonl", 36, 37, "a subscribe carrying fragment_size null resets the connection's "
                                        "size and fails itself: RCON never sends a null fragment_size"),
    ("subscribe_options.jsonl", 41, 42, "cbor together with fragment_size sends nothing: RCON never combines "
                                        "a binary compression with fragment_size (topics.py)"),
    ("subscribe_options.jsonl", 45, 45, "a count of frames, no frame (two ids on one topic give one frame "
                                        "per message; RCON keeps one subscription per topic anyway)"),
    ("subscribe_options.jsonl", 54, 54, "an id-less unsubscribe ends every id: RCON always names its id"),
    ("subscribe_options.jsonl", 68, 74, "subscribes that fail their checks get no answer: RCON gives a "
                                        "type, integer throttle_rate/queue_length (nodes.subscribe refuses "
                                        "others) and checks unusual types first (typecheck.py)"),
    ("reconnect.jsonl", 3, 3, "a count of frames, no frame"),
    ("reconnect.jsonl", 7, 7, "a connection opens: no frame (the watcher's /client_count shows it)"),
    ("reconnect.jsonl", 14, 14, "a connection closes: no frame"),
    ("reconnect.jsonl", 20, 20, "a connection opens: no frame"),
    ("reconnect.jsonl", 26, 26, "a connection is dropped without a close handshake: no frame"),
    ("reconnect.jsonl", 23, 23, "a new connection gets nothing until it subscribes again: RCON re-sends every "
                                "subscription after a reconnect (session.attached)"),
    ("malformed.jsonl", 1, 51, "bad frames get silence (or end the connection's processing); RCON never "
                               "sends them, and a call that gets no answer ends with a timeout naming it"),
    ("client_service.jsonl", 18, 18, "the connection closes; the advertised service stays behind as an orphan "
                                     "(RCON re-advertises after a reconnect, session.attached)"),
    ("client_service.jsonl", 20, 20, "a call to the orphan goes nowhere (server log only)"),
]

#: ops rosbridge never acknowledges (quirk 7): their silence is the normal case
NEVER_ACKNOWLEDGED = {"subscribe", "unsubscribe", "advertise", "unadvertise", "publish", "advertise_service",
                      "unadvertise_service", "advertise_action", "unadvertise_action", "service_response",
                      "action_feedback", "action_result", "cancel_action_goal", "fragment", "send_action_goal"}


def received(line: dict[str, Any]) -> str | bytes | None:
    if line.get("received_text") is not None:
        return line["received_text"]
    if line.get("received_b64"):
        return base64.b64decode(line["received_b64"])
    return None


def decode(frame: str | bytes) -> Any:
    """What the client's read loop makes of one frame (inbound.py: orjson, lenient text, CBOR)."""
    return loads_text(frame) if isinstance(frame, str) else decode_binary(frame)


def silence_reason(name: str, n: int, line: dict[str, Any]) -> str | None:
    for file, first, last, reason in SILENCES:
        if file == name and first <= n <= last:
            return reason
    sent = line.get("sent")
    if isinstance(sent, dict) and sent.get("op") in NEVER_ACKNOWLEDGED:
        return "never acknowledged (quirk 7); the effect shows in a later frame"
    if isinstance(sent, str) and sent.lstrip().startswith('{"op": "publish"'):
        return "a publish written with bare NaN tokens (the recorder's own frame); never acknowledged"
    return None


@pytest.mark.parametrize("name", FILES)
def test_every_received_frame_is_understood(name: str) -> None:
    client = BridgeClient("ws://127.0.0.1:9", reconnect=False)  # never connected: frames go in by hand
    taken = 0
    for n, line in enumerate(load(name, ROS2), 1):
        frame = received(line)
        if frame is None:
            continue
        if (name, n) in IGNORED_FRAMES:
            continue
        bad = client.stats["bad_frames"]
        m = decode(frame)
        assert isinstance(m, dict) and m.get("op") in UNDERSTOOD_OPS, f"{name}:{n}: {m!r:.120}"
        client.inbound.other(m)
        assert client.stats["bad_frames"] == bad, f"{name}:{n} was not understood"
        taken += 1
    assert taken > 0 or name == "publish_png.jsonl"


@pytest.mark.parametrize("name", FILES)
def test_every_silence_has_a_reason(name: str) -> None:
    unexplained = []
    for n, line in enumerate(load(name, ROS2), 1):
        if received(line) is None and (name, n) not in IGNORED_FRAMES and silence_reason(name, n, line) is None:
            unexplained.append(n)
    assert unexplained == [], f"{name}: lines {unexplained} got no answer and no rule says why"


def test_ignored_and_silence_rules_point_at_real_lines() -> None:
    for (name, n), reason in IGNORED_FRAMES.items():
        assert reason and received(load(name, ROS2)[n - 1]) is None or load(name, ROS2)[n - 1].get("abbreviated")
    for file, first, last, reason in SILENCES:
        lines = load(file, ROS2)
        assert reason and 1 <= first <= last <= len(lines)
        assert any(received(lines[n - 1]) is None for n in range(first, last + 1)), (file, first)


# ------------------------------------------------------------------------------------------ the JSON text


def test_frames_are_python_json_text_and_parse_alike() -> None:
    """Quirk 1: ', ' and ': ' separators, '/' not escaped, non-ASCII as \\uXXXX -- plain JSON all the same."""
    line = load("publish_json.jsonl", ROS2)[31]
    text = line["received_text"]
    assert '", "' in text and '/a/b' in text and "\\ud83d\\ude80" in text
    assert decode(text) == line["received"]
    assert "\u00e9" in decode(text)["msg"]["data"] and "\U0001f680" in decode(text)["msg"]["data"]


def test_bare_nan_in_fixed_size_arrays_is_read_not_dropped() -> None:
    """Quirk 5: an Imu's covariances hold bare NaN/Infinity tokens (publish_json.jsonl:62): not JSON, yet
    the client reads the frame (float NaN/inf) instead of dropping the message."""
    line = load("publish_json.jsonl", ROS2)[61]
    assert line["received_invalid_json"] is True
    with pytest.raises(orjson.JSONDecodeError):
        orjson.loads(line["received_text"])
    imu = decode(line["received_text"])["msg"]
    cov = imu["angular_velocity_covariance"]
    assert len(cov) == 9 and math.isnan(cov[0]) and cov[4] == math.inf and cov[8] == 0.5
    assert imu["orientation_covariance"][0] == -1.0
    assert imu["angular_velocity"]["x"] is None  # a scalar NaN is null as usual
    # variable-length arrays and scalars: null (publish_json.jsonl:50, :54)
    assert decode(load("publish_json.jsonl", ROS2)[53]["received_text"])["msg"] == {"data": None}
    assert None in decode(load("publish_json.jsonl", ROS2)[49]["received_text"])["msg"]["data"]


def test_nan_id_echo_is_read() -> None:
    """malformed.jsonl:34: the reply to a NaN id echoes ``"id": NaN``."""
    line = load("malformed.jsonl", ROS2)[33]
    m = decode(line["received_text"])
    assert m["op"] == "service_response" and math.isnan(m["id"])


def test_uint8_arrays_arrive_as_base64_even_for_numbers() -> None:
    """Quirk 4: uint8[] is one base64 string (Image data, UInt8MultiArray, even GetParameterTypes' type
    codes, rosapi.jsonl:37) and an empty one is ""; byte[] (octet) and int8[] stay lists."""
    lines = load("rosapi.jsonl", ROS2)
    assert list(as_bytes(lines[36]["received"]["values"]["types"])) == [4, 1]  # string, bool
    assert as_bytes(lines[37]["received"]["values"]["types"]) == b""
    assert lines[34]["received"]["values"]["values"][0]["byte_array_value"] == []
    pub = load("publish_json.jsonl", ROS2)
    assert list(as_bytes(pub[57]["received"]["msg"]["data"])) == [0, 1, 2, 253, 254, 255]
    assert pub[59]["received"]["msg"]["data"] == [-1, 0, 1, 127, -128]
    image = pub[12]["received"]["msg"]
    assert len(as_bytes(image["data"])) == image["step"] * image["height"]


# ------------------------------------------------------------------------------------------ fragments


def _fragments(first: int, last: int) -> list[dict[str, Any]]:
    lines = load("subscribe_options.jsonl", ROS2)
    return [lines[n - 1] for n in range(first, last + 1) if (lines[n - 1].get("received") or {}).get("op") == "fragment"]


def test_fragments_with_float_total_and_id_zero_reassemble() -> None:
    """Quirks 13-14: total is a float ('3.77', even '6.0'), a fragmented publish always has id 0."""
    frames = _fragments(21, 28)
    assert frames and all(isinstance(f["received"]["total"], float) for f in frames)
    assert {f["received"]["id"] for f in frames} == {0}
    asm = FragmentAssembler()
    texts = [t for f in frames if (t := asm.add(f["received"])) is not None]
    assert texts == [f["reassembled_text"] for f in frames if "reassembled_text" in f]
    assert [decode(t)["msg"]["data"].startswith("hello from ros2 peer") for t in texts] == [True, True]


def test_sticky_fragment_size_reaches_service_responses() -> None:
    """Quirk 15: the size from an earlier subscribe stays in force, so a later service_response arrives in
    fragments carrying the request's id (subscribe_options.jsonl:29-35); the client joins it."""
    frames = _fragments(30, 35)
    assert len(frames) == 6 and {f["received"]["id"] for f in frames} == {"frag-sticky-call"}
    asm = FragmentAssembler()
    out = [asm.add(f["received"]) for f in frames]
    assert out[:-1] == [None] * 5
    reply = decode(out[-1])
    assert reply["op"] == "service_response" and reply["id"] == "frag-sticky-call"
    assert reply["values"]["message"].startswith("triggered")


# ------------------------------------------------------------------------------------------ binary frames


def test_cbor_frames_have_typed_arrays_and_byte_strings() -> None:
    """Quirk 18: {op, topic, msg}; uint8[] a byte string, numeric arrays RFC 8746 typed arrays (lists here)."""
    seen = {}
    for line in load("publish_cbor.jsonl", ROS2):
        frame = received(line)
        if isinstance(frame, bytes):
            m = decode(frame)
            assert list(m) == ["op", "topic", "msg"] and m["op"] == "publish"
            seen[m["topic"]] = m["msg"]
    assert isinstance(seen["/peer/image"]["data"], bytes)
    f32 = seen["/client/f32arr"]["data"]
    assert isinstance(f32, list) and any(math.isnan(v) for v in f32) and math.inf in f32
    assert seen["/client/i8arr"]["data"] == [-1, 0, 127] and seen["/client/i32arr"]["data"] == [-1, 0, 70000]
    assert seen["/client/u8arr"]["data"] == b"\x00\x01\xff" and math.isnan(seen["/client/f64"]["data"])
    assert seen["/client/str"]["data"] == "caf\u00e9 \u00b0C /a/b \U0001f680"
    assert "/client/imu" not in seen  # cbor sends nothing for an Imu


def test_cbor_raw_payloads_are_cdr_with_the_servers_clock() -> None:
    """Quirk 19: msg = {secs, nsecs, bytes}; bytes are CDR (header 00 01 00 00), decoded by the registry."""
    from rcon_core.msgs import TypeRegistry

    reg = TypeRegistry.standard(ros2=True)
    n = 0
    for line in load("publish_cbor_raw.jsonl", ROS2):
        frame = received(line)
        if not isinstance(frame, bytes):
            continue
        m = decode(frame)
        raw = m["msg"]
        assert set(raw) == {"secs", "nsecs", "bytes"} and raw["bytes"][:4] == b"\x00\x01\x00\x00"
        expected = line["cdr"]
        type_name = {"/chatter": "std_msgs/msg/String", "/peer/image": "sensor_msgs/msg/Image",
                     "/client_count": "std_msgs/msg/Int32", "/client/f32arr": "std_msgs/msg/Float32MultiArray",
                     "/client/str": "std_msgs/msg/String", "/client/imu": "sensor_msgs/msg/Imu"}[m["topic"]]
        msg = reg.deserialize_cdr(type_name, raw["bytes"])
        want = expected["decoded_with_rclpy"]
        if type_name.endswith("Image"):
            assert msg["data"] == base64.b64decode(want["data"]["bytes_b64"])
            assert msg["header"]["frame_id"] == want["header"]["frame_id"] == "peer2_camera"
        elif type_name.endswith("Imu"):
            assert msg["header"] == want["header"] and len(msg["orientation_covariance"]) == 9
        else:
            assert _same(msg, want), (m["topic"], msg, want)
        n += 1
    assert n >= 8


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, float) and isinstance(b, str):  # the recording spells NaN/inf as strings
        return str(a).lower().lstrip("-").startswith(b.lower().lstrip("-")[:3])
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, list | tuple) and isinstance(b, list | tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, float) and isinstance(b, float | int):
        return a == b or abs(a - b) < 1e-6 * max(1.0, abs(b))
    return a == b
