"""The sim against a hostile client, with raw WebSocket frames on loopback: a frame limit, nothing but a
small ``auth`` op read before authentication, a timeout for clients that never authenticate, and a
lenient frame scanner that stays linear."""

from __future__ import annotations

import asyncio
import base64
import json
import os
import struct
import time
from typing import Any

import pytest
import websockets
from websockets.frames import Frame, Opcode

from rcon_core.sim import SimServer
from rcon_core.sim.auth import make_mac
from rcon_core.sim.frames import LENIENT_LIMIT, MAX_VALUES, parse_frame, scan_objects

SECRET = "s3cret"


def auth_op(secret: str = SECRET, **override: Any) -> bytes:
    now = int(time.time())
    fields = {"client": "192.168.1.5", "dest": "192.168.1.2", "rand": "r4nd", "t": now, "level": "admin",
              "end": now + 60, **override}
    mac = make_mac(secret, fields["client"], fields["dest"], fields["rand"], fields["t"], fields["level"],
                   fields["end"])
    return json.dumps({"op": "auth", "mac": mac, **fields}).encode()


def call_op(call_id: str, pad: int = 0) -> bytes:
    return json.dumps({"op": "call_service", "service": "/rosapi/get_time", "id": call_id, "args": {},
                       "pad": "x" * pad}).encode()


