"""issue 22.12: a 2 KB rosapi answer nested 1000 deep raised RecursionError in the library (the JSON text of
a parameter's value, parsed by the standard parser; ``str()`` of a nested answer in ``detect_ros``) and a
traceback in the CLI. Every service answer nested deeper than ``MAX_ANSWER_DEPTH`` now fails the call
with a sentence, JSON text inside an answer is bounded the same way, and the CLI says one line."""

from __future__ import annotations

import asyncio
import sys

import orjson
import pytest

from rcon_core.bridge import ServiceError
from rcon_core.bridge.safety import MAX_ANSWER_DEPTH, json_text_value, nested_deeper
from rcon_core.loopback import HostileServer
from rcon_core.testing import connected

DEEP_TEXT = "[" * 1000 + "]" * 1000  # 2 KB, 1000 levels (orjson parses it; the standard parser recurses)


def deep(levels: int) -> object:
    value: object = 0
    for _ in range(levels):
        value = [value]
    return value


def test_depth_is_measured_without_recursion():
    assert not nested_deeper({"a": [1, 2, {"b": "c"}]}, 3)
    assert nested_deeper({"a": [1, 2, {"b": [0]}]}, 3)
    assert nested_deeper(orjson.loads(DEEP_TEXT))
    assert not nested_deeper(list(range(1_000_000)))
    assert not nested_deeper(deep(MAX_ANSWER_DEPTH - 1)) and nested_deeper(deep(MAX_ANSWER_DEPTH + 1))
    with pytest.raises(ValueError, match="nested deeper"):
        json_text_value(DEEP_TEXT)
    with pytest.raises(ValueError, match="nested deeper"):
        json_text_value("[" * 150 + "]" * 150)
    assert json_text_value("[[1.5]]") == [[1.5]]


class DeepRosapi(HostileServer):
    """Answers every call: ``/rosapi/get_param`` with the 2 KB nested JSON text, anything else with values
    nested 1000 deep in every field."""

    async def answer(self) -> None:
        seen = 0
        while True:
            await self.wait(lambda done=seen: len(self.ops("call_service")) > done, timeout=1e9)
            for op in self.ops("call_service")[seen:]:
                if op["service"] == "/rosapi/get_param":
                    values = orjson.dumps({"value": DEEP_TEXT}).decode()
                else:
                    values = "{" + ",".join(f'"{k}":{DEEP_TEXT}' for k in ("topics", "types", "type", "version",
                                                                           "value")) + "}"
                ident, service = orjson.dumps(op["id"]).decode(), orjson.dumps(op["service"]).decode()
                await self.send(f'{{"op":"service_response","id":{ident},"service":{service},"result":true,'
                                f'"values":{values}}}')
            seen = len(self.ops("call_service"))


@pytest.fixture
async def deep_server():
    async with DeepRosapi() as srv:
        task = asyncio.ensure_future(srv.answer())
        yield srv
        task.cancel()


async def test_the_library_says_a_sentence_instead_of_recursing(deep_server):
    async with connected(deep_server.url, call_timeout=5) as client:
        with pytest.raises(ServiceError, match="nested deeper than 100 levels"):
            await client.rosapi.get_param("/rosdistro")
        with pytest.raises(ServiceError, match="nested deeper than 100 levels"):
            await client.rosapi.topics()
        with pytest.raises(ServiceError, match="nested deeper than 100 levels"):
            await client.call_service("/any", {})
        info = await client.detect_ros()  # asks several rosapi services: none of them may raise
        assert info.version is None
        assert client.stats["bad_frames"] >= 3


@pytest.mark.parametrize("argv", [["call", "/any"], ["topics"], ["services"], ["echo", "/t", "-n", "1",
                                                                              "--type", "std_msgs/String",
                                                                              "--timeout", "3"]])
async def test_the_cli_prints_one_line_not_a_traceback(deep_server, argv):
    proc = await asyncio.create_subprocess_exec(
        sys.executable, "-m", "rcon_core", *argv, "--url", deep_server.url,
        stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.PIPE)
    if argv[0] == "echo":
        await deep_server.wait_for("subscribe", topic="/t", timeout=20)
        await deep_server.send('{"op":"publish","topic":"/t","msg":{"data":%s}}' % ("[" * 300 + "]" * 300))
    out, err = await asyncio.wait_for(proc.communicate(), 60)
    text = err.decode()
    assert proc.returncode == 1, (out, text)
    assert "Traceback" not in text and "RecursionError" not in text
    assert text.startswith("rcon: ") and ("nested deeper" in text or "could not be printed" in text), text
