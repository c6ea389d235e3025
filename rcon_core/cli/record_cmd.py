"""``rcon record``: record a robot's topics to an MCAP file; ``rcon record --recover`` mends a cut one.

    rcon record -o run.mcap [TOPIC ...|--all] [--exclude RE] [--duration S] [--split-size MB] [--url URL]

Raw bytes (``cbor-raw``) and the robot's own definitions where it offers them (``record/ingest.py``),
profile ``ros1`` or ``ros2`` from the robot; a Foxglove robot (detected, or ``--protocol foxglove``) is
recorded with each channel's own schema and encoding and the payloads unchanged
(``record/foxglove_source.py``). Progress on stderr (topics, messages, MB, rate) about once
a second; Ctrl-C or SIGTERM closes the file properly (summary and footer). The link reconnects on its
own while recording; each change is written on ``/rcon/link``. Exit status: 0 when the file was closed
properly, 1 when the robot could not be reached or the recording stopped on an error (said on stderr).
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import re
import signal
import sys
import time
from typing import Any

DEFAULT_URL = "ws://localhost:9090"


def configure(name: str, parser: argparse.ArgumentParser) -> None:
    from rcon_core.cli.link_options import add_link_options

    parser.add_argument("topics", nargs="*", metavar="TOPIC", help="topics to record (or --all)")
    parser.add_argument("-o", "--output", metavar="FILE", help="the MCAP file to write (run.mcap)")
    parser.add_argument("--all", action="store_true", help="record every topic the robot has (and new ones)")
    parser.add_argument("--exclude", metavar="RE", help="with --all: leave out topics matching this regex")
    parser.add_argument("--duration", type=float, metavar="S", help="stop after S seconds")
    parser.add_argument("--split-size", type=float, metavar="MB", help="start a new file after MB megabytes")
    parser.add_argument("--budget", type=float, metavar="MB",
                        help="stop (closing the file properly) when the recording reaches MB megabytes")
    parser.add_argument("--compression", choices=("zstd", "lz4", "none"), default="zstd",
                        help="chunk compression (default zstd)")
    parser.add_argument("--url", dest="bridge_url", metavar="URL",
                        help=f"the robot's URL, rosbridge or Foxglove (default {DEFAULT_URL})")
    parser.add_argument("--recover", metavar="FILE",
                        help="instead of recording: rewrite FILE, cut short by a crash, with every complete "
                        "chunk and a summary, to -o (default FILE-recovered.mcap)")
    parser.add_argument("-q", "--quiet", action="store_true", help="no progress lines")
    add_link_options(parser)


def run(name: str, args: argparse.Namespace) -> int:
    if args.recover:
        return _recover(args)
    if not args.output:
        print("rcon record: say where to write: -o FILE.mcap", file=sys.stderr)
        return 2
    if not args.topics and not args.all:
        print("rcon record: name the topics to record, or --all", file=sys.stderr)
        return 2
    if args.exclude:
        try:
            re.compile(args.exclude)
        except re.error as exc:
            print(f"rcon record: --exclude is not a regular expression: {exc}", file=sys.stderr)
            return 2
    for opt in ("duration", "split_size", "budget"):
        value = getattr(args, opt)
        if value is not None and not value > 0:
            print(f"rcon record: --{opt.replace('_', '-')} must be positive, got {value:g}", file=sys.stderr)
            return 2
    url = args.bridge_url or getattr(args, "url", None) or DEFAULT_URL
    if not url.startswith(("ws://", "wss://")):
        print(f"rcon record: --url must be a ws:// or wss:// URL, got {url!r}", file=sys.stderr)
        return 2
    from rcon_core.mallocpolicy import keep_big_blocks

    keep_big_blocks()  # a camera frame's pages kept for the next one (mallocpolicy.py)
    try:
        return asyncio.run(_record(url, args))
    except KeyboardInterrupt:
        return 0


def _recover(args: argparse.Namespace) -> int:
    from rcon_core.record.recover import recover

    out = args.output or re.sub(r"(\.mcap)?$", "-recovered.mcap", args.recover, count=1)
    try:
        report = recover(args.recover, out)
    except (OSError, ValueError) as exc:
        print(f"rcon record: cannot recover {args.recover}: {exc}", file=sys.stderr)
        return 1
    print(f"rcon record: {report}", file=sys.stderr)
    return 0


async def _connect(url: str, args: argparse.Namespace) -> Any:
    from rcon_core.bridge import LinkSettingsError
    from rcon_core.bridge.reasons import describe
    from rcon_core.cli.link_options import link_settings
    from rcon_core.link import detect, make_client

    try:
        settings = link_settings(args, url)
        protocol = getattr(args, "protocol", None)
        if protocol is None:  # rosbridge or Foxglove, from the server's answer (rcon_core/link/detect.py)
            protocol = await asyncio.wait_for(detect(url, ca_file=settings["ca_file"], client_cert=settings[
                "client_cert"], client_key=settings["client_key"]), 10.0)
        client = make_client(url, str(protocol), reconnect=True, **settings)
    except (LinkSettingsError, ValueError) as exc:
        print(f"rcon record: {exc}", file=sys.stderr)
        return None
    except Exception as exc:  # noqa: BLE001 - the handshake failed: said as any connection failure
        print(f"rcon record: cannot connect to {url}: {describe(exc).reason}", file=sys.stderr)
        return None
    try:
        await asyncio.wait_for(client.connect(), 10.0)
    except Exception as exc:  # noqa: BLE001
        await client.close()
        print(f"rcon record: cannot connect to {url}: {describe(exc).reason}", file=sys.stderr)
        return None
    return client


async def _record(url: str, args: argparse.Namespace) -> int:
    from rcon_core.record.foxglove_source import is_foxglove, recorder_for, wait_profile
    from rcon_core.record.writer import McapSink

    client = await _connect(url, args)
    if client is None:
        return 1
    if is_foxglove(client):  # the channels' own encodings say (record/foxglove_source.py)
        profile = await wait_profile(client, None if args.all else list(args.topics))
    else:
        try:
            info = await client.detect_ros()
            profile = "ros2" if info.version == 2 else "ros1"
        except Exception:  # noqa: BLE001 - the typedefs will tell per topic; ROS 1 is the default profile
            profile = "ros1"
    mb = 1_000_000
    try:
        sink = McapSink(args.output, profile, compression=args.compression,
                        split_size=int(args.split_size * mb) if args.split_size else None,
                        budget=int(args.budget * mb) if args.budget else None,
                        metadata={"url": url, "recorder": "rcon record", "started": time.strftime("%FT%T%z")})
    except OSError as exc:
        await client.close()
        print(f"rcon record: cannot write {args.output}: {exc.strerror or exc}", file=sys.stderr)
        return 1
    recorder = recorder_for(client, sink, ros2=profile == "ros2", robot=url, topics=list(args.topics),
                            all_topics=args.all, exclude=args.exclude, operator=False)
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    for sig in (signal.SIGINT, signal.SIGTERM):
        with contextlib.suppress(NotImplementedError, RuntimeError):
            loop.add_signal_handler(sig, stop.set)
    said = 0
    try:
        await recorder.start()
        started = time.monotonic()
        deadline = started + args.duration if args.duration else None
        last = (started, 0, 0)
        while not stop.is_set():
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(stop.wait(), 1.0)
            for text in recorder.problems[said:]:
                print(f"rcon record: {text}", file=sys.stderr)
            said = len(recorder.problems)
            now = time.monotonic()
            st = sink.stats
            if not args.quiet:
                dt = max(1e-6, now - last[0])
                rate = (st.messages - last[1]) / dt
                mbps = (st.bytes_in - last[2]) / dt / mb
                print(f"\rrecording {len(recorder.topics)} topics  {st.messages} msgs  {sink.size / mb:.1f} MB  "
                      f"{rate:.0f} msg/s  {mbps:.1f} MB/s  {now - started:.0f} s", end="", file=sys.stderr,
                      flush=True)
            last = (now, st.messages, st.bytes_in)
            if sink.stopped or (deadline is not None and now >= deadline):
                break
    finally:
        recorder.stop()
        await loop.run_in_executor(None, sink.close)
        await client.close()
    st = sink.stats
    if not args.quiet:
        print(file=sys.stderr)
    files = ", ".join(st.files)
    print(f"rcon record: {st.messages} messages on {len(st.per_topic)} topics, {sink.size / mb:.1f} MB in "
          f"{files}" + (f"; {st.dropped} dropped" if st.dropped else ""), file=sys.stderr)
    if sink.problem:
        print(f"rcon record: {sink.problem}", file=sys.stderr)
        return 1 if "budget" not in sink.problem else 0
    return 0