class RawClient:
    """A WebSocket client written by hand: it sends exactly the bytes a test asks for."""

    def __init__(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        self.reader, self.writer = reader, writer

    @classmethod
    async def open(cls, server: SimServer) -> RawClient:
        reader, writer = await asyncio.open_connection("127.0.0.1", server.port)
        key = base64.b64encode(os.urandom(16)).decode()
        writer.write((f"GET / HTTP/1.1\r\nHost: 127.0.0.1:{server.port}\r\nUpgrade: websocket\r\n"
                      f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n").encode())
        head = await asyncio.wait_for(reader.readuntil(b"\r\n\r\n"), 5)
        assert head.startswith(b"HTTP/1.1 101"), head
        return cls(reader, writer)

    @staticmethod
    def frame(data: bytes, opcode: Opcode = Opcode.TEXT, fin: bool = True) -> bytes:
        return Frame(opcode, data, fin).serialize(mask=True, extensions=[])

    async def send(self, *frames: bytes) -> None:
        """All frames in one write (they reach the server in one read, back to back)."""
        self.writer.write(b"".join(frames))
        await self.writer.drain()

    async def recv(self, timeout: float = 5.0) -> tuple[Opcode, bytes]:
        async def one() -> tuple[Opcode, bytes]:
            b0, b1 = await self.reader.readexactly(2)
            n = b1 & 0x7F
            if n == 126:
                (n,) = struct.unpack(">H", await self.reader.readexactly(2))
            elif n == 127:
                (n,) = struct.unpack(">Q", await self.reader.readexactly(8))
            return Opcode(b0 & 0x0F), await self.reader.readexactly(n)

        return await asyncio.wait_for(one(), timeout)

    async def reply(self, call_id: str, timeout: float = 5.0) -> dict[str, Any]:
        while True:
            opcode, data = await self.recv(timeout)
            assert opcode is not Opcode.CLOSE, f"closed: {data!r}"
            if opcode is Opcode.TEXT:
                msg = json.loads(data)
                if msg.get("op") == "service_response" and msg.get("id") == call_id:
                    return msg

    async def closed(self, timeout: float = 5.0) -> tuple[int, str]:
        """The close frame's code and reason (skipping anything before it)."""
        while True:
            opcode, data = await self.recv(timeout)
            if opcode is Opcode.CLOSE:
                return struct.unpack(">H", data[:2])[0], data[2:].decode()

    def close(self) -> None:
        self.writer.close()


@pytest.fixture
async def limited():
    server = SimServer(robot=False, max_frame=64 * 1024)
    await server.start()
    yield server
    await server.stop()


@pytest.fixture
async def guarded():
    server = SimServer(robot=False, auth_secret=SECRET, auth_timeout=1.0)
    await server.start()
    yield server
    await server.stop()


# -------------------------------------------------------------------------------------------- frame limit
def test_the_default_limit_fits_a_1080p_image_and_the_sim_has_one():
    server = SimServer(robot=False)
    assert 1920 * 1080 * 3 * 4 // 3 + 4096 < server.max_frame <= 64 * 1024 * 1024
    with pytest.raises(ValueError):
        SimServer(robot=False, max_frame=10)


async def test_a_frame_over_the_limit_closes_that_client_only(limited):
    good, bad = await RawClient.open(limited), await RawClient.open(limited)
    try:
        await good.send(RawClient.frame(call_op("fits", pad=60 * 1024)))
        assert (await good.reply("fits"))["result"] is True
        # a header announcing 200 MB: refused as soon as the header is read, nothing is buffered
        await bad.send(b"\x81\xff" + struct.pack(">Q", 200_000_000) + os.urandom(4) + b"x" * 1024)
        code, reason = await bad.closed()
        assert code == 1009 and "65536" in reason, reason
        await good.send(RawClient.frame(call_op("still")))
        assert (await good.reply("still"))["result"] is True
    finally:
        good.close()
        bad.close()


async def test_a_message_split_in_fragments_counts_whole(limited):
    client = await RawClient.open(limited)
    try:
        part = b" " * (40 * 1024)
        await client.send(RawClient.frame(part, fin=False), RawClient.frame(part, Opcode.CONT, fin=False))
        code, _ = await client.closed()
        assert code == 1009
    finally:
        client.close()


async def test_rosbridge_fragment_ops_are_bounded_too(limited):
    async with websockets.connect(limited.url) as ws:
        chunk = "y" * 30 * 1024
        for num in range(3):  # 90 KB in flight in one message of 100 parts, more than max_frame
            await ws.send(json.dumps({"op": "fragment", "id": "big", "data": chunk, "num": num, "total": 100}))
        await ws.send(json.dumps({"op": "call_service", "service": "/rosapi/get_time", "id": "after"}))
        reply = json.loads(await asyncio.wait_for(ws.recv(), 5))
        assert reply["id"] == "after"
        [conn] = limited.connections
        assert len(conn.fragments) == 0 and conn.fragments.bytes_held == 0  # dropped, not held


# ---------------------------------------------------------------------------------------------- auth
async def test_auth_then_a_big_frame_in_the_same_write_is_read(guarded):
    for attempt in range(5):  # the big frame is parsed before the handler saw the auth op
        client = await RawClient.open(guarded)
        try:
            await client.send(RawClient.frame(auth_op()), RawClient.frame(call_op(f"big{attempt}", pad=200_000)))
            assert (await client.reply(f"big{attempt}"))["result"] is True
        finally:
            client.close()


async def test_before_auth_a_frame_over_4_kb_is_refused_unread(guarded):
    client = await RawClient.open(guarded)
    try:
        await client.send(b"\x81\xff" + struct.pack(">Q", 200_000_000) + os.urandom(4) + b"x" * 1024)
        code, reason = await client.closed()
        assert code == 1009 and "4096" in reason, reason
    finally:
        client.close()
    assert guarded.connections == set()


@pytest.mark.parametrize("first, why", [  # frames made when the test runs: auth ops carry the time
    (lambda: call_op("sneaky"), "authentication failed: the first frame must be an auth op (got op 'call_service')"),
    (lambda: b"not json", "authentication failed: the first frame must be an auth op (it is not a JSON object)"),
    (lambda: auth_op() + auth_op(), "authentication failed: the first frame must be an auth op (it is not a JSON"),
    (lambda: auth_op("wrong"), "authentication failed: mac does not match"),
    (lambda: auth_op(end=int(time.time()) - 100), "authentication failed: the authentication has expired"),
])
async def test_anything_but_a_valid_auth_op_first_closes_with_the_reason(guarded, first, why):
    client = await RawClient.open(guarded)
    try:
        await client.send(RawClient.frame(first()), RawClient.frame(call_op("behind")))
        code, reason = await client.closed()
        assert code == 4001 and reason.startswith(why), reason
    finally:
        client.close()
    assert guarded.connections == set()


async def test_a_client_that_never_authenticates_is_dropped(guarded):
    client = await RawClient.open(guarded)
    try:
        started = time.monotonic()
        code, reason = await client.closed(timeout=10)
        assert code == 4001 and reason.startswith("authentication timed out"), reason
        assert time.monotonic() - started >= 0.9
    finally:
        client.close()


async def test_the_websockets_client_authenticates_and_works(guarded):
    async with websockets.connect(guarded.url) as ws:
        await ws.send(auth_op().decode())
        await ws.send(call_op("ok").decode())
        reply = json.loads(await asyncio.wait_for(ws.recv(), 5))
        assert reply["id"] == "ok" and reply["result"] is True


# ---------------------------------------------------------------------------------------- the scanner
async def test_a_megabyte_of_garbage_does_not_stall_the_sim():
    sim = SimServer(robot=False, max_frame=8 * 1024 * 1024)
    await sim.start()
    try:
        async with websockets.connect(sim.url, max_size=None) as ws, websockets.connect(sim.url) as other:
            for garbage in ("{" * 1_000_000, '{"' * 500_000, '{"a":' * 200_000, "{" + "{}" * 400_000):
                await ws.send(garbage)
            # the old scanner needed minutes for these (an error message per "{", each counting lines)
            await other.send(call_op("alive").decode())
            reply = json.loads(await asyncio.wait_for(other.recv(), 10))
            assert reply["id"] == "alive"
    finally:
        await sim.stop()


def test_the_scanner_skips_deep_objects_whatever_the_recursion_limit():
    """Found by the full suite: another test had raised the interpreter's recursion limit, and the 5000-deep
    object then parsed (a C stack overflow risk); the depth is now checked before parsing."""
    import sys

    old = sys.getrecursionlimit()
    sys.setrecursionlimit(20_000)
    try:
        text = '{"op": "a"} {"deep": ' + "[" * 5000 + "]" * 5000 + '} {"op": "b", "ok": [[[1]]]}'
        assert [v.get("op") for v in scan_objects(text)] == ["a", "b"]
    finally:
        sys.setrecursionlimit(old)


def test_the_scanner_finds_every_balanced_object_and_skips_broken_ones():
    text = ('junk {"op": "a"}{"op": "b", "s": "}{\\"}"} {"op": tru} {"op": "c", "x": NaN} '
            '{"deep": ' + "[" * 5000 + "]" * 5000 + '} {"op": "d"} {"open": "never closed')
    values = scan_objects(text)
    assert [v.get("op") for v in values] == ["a", "b", "c", "d"]
    assert values[1]["s"] == '}{"}'
    assert parse_frame(b'{"op": "e"}', "t") == [{"op": "e"}] and parse_frame(b"\xff", "t") == []
    assert len(scan_objects("{}" * (MAX_VALUES * 3))) == MAX_VALUES
    big_nan = '{"op": "n", "v": [' + "NaN, " * (LENIENT_LIMIT // 5) + "1]}"
    [one] = parse_frame(big_nan, "t")  # big: must be one value, NaN accepted
    assert one["op"] == "n"
    assert parse_frame(big_nan + '{"op": "m"}', "t") == []  # big and not one value: dropped


# ------------------------------------------------------------------------------------------- rcon sim
async def test_rcon_sim_takes_the_frame_limit_from_the_command_line():
    import re
    import subprocess
    import sys

    from rcon_core.cli.main import main

    assert main(["sim", "--max-frame", "0"]) == 2
    proc = subprocess.Popen([sys.executable, "-m", "rcon_core.cli.main", "sim", "--port", "0", "--max-frame",
                             "0.0625", "--auth"], stdout=subprocess.PIPE, text=True,
                            env={**os.environ, "RCON_AUTH_SECRET": SECRET})
    try:
        line = await asyncio.wait_for(asyncio.to_thread(proc.stdout.readline), 60)
        url = re.search(r"ws://\S+", line).group(0)
        async with websockets.connect(url, max_size=None) as ws:
            await ws.send(auth_op().decode())
            await ws.send(call_op("small", pad=60 * 1024).decode())
            assert json.loads(await asyncio.wait_for(ws.recv(), 10))["id"] == "small"
            await ws.send(call_op("too big", pad=70 * 1024).decode())
            with pytest.raises(websockets.ConnectionClosed) as info:
                await asyncio.wait_for(ws.recv(), 10)
            assert info.value.rcvd is not None and info.value.rcvd.code == 1009
    finally:
        proc.terminate()
        proc.wait(timeout=30)
