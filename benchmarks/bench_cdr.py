"""cbor-raw decode speed: RCON's serializers (``rcon_core.msgs.cdr``, ``msgs.ros1_wire``) against rosbags'.

For each type one realistic message from the sim is serialized both ways, then decoded N times by:
``cdr`` (the client's ROS 2 path: a registry learned from typedefs), ``ros1`` (the client's ROS 1 path:
``bridge.rawdecode.RawDecoder``, a registry learned from typedefs decoding with ``msgs.ros1_wire``), and
rosbags' own ``deserialize_cdr`` / ``deserialize_ros1`` -- once as they are (dataclass objects, numpy
arrays) and once with the conversion to the dicts of the JSON wire shape that every RCON consumer takes
(``+dict``: nested dicts, lists, ``uint8[]`` as bytes, times as ``{secs, nsecs}`` / ``{sec, nanosec}``).
Prints CPU microseconds per message (best of 5 rounds).  Usage: ``python benchmarks/bench_cdr.py [--n 2000]``.
"""

from __future__ import annotations

import argparse
import asyncio
import time
from typing import Any

import numpy as np
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


def wire_dict(obj: Any, time_keys: tuple[str, str], store: Any) -> Any:
    """A rosbags message object -> the dict RCON's decoders give (the JSON wire shape)."""
    msgtype = getattr(obj, "__msgtype__", None)
    if msgtype is not None:
        if msgtype in ("builtin_interfaces/msg/Time", "builtin_interfaces/msg/Duration"):
            return {time_keys[0]: obj.sec, time_keys[1]: obj.nanosec}
        return {k: wire_dict(getattr(obj, k), time_keys, store) for k, _ in store.fielddefs[msgtype][1]}
    if isinstance(obj, np.ndarray):
        return obj.tobytes() if obj.dtype == np.uint8 else obj.tolist()
    if isinstance(obj, list):
        return [wire_dict(v, time_keys, store) for v in obj]
    return obj


def per_message(fn: Any, a: Any, b: Any, n: int, rounds: int = 5) -> float:
    """CPU time (``time.process_time``: steadier than wall time on a shared machine) per call, the best
    of ``rounds``."""
    fn(a, b)
    best = float("inf")
    for _ in range(rounds):
        start = time.process_time()
        for _ in range(n):
            fn(a, b)
        best = min(best, time.process_time() - start)
    return best / n * 1e6


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--n", type=int, default=2000)
    args = parser.parse_args()
    reg2, reg1 = TypeRegistry.standard(ros2=True), TypeRegistry.standard(ros2=False)
    store2, store1 = get_typestore(Stores.ROS2_HUMBLE), get_typestore(Stores.ROS1_NOETIC)
    print(f"{'topic':<26}{'bytes cdr/ros1':>16}{'cdr':>9}{'rosbags':>9}{'+dict':>9}"
          f"{'ros1':>9}{'rosbags':>9}{'+dict':>9}  (us/msg)")
    for topic, (type2, msg2, msg1) in asyncio.run(samples()).items():
        type1 = type2.replace("/msg/", "/")
        cdr = reg2.serialize_cdr(type2, msg2)
        ros1 = reg1.serialize_ros1(type1, msg1)
        client_cdr = CdrDecoder()
        client_cdr.add_typedefs(reg2.typedefs(type2))
        raw = RawDecoder()
        raw.add_typedefs(reg1.typedefs(type1))
        n = max(50, args.n // 20) if "image" in topic else args.n
        bags2 = lambda a, b: wire_dict(store2.deserialize_cdr(a, b), ("sec", "nanosec"), store2)  # noqa: E731
        bags1 = lambda a, b: wire_dict(store1.deserialize_ros1(a, b), ("secs", "nsecs"), store1)  # noqa: E731
        row = [per_message(client_cdr.decode, type2, cdr, n),
               per_message(store2.deserialize_cdr, cdr, type2, n),
               per_message(bags2, cdr, type2, n),
               per_message(raw.decode, type1, ros1, n),
               per_message(store1.deserialize_ros1, ros1, type2, n),
               per_message(bags1, ros1, type2, n)]
        print(f"{topic:<26}{len(cdr):>8}/{len(ros1):<7}" + "".join(f"{v:>9.1f}" for v in row))

if __name__ == "__main__":
    main()
