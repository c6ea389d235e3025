"""``rcon sim``: run the embedded simulated robot as a rosbridge v2 server until interrupted; with
``--protocol foxglove`` the same vessel is served over the Foxglove WebSocket protocol (through
foxglove-sdk: ``rcon_core/foxglove/gateway.py``), its rosbridge port then on loopback only.  ``--play FILE``
serves a recording instead (``sim/playback.py``), over either protocol.

With ``--auth`` it requires a rosauth ``auth`` op signed with the secret in ``RCON_AUTH_SECRET``, or in the
file ``--auth-secret-file`` names (its first line), as the client reads it: never from the command line,
where every user of the machine sees it (``ps``).
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import ipaddress
import logging
import signal
import ssl
import sys
from typing import Any

OPEN_WARNING = """\
rcon sim: WARNING: listening on {host} without --auth.
rcon sim: WARNING: anyone who can reach this address can drive the simulated robot and read everything;
rcon sim: WARNING: add --auth (the secret in RCON_AUTH_SECRET or --auth-secret-file) and --tls-cert/--tls-key,
rcon sim: WARNING: or listen on 127.0.0.1 only."""
SECRET_ON_COMMAND_LINE = """\
rcon sim: --auth takes no secret on the command line: every user of this machine could read it in the
rcon sim: process list. Put it in RCON_AUTH_SECRET, or in a file given with --auth-secret-file PATH."""


def configure(name: str, parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--host", default="127.0.0.1", help="address to listen on (default 127.0.0.1)")
    parser.add_argument("--port", type=int, default=9090, help="port to listen on (default 9090; 0 = any free)")
    parser.add_argument("--name", metavar="NAME",
                        help="the robot's name, one vessel of a fleet: its topics, services and node move under "
                        "/NAME (/NAME/cmd_vel, /NAME/gps/fix), and it gets its own start position and camera "
                        "scene; without it the sim is the one unnamed robot")
    parser.add_argument("--no-namespace", action="store_true",
                        help="with --name: keep the plain topic names (/cmd_vel), as a robot behind its own "
                        "rosbridge has them; only the start position and the camera scene change")
    parser.add_argument("--ros2", action="store_true",
                        help="answer as rosbridge 2.x on ROS 2: pkg/msg/Type, sec/nanosec, rosapi_msgs, "
                        "<node>:<param> parameters, actions, CDR cbor-raw")
    parser.add_argument("--rate-scale", type=float, default=1.0, metavar="X",
                        help="multiply every publish rate by X (default 1.0)")
    parser.add_argument("--auth", nargs="?", const="", default=None, metavar="",
                        help="require a rosauth 'auth' op signed with the secret in $RCON_AUTH_SECRET (or in "
                        "--auth-secret-file); never on the command line")
    parser.add_argument("--auth-secret-file", metavar="PATH",
                        help="require a rosauth 'auth' op signed with the secret in this file (its first line)")
    parser.add_argument("--max-frame", type=float, default=32.0, metavar="MB",
                        help="largest message a client may send, in MB (default 32)")
    parser.add_argument("--no-plugin-types", action="store_true",
                        help="do not load the message types installed widget plugins contribute (the sim then "
                        "refuses them, like a robot without the lab's package)")
    parser.add_argument("--video-bitrate", type=float, metavar="KBIT", default=None,
                        help="the front camera's H.264 stream (/camera/front/image_raw/foxglove and /ffmpeg): "
                        "bits per second asked of the encoder, in kbit/s (default 600)")
    parser.add_argument("--video-keyframe-interval", type=float, metavar="S", default=None,
                        help="seconds between the H.264 stream's keyframes: what a viewer joining mid-stream "
                        "waits at most (default 1)")
    parser.add_argument("--tls-cert", metavar="FILE", help="serve wss:// with this certificate (PEM)")
    parser.add_argument("--tls-key", metavar="FILE", help="the certificate's private key (PEM)")
    parser.add_argument("--protocol", choices=("rosbridge", "foxglove"), default="rosbridge",
                        help="serve rosbridge v2 (the default) or the Foxglove WebSocket protocol (Foxglove, "
                        "Lichtblick and RCON open it; no rosauth on that protocol)")
    parser.add_argument("-v", "--verbose", action="store_true", help="log every client op")
    play = parser.add_argument_group("a recording as the robot (sim/playback.py)")
    play.add_argument("--play", metavar="FILE",
                      help="serve this recording as the robot instead of the simulated vessel: an .mcap file, a "
                      "rosbag1 .bag or a rosbag2 folder; ROS 1 or 2 as the file is (--ros2 forces ROS 2)")
    play.add_argument("--rate", type=float, default=1.0, metavar="X", help="with --play: play X times as fast")
    play.add_argument("--loop", action="store_true", help="with --play: start again at the end")
    play.add_argument("--start", type=float, default=0.0, metavar="S", help="with --play: begin S seconds in")


def run(name: str, args: argparse.Namespace) -> int:
    if args.rate_scale <= 0:
        print(f"rcon sim: --rate-scale must be positive, got {args.rate_scale}")
        return 2
    if not 0.001 <= args.max_frame <= 2048:
        print(f"rcon sim: --max-frame must be between 0.001 and 2048 MB, got {args.max_frame:g}")
        return 2
    if not 0 <= args.port <= 65535:
        print(f"rcon sim: --port must be between 0 and 65535, got {args.port}")
        return 2
    if args.play is None and (args.rate != 1.0 or args.loop or args.start):
        print("rcon sim: --rate, --loop and --start go with --play FILE", file=sys.stderr)
        return 2
    if not args.rate > 0 or args.start < 0:
        print("rcon sim: --rate must be positive and --start not negative", file=sys.stderr)
        return 2
    if args.no_namespace and args.name is None:
        print("rcon sim: --no-namespace goes with --name", file=sys.stderr)
        return 2
    if args.name is not None:
        from rcon_core.sim.identity import check_name

        try:
            check_name(args.name)
        except ValueError as exc:
            print(f"rcon sim: --name: {exc}", file=sys.stderr)
            return 2
    video = _video_params(args)
    if isinstance(video, str):
        print(f"rcon sim: {video}", file=sys.stderr)
        return 2
    args.video_params = video
    if bool(args.tls_cert) != bool(args.tls_key):
        print("rcon sim: --tls-cert and --tls-key go together", file=sys.stderr)
        return 2
    if args.auth:  # a value after --auth: the secret on the command line
        print(SECRET_ON_COMMAND_LINE, file=sys.stderr)
        return 2
    try:
        secret = _secret(args)
    except ValueError as exc:
        print(f"rcon sim: {exc}", file=sys.stderr)
        return 2
    try:
        tls = _tls_context(args.tls_cert, args.tls_key) if args.tls_cert else None
    except (OSError, ssl.SSLError) as exc:
        print(f"rcon sim: cannot use {args.tls_cert} / {args.tls_key}: {exc}", file=sys.stderr)
        return 2
    if getattr(args, "protocol", "rosbridge") == "foxglove" and secret is not None:
        print("rcon sim: --auth: the Foxglove WebSocket protocol has no rosauth; use --tls-cert/--tls-key and "
              "listen on a network you trust", file=sys.stderr)
        return 2
    if not _loopback(args.host) and secret is None:
        print(OPEN_WARNING.format(host=args.host), file=sys.stderr, flush=True)
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING,
                        format="%(asctime)s %(levelname)s %(name)s: %(message)s")
    try:
        return asyncio.run(_serve(args, tls, secret))
    except KeyboardInterrupt:
        return 0


def _secret(args: argparse.Namespace) -> str | None:
    """The secret ``--auth``/``--auth-secret-file`` ask for, None without them; ValueError says what is
    missing or cannot be read."""
    if args.auth is None and not args.auth_secret_file:
        return None
    from rcon_core.bridge.errors import LinkSettingsError
    from rcon_core.bridge.secure import AUTH_ENV, read_secret

    try:
        secret = read_secret(args.auth_secret_file)
    except LinkSettingsError as exc:
        raise ValueError(str(exc)) from None
    if not secret:
        raise ValueError(f"--auth needs the secret: put it in {AUTH_ENV}, or in a file given with --auth-secret-file")
    return secret


def _video_params(args: argparse.Namespace) -> dict[str, float] | str:
    """The robot node's ``video/*`` parameters the options ask for, or what is wrong with them."""
    from rcon_core.sim.video import VideoSettings

    params: dict[str, float] = {}
    if args.video_bitrate is not None:
        params["bitrate"] = int(args.video_bitrate * 1000)
    if args.video_keyframe_interval is not None:
        params["keyframe_interval"] = args.video_keyframe_interval
    base = VideoSettings()
    settings = VideoSettings(keyframe_interval=params.get("keyframe_interval", base.keyframe_interval),
                             bitrate=int(params.get("bitrate", base.bitrate)))
    problems = settings.problems()
    return "; ".join(problems) if problems else params


