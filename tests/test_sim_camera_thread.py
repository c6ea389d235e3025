"""The sim draws camera frames off its event loop, so a command is never held up behind a picture."""

from __future__ import annotations

import asyncio
import json
import threading

import websockets

from rcon_core.sim import SimServer


async def test_camera_frames_are_drawn_off_the_loop_and_still_arrive_in_order() -> None:
    async with SimServer(rate_scale=2.0) as sim:
        threads: list[threading.Thread] = []
        front = sim.robot_node.front
        draw = front.render

        def recording_render(vessel, stamp, use):  # noqa: ANN001, ANN202 - the renderer's own signature
            threads.append(threading.current_thread())
            return draw(vessel, stamp, use)

        front.render = recording_render
        async with websockets.connect(sim.url, max_size=None) as ws:
            await ws.send(json.dumps({"op": "subscribe", "topic": "/camera/front/image_raw"}))
            stamps = []
            while len(stamps) < 4:
                msg = json.loads(await asyncio.wait_for(ws.recv(), 10))
                if msg.get("topic") == "/camera/front/image_raw":
                    stamp = msg["msg"]["header"]["stamp"]
                    stamps.append(stamp["secs"] + stamp["nsecs"] / 1e9)
        assert threads and all(t is not threading.main_thread() for t in threads)
        assert all(t.name.startswith("sim-camera") for t in threads)
        assert stamps == sorted(stamps)
