"""issue 22.10: ``png`` frames under 1 MB were decoded on the bridge loop, and the size check counted one
byte per pixel: a 5.6 KB palette PNG stalled the loop 2.2 s and took +306 MB. Every PNG is now decoded in
the worker, and the decoded size checked before decoding counts what OpenCV makes of it (a palette as 3
or 4 channels, sub-byte samples as bytes, a colour image's tRNS as alpha)."""

from __future__ import annotations

import base64
import struct
import zlib

import orjson
import pytest

from rcon_core.bridge.protocol import decode_png
from rcon_core.bridge.safety import PngTooLarge, check_png, png_decoded_size
from rcon_core.loopback import HostileServer, png_data
from rcon_core.testing import connected, until


def chunk(kind: bytes, body: bytes) -> bytes:
    return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF)


def png(width: int, height: int, depth: int, colour: int, row_bytes: int, extra: bytes = b"") -> bytes:
    comp = zlib.compressobj(9)
    row = b"\x00" + b"\x00" * row_bytes
    body = b"".join(comp.compress(row) for _ in range(height)) + comp.flush()
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, depth, colour, 0, 0, 0))
            + extra + chunk(b"IDAT", body) + chunk(b"IEND", b""))


PLTE = chunk(b"PLTE", b"\x00\x00\x00\xff\xff\xff")


def test_a_5_6_kb_palette_png_is_counted_as_the_94_mb_it_decodes_to():
    """5600 x 5600 pixels of a 1-bit palette: 31.4 M 'bytes' by the old count (under the 32 MB limit),
    94 MB of BGR pixels as OpenCV decodes it."""
    bomb = png(5600, 5600, 1, 3, 700, PLTE)
    assert len(bomb) < 6_000
    assert png_decoded_size(bomb) == 5600 * 5600 * 3
    with pytest.raises(PngTooLarge):
        check_png(bomb, 32 << 20)
    assert png_decoded_size(png(100, 10, 1, 3, 13, PLTE + chunk(b"tRNS", b"\x00"))) == 100 * 10 * 4


@pytest.mark.parametrize(("depth", "colour", "row_bytes", "extra", "per_pixel"), [
    (1, 0, 2, b"", 1), (8, 0, 16, b"", 1), (16, 0, 32, b"", 2), (8, 0, 16, chunk(b"tRNS", b"\x00\x00"), 1),
    (8, 2, 48, chunk(b"tRNS", b"\x00\x00" * 3), 4), (16, 2, 96, chunk(b"tRNS", b"\x00\x00" * 3), 8),
    (8, 2, 48, b"", 3), (16, 2, 96, b"", 6), (8, 3, 16, PLTE, 3), (8, 4, 32, b"", 4), (16, 4, 64, b"", 8),
    (8, 6, 64, b"", 4), (16, 6, 128, b"", 8),
])
def test_the_counted_size_is_what_opencv_decodes(depth, colour, row_bytes, extra, per_pixel):
    import cv2
    import numpy as np

    data = png(16, 4, depth, colour, row_bytes, extra)
    img = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_UNCHANGED)
    assert png_decoded_size(data) == img.nbytes == 16 * 4 * per_pixel


def test_decoding_keeps_the_text_exactly():
    text = orjson.dumps({"op": "publish", "topic": "/t", "msg": {"s": "x\n" * 50, "n": [0, 1, 2]}})
    frame = {"op": "png", "data": png_data(text, 40, 40)}
    assert decode_png(frame["data"]) == orjson.loads(text)


async def test_every_png_frame_is_decoded_off_the_loop_and_the_bomb_refused():
    async with HostileServer() as srv, connected(srv.url) as client:
        got: list = []
        client.node("n").subscribe("/t", got.append)
        await srv.wait_for("subscribe", topic="/t")
        small = orjson.dumps({"op": "publish", "topic": "/t", "msg": {"n": 1}})
        await srv.send({"op": "png", "data": png_data(small, 8, 8)})  # a 100-byte frame
        await until(lambda: got == [{"n": 1}], what="the small png frame")
        assert client.stats["big_frames"] == 1  # went through the worker, not the loop
        bomb = base64.b64encode(png(5600, 5600, 1, 3, 700, PLTE)).decode()
        await srv.send({"op": "png", "data": bomb})
        await until(lambda: client.stats["png_refused"] == 1, what="the palette bomb refused")
        await srv.send({"op": "publish", "topic": "/t", "msg": {"n": 2}})
        await until(lambda: got == [{"n": 1}, {"n": 2}], what="the link goes on")