def _loopback(host: str) -> bool:
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def _tls_context(cert: str, key: str) -> ssl.SSLContext:
    ctx = ssl.SSLContext(ssl.PROTOCOL_TLS_SERVER)
    ctx.load_cert_chain(cert, key)
    return ctx


async def _serve(args: argparse.Namespace, tls: ssl.SSLContext | None = None, secret: str | None = None) -> int:
    from rcon_core.sim import SimServer

    recording = None
    if args.play is not None:
        from rcon_core.record.files import RecordingError, open_recording

        try:
            recording = open_recording(args.play)
        except RecordingError as exc:
            print(f"rcon sim: cannot play {exc}", file=sys.stderr)
            return 2
    foxglove = getattr(args, "protocol", "rosbridge") == "foxglove"
    # over Foxglove the sim's own rosbridge port stays on loopback, behind the gateway (foxglove/gateway.py)
    server = SimServer(host="127.0.0.1" if foxglove else args.host, port=0 if foxglove else args.port,
                       ros2=args.ros2 or bool(recording and recording.ros2), rate_scale=args.rate_scale,
                       auth_secret=secret, max_frame=int(args.max_frame * 1024 * 1024),
                       plugin_types=not args.no_plugin_types, ssl=None if foxglove else tls, name=args.name,
                       namespace=not args.no_namespace, robot=recording is None)
    try:
        await server.start()
    except OSError as exc:
        print(f"rcon sim: cannot listen on {args.host}:{args.port}: {exc.strerror or exc}")
        return 1
    video = getattr(server.robot_node, "video", None)
    if video is not None:
        if video.unavailable:
            print(f"rcon sim: no video: {video.unavailable}", flush=True)
        for key, value in getattr(args, "video_params", {}).items():  # checked in run()
            server.params_tree.set(f"{server.robot_node.node}/video/{key}", value)
    if recording is not None:
        return await _play(server, recording, args, _gateway_options(args) if foxglove else None)
    flavour = "ROS 2" if args.ros2 else "ROS 1"
    ns = server.identity.namespace
    who = f"Kingfisher '{server.name}'" + (f" (topics under {ns})" if ns else "") if server.name else "Kingfisher"
    gateway = None
    if foxglove:
        from rcon_core.foxglove.gateway import FoxgloveGateway

        gateway = FoxgloveGateway(server.url, name=server.name or "rcon-sim", **_gateway_options(args))
        try:
            await asyncio.to_thread(gateway.start)
        except Exception as exc:
            print(f"rcon sim: cannot serve the Foxglove protocol on {args.host}:{args.port}: {exc}")
            await server.stop()
            return 1
        print(f"rcon sim: {flavour} {who} simulator over the Foxglove WebSocket protocol on {gateway.url} "
              "(Ctrl+C to stop)", flush=True)
    else:
        print(f"rcon sim: {flavour} {who} simulator on {server.url} (Ctrl+C to stop)", flush=True)
    if server.types.plugin_type_names:
        print(f"rcon sim: plugin types: {', '.join(server.types.plugin_type_names)}", flush=True)
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    for sig in (signal.SIGINT, signal.SIGTERM):
        with contextlib.suppress(NotImplementedError, RuntimeError):
            loop.add_signal_handler(sig, stop.set)
    from rcon_core.gcpolicy import keep_settled
    from rcon_core.mallocpolicy import keep_big_blocks
    from rcon_core.priority import favour_latency

    favour_latency()  # the loop that receives commands raised, the GIL's switch interval short (priority.py)
    keep_big_blocks()  # camera frames' pages kept from one frame to the next (mallocpolicy.py)
    settler = asyncio.create_task(keep_settled())  # the collector's pauses kept short (gcpolicy.py)
    try:
        await stop.wait()
    finally:
        settler.cancel()
        if gateway is not None:
            await asyncio.to_thread(gateway.stop)
        await server.stop()
    return 0



