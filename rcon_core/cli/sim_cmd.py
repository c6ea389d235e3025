"""``rcon sim``: run the embedded simulated robot as a rosbridge v2 server until interrupted."""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import logging
import signal


def configure(name: str, parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--host", default="127.0.0.1", help="address to listen on (default 127.0.0.1)")
    parser.add_argument("--port", type=int, default=9090, help="port to listen on (default 9090; 0 = any free)")
    parser.add_argument("--ros2", action="store_true",
                        help="answer as rosbridge 2.x on ROS 2: pkg/msg/Type, sec/nanosec, rosapi_msgs, "
                        "<node>:<param> parameters, actions, CDR cbor-raw")
    parser.add_argument("--rate-scale", type=float, default=1.0, metavar="X",
                        help="multiply every publish rate by X (default 1.0)")
    parser.add_argument("--auth", metavar="SECRET", help="require a rosauth 'auth' op signed with SECRET")
    parser.add_argument("-v", "--verbose", action="store_true", help="log every client op")


def run(name: str, args: argparse.Namespace) -> int:
    if args.rate_scale <= 0:
        print(f"rcon sim: --rate-scale must be positive, got {args.rate_scale}")
        return 2
    if not 0 <= args.port <= 65535:
        print(f"rcon sim: --port must be between 0 and 65535, got {args.port}")
        return 2
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING,
                        format="%(asctime)s %(levelname)s %(name)s: %(message)s")
    try:
        return asyncio.run(_serve(args))
    except KeyboardInterrupt:
        return 0


async def _serve(args: argparse.Namespace) -> int:
    from rcon_core.sim import SimServer

    server = SimServer(host=args.host, port=args.port, ros2=args.ros2, rate_scale=args.rate_scale,
                       auth_secret=args.auth)
    try:
        await server.start()
    except OSError as exc:
        print(f"rcon sim: cannot listen on {args.host}:{args.port}: {exc.strerror or exc}")
        return 1
    flavour = "ROS 2" if args.ros2 else "ROS 1"
    print(f"rcon sim: {flavour} Kingfisher simulator on {server.url} (Ctrl+C to stop)", flush=True)
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    for sig in (signal.SIGINT, signal.SIGTERM):
        with contextlib.suppress(NotImplementedError, RuntimeError):
            loop.add_signal_handler(sig, stop.set)
    try:
        await stop.wait()
    finally:
        await server.stop()
    return 0
