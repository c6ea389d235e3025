"""cbor-raw decode speed: ROS 2 CDR (``rcon_core.msgs.cdr``) against the ROS 1 path, per message type.

For each type one realistic message from the sim is serialized both ways, then decoded N times by:
``cdr`` (the client's ROS 2 path: registry learned from typedefs), ``ros1-registry`` (the registry's
compiled ROS 1 decoder) and ``ros1-typedefs`` (the client's built-in typedef-driven ROS 1 decoder), plus
rosbags' own ``deserialize_cdr`` (to dataclasses) for scale.  Prints microseconds per message.
Usage: ``python benchmarks/bench_cdr.py [--n 2000]``.
"""

from __future__ import annotations

import argparse
import asyncio
import time
from typing import Any

from rosbags.typesys import Stores, get_typestore

from rcon_core.bridge.cdrdecode import CdrDecoder
from rcon_core.bridge.rawdecode import RawDecoder
from rcon_core.msgs import TypeRegistry
from rcon_core.sim import SimServer

TOPICS = ["/imu/data", "/odom", "/gps/fix", "/scan", "/battery", "/camera/front/image_raw"]


async def samples() -> dict[str, tuple[str, dict[str, Any], dict[str, Any]]]:
    """topic -> (ROS 2 type, ROS 2 message, ROS 1 message) taken from the two sims."""
    out: dict[str, Any] = {}
    for ros2 in (True, False):
        async with SimServer(ros2=ros2, rate_scale=5.0) as sim:
            got: dict[str, Any] = {}
            for topic in TOPICS:
                sim.subscribe_internal(topic, sim.topics[topic].type, "/bench",
                                       lambda m, t=topic, box=got: box.setdefault(t, m))
            for _ in range(100):
                if len(got) == len(TOPICS):
                    break
                await asyncio.sleep(0.05)
            for topic, msg in got.items():
                entry = out.setdefault(topic, [sim.topics[topic].type if ros2 else None, None, None])
                entry[1 if ros2 else 2] = msg
    return {t: tuple(v) for t, v in out.items()}


def per_message(fn: Any, a: Any, b: Any, n: int) -> float:
    fn(a, b)
    start = time.perf_counter()
    for _ in range(n):
        fn(a, b)
    return (time.perf_counter() - start) / n * 1e6


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--n", type=int, default=2000)
    args = parser.parse_args()
    reg2, reg1 = TypeRegistry.standard(ros2=True), TypeRegistry.standard(ros2=False)
    store = get_typestore(Stores.ROS2_HUMBLE)
    print(f"{'topic':<26}{'bytes cdr/ros1':>16}{'cdr':>9}{'ros1-reg':>10}{'ros1-td':>9}{'rosbags':>9}  (us/msg)")
    for topic, (type2, msg2, msg1) in asyncio.run(samples()).items():
        type1 = type2.replace("/msg/", "/")
        cdr = reg2.serialize_cdr(type2, msg2)
        ros1 = reg1.serialize_ros1(type1, msg1)
        client_cdr = CdrDecoder()
        client_cdr.add_typedefs(reg2.typedefs(type2))
        raw = RawDecoder()
        raw.add_typedefs(reg1.typedefs(type1))
        n = max(50, args.n // 20) if "image" in topic else args.n
        row = [per_message(client_cdr.decode, type2, cdr, n),
               per_message(reg1.deserialize_ros1, type1, ros1, n),
               per_message(raw.decode, type1, ros1, n),
               per_message(store.deserialize_cdr, cdr, type2, n)]
        print(f"{topic:<26}{len(cdr):>8}/{len(ros1):<7}" + "".join(f"{v:>9.1f}" for v in row))


if __name__ == "__main__":
    main()