def _gateway_options(args: argparse.Namespace) -> dict[str, Any]:
    """Where the Foxglove gateway listens (the sim's own rosbridge port is then on loopback behind it)."""
    pem = None
    if args.tls_cert:
        with open(args.tls_cert, "rb") as cert, open(args.tls_key, "rb") as key:
            pem = (cert.read(), key.read())
    return {"host": args.host, "port": args.port, "tls": pem}


async def _play(server: Any, recording: Any, args: argparse.Namespace,
                foxglove: dict[str, Any] | None = None) -> int:
    """Serve ``recording`` as the robot until interrupted (``sim/playback.py``); with ``foxglove`` (the
    gateway's options) over the Foxglove protocol, the player's bare sim on loopback behind the gateway,
    the server time the recording's."""
    from rcon_core.sim.playback import Player

    player = Player(server, recording, rate=args.rate, loop=args.loop, start=args.start)
    player.install()
    flavour = "ROS 2" if server.ros2 else "ROS 1"
    url, over = server.url, ""
    gateway = None
    if foxglove is not None:
        from rcon_core.foxglove.gateway import FoxgloveGateway

        gateway = FoxgloveGateway(server.url, name="rcon-player", clock=lambda: recording.start_ns + player.position_ns,
                                  **foxglove)
        try:
            await asyncio.to_thread(gateway.start)
        except Exception as exc:
            print(f"rcon sim: cannot serve the Foxglove protocol on {args.host}:{args.port}: {exc}")
            await player.stop()
            await server.stop()
            recording.close()
            return 1
        url, over = gateway.url, " over the Foxglove WebSocket protocol"
    print(f"rcon sim: playing {recording.path} ({recording.kind}, {flavour}, {len(recording.tracks)} topics, "
          f"{recording.message_count} messages, {recording.duration:.1f} s){over} on {url} at {args.rate:g}x"
          f"{' in a loop' if args.loop else ''} (Ctrl+C to stop)", flush=True)
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    for sig in (signal.SIGINT, signal.SIGTERM):
        with contextlib.suppress(NotImplementedError, RuntimeError):
            loop.add_signal_handler(sig, stop.set)
    try:
        await stop.wait()
    finally:
        if gateway is not None:
            await asyncio.to_thread(gateway.stop)
        await player.stop()
        await server.stop()
        recording.close()
    if player.absorbed:
        print(f"rcon sim: absorbed (sent nowhere): {dict(player.absorbed)}", flush=True)
    return 0
