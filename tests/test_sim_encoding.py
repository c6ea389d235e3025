"""The sim's encodings: long byte strings spliced into CBOR after encoding give exactly cbor2's bytes, and bytes
that bring their base64 text encode as plain bytes do."""

from __future__ import annotations

import base64

import cbor2
import numpy as np
import pytest

from rcon_core.sim import encoding
from rcon_core.sim.encoding import SPLICE_MIN, cbor_dumps


def plain(obj: object) -> bytes:
    return cbor2.dumps(obj, default=encoding.cbor_default)


def pixels(n: int, seed: int = 0) -> bytes:
    return np.random.default_rng(seed).integers(0, 256, n, dtype=np.uint8).tobytes()


@pytest.mark.parametrize("n", [SPLICE_MIN - 1, SPLICE_MIN, 0xFFFF, 0x10000, 640 * 480 * 3])
def test_an_image_message_encodes_as_cbor2_does(n: int) -> None:
    msg = {"header": {"seq": 3, "stamp": {"secs": 1, "nsecs": 2}, "frame_id": "camera"}, "height": 1,
           "width": n // 3, "encoding": "rgb8", "is_bigendian": 0, "step": n, "data": pixels(n)}
    frame = encoding.publish_frame("/camera/front/image_raw", msg)
    out = cbor_dumps(frame)
    assert out == plain(frame)
    assert cbor2.loads(out)["msg"]["data"] == msg["data"]


def test_several_long_byte_strings_at_any_depth_and_in_arrays_of_messages() -> None:
    """The ones in reach are spliced, deeper ones left to cbor2: the same bytes either way."""
    msg = {"images": [{"data": pixels(SPLICE_MIN, 1), "format": "jpeg"}, {"data": b"short", "format": "png"},
                      {"data": bytearray(pixels(SPLICE_MIN * 3, 2)), "format": "jpeg"}],
           "raw": {"bytes": pixels(100_000, 3)}, "ranges": np.arange(5, dtype=np.float32), "numbers": [1, 2.5],
           "tuple": ({"data": pixels(SPLICE_MIN + 1, 4)},)}
    out = cbor_dumps(msg)
    assert out == plain(msg)
    back = cbor2.loads(out)
    assert back["images"][2]["data"] == bytes(msg["images"][2]["data"]) and back["raw"]["bytes"] == msg["raw"]["bytes"]


def test_the_message_itself_is_left_alone() -> None:
    data = pixels(SPLICE_MIN * 2)
    msg = {"msg": {"data": data, "items": [{"data": data}]}}
    cbor_dumps(msg)
    assert msg["msg"]["data"] is data and msg["msg"]["items"][0]["data"] is data


def test_a_byte_string_that_looks_like_the_placeholder_is_encoded_as_it_is() -> None:
    """Even a message holding the placeholder's own bytes comes out as cbor2 encodes it."""
    lookalike = encoding.SPLICE_TOKEN + (0).to_bytes(4, "big")
    msg = {"a": lookalike, "b": pixels(SPLICE_MIN), "c": lookalike}
    out = cbor_dumps(msg)
    assert out == plain(msg) and cbor2.loads(out)["c"] == lookalike


@pytest.mark.parametrize("n", [0, 5, SPLICE_MIN * 2])
def test_bytes_with_their_base64_encode_as_plain_bytes_do(n: int) -> None:
    data = pixels(n, 5)
    ahead = encoding.Base64Bytes.of(np.frombuffer(data, dtype=np.uint8))
    assert ahead == data and ahead.base64 == base64.b64encode(data).decode("ascii")
    for dumps in (encoding.dumps, cbor_dumps):
        assert dumps({"msg": {"data": ahead}}) == dumps({"msg": {"data": data}})
