"""``rcon topics|services|type|echo|pub|call``: the robot's graph and traffic from a terminal.

Every command takes ``--url`` (default ws://localhost:9090), ``--json``, ``--timeout`` (how long to wait
for the robot; ``echo`` waits for ever unless given one) and the secure-link options (``--ca-file``,
``--client-cert``/``--client-key``, ``--auth-secret-file`` or ``$RCON_AUTH_SECRET``).  Failures print one
line on stderr (the server's own message where it sent one) and exit non-zero: 1 for a failed call,
connection or refusal, 2 for bad input.  ``pub`` and ``echo`` of a type that is not standard first ask the
robot whether it knows it (rosbridge 0.11 refuses such a type only in its log; see
:mod:`rcon_core.bridge.typecheck`). ``pub --envelope [LAYOUT]`` holds what it publishes to a robot's safety
envelope saved in a workspace file (``--robot`` picks the robot): a motion command beyond it is clamped and
says so on stderr; NaN or infinity in one is refused (exit 1), with or without ``--envelope``.
"""

from __future__ import annotations

import argparse
import asyncio
import base64
import logging
import os
import sys
from typing import Any

import orjson

from rcon_core.cli.link_options import add_link_options, open_client
from rcon_core.cli.type_text import typedefs_text

DEFAULT_URL = "ws://localhost:9090"


def configure(name: str, parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--url", dest="bridge_url", metavar="URL",
                        help=f"rosbridge WebSocket URL (default {DEFAULT_URL})")
    parser.add_argument("--json", action="store_true", help="machine-readable JSON output")
    add_link_options(parser)
    if name == "type":
        parser.add_argument("type_name", metavar="TYPE", help="message or service type, e.g. sensor_msgs/Imu")
        parser.add_argument("--recursive", "-r", action="store_true",
                            help="write each nested type's fields out under its field, indented")
    elif name == "echo":
        parser.add_argument("topic", metavar="TOPIC")
        parser.add_argument("-n", type=int, default=0, metavar="N", help="exit after N messages (default: run)")
        parser.add_argument("--type", dest="msg_type", help="message type (default: ask the server)")
        parser.add_argument("--compression", default="none", choices=["none", "png", "cbor", "cbor-raw"])
        parser.add_argument("--throttle", type=int, default=0, metavar="MS", help="throttle_rate in ms")
    elif name == "pub":
        parser.add_argument("topic", metavar="TOPIC")
        parser.add_argument("msg_type", metavar="TYPE")
        parser.add_argument("msg", metavar="MSG", help="the message as YAML or JSON text, e.g. '{data: 1.5}'")
        parser.add_argument("--rate", type=float, metavar="HZ", help="publish repeatedly at this rate")
        parser.add_argument("--once", action="store_true", help="publish once and exit (the default without --rate)")
        parser.add_argument("--count", type=int, default=0, metavar="N", help="with --rate: stop after N messages")
        parser.add_argument("--latch", action="store_true", help="advertise the topic as latched")
        parser.add_argument("--envelope", nargs="?", const="", default=None, metavar="LAYOUT",
                            help="hold the message to a robot's safety envelope saved in a workspace file "
                                 "(default: the app's workspace); motion commands beyond it are clamped")
        parser.add_argument("--robot", metavar="ROBOT",
                            help="with --envelope: the robot (its name or id; default: the one whose URL is "
                                 "--url, else the first)")
    elif name == "call":
        parser.add_argument("service", metavar="SERVICE")
        parser.add_argument("args", nargs="?", default=None, metavar="ARGS",
                            help="request as YAML or JSON text, e.g. '{data: true}'")
        parser.add_argument("--timeout", type=float, default=10.0, metavar="S", help="seconds to wait (default 10)")
    if name == "echo":
        parser.add_argument("--timeout", type=float, default=None, metavar="S",
                            help="exit 1 when no message arrives for S seconds (default: wait for ever)")
    elif name != "call":
        parser.add_argument("--timeout", type=float, default=10.0, metavar="S",
                            help="seconds to wait for the robot's answers (default 10)")


def run(name: str, args: argparse.Namespace) -> int:
    url = getattr(args, "bridge_url", None) or getattr(args, "url", None) or DEFAULT_URL
    if not url.startswith(("ws://", "wss://")):
        _err(f"--url must be a ws:// or wss:// URL, got {url!r}")
        return 2
    timeout = getattr(args, "timeout", None)
    if timeout is not None and not timeout > 0:
        _err(f"--timeout must be a positive number of seconds, got {timeout}")
        return 2
    # the command prints its own one-line errors; the bridge's log lines would repeat them
    logging.getLogger("rcon_core.bridge").addHandler(logging.NullHandler())
    handler = {"topics": _topics, "services": _services, "type": _type, "echo": _echo, "pub": _pub,
               "call": _call}[name]
    try:
        return asyncio.run(handler(url, args))
    except KeyboardInterrupt:
        return 0
    except BrokenPipeError:  # the reader went away (`| head`): the entry point stops quietly (main.py)
        raise
    except Exception as exc:  # the boundary: an answer the command could not use is one line, not a traceback
        from rcon_core.bridge.safety import safe_text

        _err(f"the robot's answer could not be used: {safe_text(exc)}")
        return 1


# ---------------------------------------------------------------------------------------------- helpers


def _err(text: str) -> None:
    print(f"rcon: {text}", file=sys.stderr)


def _default(value: Any) -> Any:
    if isinstance(value, bytes | bytearray | memoryview):
        return base64.b64encode(bytes(value)).decode()
    if hasattr(value, "tolist"):
        return value.tolist()
    raise TypeError(f"cannot print {type(value).__name__}")


def _json(value: Any, indent: bool = False) -> str:
    opts = orjson.OPT_SERIALIZE_NUMPY | (orjson.OPT_INDENT_2 if indent else 0)
    return orjson.dumps(value, default=_default, option=opts).decode()


async def _connect(url: str, args: argparse.Namespace) -> Any:
    """A connected client, or None after one line saying why not (see ``link_options.open_client``)."""
    return await open_client(url, args, call_timeout=10.0)


def _table(rows: dict[str, str]) -> None:
    width = max((len(k) for k in rows), default=0)
    for k in sorted(rows):
        print(f"{k:<{width}}  {rows[k]}")


def _registry() -> Any:
    """The standard types plus those installed widget plugins contribute (a lab's own lab_msgs)."""
    from rcon_core.plugins import PluginManager

    pm = PluginManager()
    pm.load_entry_points()
    return pm.type_registry()


def _yaml(value: Any) -> str:
    import yaml

    return str(yaml.safe_dump(orjson.loads(_json(value)), sort_keys=False, allow_unicode=True))


def _parse_text(text: str) -> Any:
    from rcon_core.msgs.text import parse_text  # YAML whose keys stay text: {on: true} is the field "on"

    return parse_text(text)


# ---------------------------------------------------------------------------------------------- commands


async def _topics(url: str, args: argparse.Namespace) -> int:
    return await _listing(url, args, lambda rosapi: rosapi.topics())


async def _services(url: str, args: argparse.Namespace) -> int:
    return await _listing(url, args, lambda rosapi: rosapi.services_with_types())


async def _listing(url: str, args: argparse.Namespace, fetch: Any) -> int:
    """Print what ``fetch(client.rosapi)`` returns ([(name, type)...]) as a table, or JSON with --json."""
    from rcon_core.bridge import ServiceError

    client = await _connect(url, args)
    if client is None:
        return 1
    try:
        rows = await asyncio.wait_for(fetch(client.rosapi), args.timeout)
    except TimeoutError:
        _err(f"no answer from {url} within {args.timeout:g} s")
        return 1
    except ServiceError as exc:
        _err(str(exc))
        return 1
    finally:
        await client.close()
    if args.json:
        print(_json(rows, indent=True))
    else:
        _table(rows)
    return 0


async def _server_definition(url: str, name: str, timeout: float = 5.0) -> tuple[Any, str] | None:
    """(typedefs, text) from the server, or None when it is unreachable, does not know the type, or may not
    be asked (``rosapi_guard``: a note on stderr says why).  A message type some topic carries is read from
    ``topics_and_raw_types`` -- the robot's own ``.msg`` text -- before ``message_details``."""
    from rcon_core.bridge import BridgeClient, BridgeError, RosapiRefusedError
    from rcon_core.msgs.names import pkg_type

    client = BridgeClient(url, reconnect=False, call_timeout=timeout)
    try:
        await asyncio.wait_for(client.connect(), 2.0)
    except Exception:
        return None
    try:
        short = pkg_type(name)
        if "/srv/" in name or ("/msg/" not in name and await _is_service_type(client, short)):
            req = await client.rosapi.service_request_details(short)
            resp = await client.rosapi.service_response_details(short)
            if req or resp:
                return {"request": req, "response": resp}, typedefs_text(req) + "\n---\n" + typedefs_text(resp)
            return None
        raw = await client.rosapi.raw_definition(name)
        if raw is not None:
            tds = await client.rosapi.typedefs_from_text(name)
            return (tds, raw[1].rstrip("\n")) if tds else None
        tds = await client.rosapi.message_details(short)
        return (tds, typedefs_text(tds)) if tds and tds[0].get("fieldnames") is not None else None
    except RosapiRefusedError as exc:
        print(f"rcon type: note: the robot was not asked ({exc.message})", file=sys.stderr)
        return None
    except BridgeError:
        return None
    finally:
        await client.close()


async def _is_service_type(client: Any, name: str) -> bool:
    from rcon_core.bridge import BridgeError

    try:
        if await client.rosapi.raw_definition(name) is not None:
            return False
        tds = await client.rosapi.message_details(name)
    except BridgeError:
        tds = []
    if tds:
        return False
    try:
        return bool(await client.rosapi.service_request_details(name))
    except BridgeError:
        return False


async def _type(url: str, args: argparse.Namespace) -> int:
    name = args.type_name
    from rcon_core.cli import type_text

    found = await _server_definition(url, name, args.timeout)
    if found is not None:
        typedefs, text = found
        if args.recursive:
            text = (type_text.service_expanded_text(typedefs) if isinstance(typedefs, dict)
                    else type_text.expanded_text(typedefs))
        print(_json({"type": name, "source": "server", "typedefs": typedefs}, indent=True) if args.json else text)
        return 0
    reg = _registry()
    if reg is not None and (reg.has(name) or reg.has_service(name)):
        if args.json:
            print(_json({"type": name, "source": "local", "definition": reg.definition_text(name)}, indent=True))
        elif args.recursive:
            typedefs = type_text.local_typedefs(reg, name)
            print(type_text.service_expanded_text(typedefs) if isinstance(typedefs, dict)
                  else type_text.expanded_text(typedefs))
        else:
            print(reg.definition_text(name))
        return 0
    _err(f"unknown type {name} (not on the server at {url}, not a standard type and not contributed by an "
         "installed widget plugin)")
    return 1


async def _echo(url: str, args: argparse.Namespace) -> int:
    from rcon_core.cli.refusals import StatusErrors, silent_for, type_refusal

    client = await _connect(url, args)
    if client is None:
        return 1
    done = asyncio.Event()
    count = 0
    loop = asyncio.get_running_loop()
    last_seen = loop.time()

    def on_msg(msg: dict[str, Any]) -> None:
        nonlocal count, last_seen
        if done.is_set():
            return
        count += 1
        last_seen = loop.time()
        try:
            text = _json(msg) if args.json else _yaml(msg) + "---"
        except (TypeError, ValueError, RecursionError) as exc:  # nested too deep to print, not JSON...
            from rcon_core.bridge.safety import safe_text

            _err(f"message {count} could not be printed: {safe_text(exc)}")
            return
        try:
            print(text, flush=True)
        except BrokenPipeError:  # the reader went away (`rcon echo ... | head`): stop quietly
            _silence_stdout()
            done.set()
            return
        if args.n and count >= args.n:
            done.set()

    status = StatusErrors(client, args.topic)
    try:
        refusal = await type_refusal(client, args.msg_type)
        if refusal:
            _err(refusal)
            return 1
        hint = "" if args.msg_type else await _unadvertised_hint(client, args.topic)
        if hint:
            _err(f"note: {hint}")
        client.node("rcon-echo").subscribe(args.topic, on_msg, type=args.msg_type, throttle_rate=args.throttle,
                                           compression=args.compression)
        waits = {asyncio.ensure_future(done.wait()), asyncio.ensure_future(_until_closed(client)),
                 asyncio.ensure_future(status.event.wait())}
        silence = None
        if args.timeout is not None:
            silence = asyncio.ensure_future(silent_for(args.timeout, lambda: last_seen))
            waits.add(silence)
        await asyncio.wait(waits, return_when=asyncio.FIRST_COMPLETED)
        for w in waits:
            w.cancel()
        if done.is_set():
            return 0
        more = f" ({hint})" if hint else ""
        if status.errors:
            _err(status.sentence() + more)
        elif silence is not None and silence.done() and client.connected:
            _err(f"no message on {args.topic} within {args.timeout:g} s{more}")
        else:
            _err(f"connection to {url} lost")
        return 1
    finally:
        status.close()
        await client.close()


async def _unadvertised_hint(client: Any, topic: str) -> str:
    """A sentence when nobody advertises ``topic``: rosbridge then cannot tell its type (ROS 1 refuses the
    subscription), so ``--type`` is what makes echo wait for it; "" when it is advertised or unknowable."""
    from rcon_core.bridge import BridgeError

    try:
        topics = await asyncio.wait_for(client.rosapi.topics(), 5.0)
    except (BridgeError, TimeoutError):
        return ""
    if topics.get(topic):
        return ""
    return f"{topic} is not advertised: give --type pkg/Msg to subscribe before it is"


def _silence_stdout() -> None:
    """Point stdout at the null device so the interpreter's final flush does not fail again."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())
    os.close(devnull)


async def _until_closed(client: Any) -> None:
    while client.connected:
        await asyncio.sleep(0.2)


def saved_envelope(layout: str, robot: str | None, url: str) -> tuple[Any, str]:
    """(the safety envelope, the robot's name) saved in the workspace file ``layout`` (``""``: the app's)
    for ``robot`` (a name or id; None: the robot whose URL is ``url``, else the first). ValueError with a
    sentence when the file cannot be read, the robot is not in it or it has no envelope: a command that
    asked to be held to an envelope is never sent without one."""
    from pathlib import Path

    from rcon_core.canvas.store import WorkspaceFileError, default_path, loads_workspace

    path = Path(layout) if layout else default_path()
    try:
        ws = loads_workspace(path.read_bytes(), path)
    except OSError as exc:
        raise ValueError(f"--envelope: cannot read {path}: {exc.strerror or exc}") from None
    except WorkspaceFileError as exc:
        raise ValueError(f"--envelope: {exc}") from None
    if robot:
        found = [r for r in ws.robots if robot in (r.id, r.name)]
        if not found:
            names = ", ".join(r.label for r in ws.robots)
            raise ValueError(f"--envelope: no robot {robot!r} in {path} (it has {names})")
    else:
        found = [r for r in ws.robots if r.url == url] or ws.robots[:1]
    chosen = found[0]
    if chosen.envelope is None:
        raise ValueError(f"--envelope: robot {chosen.label!r} in {path} has no safety envelope "
                         "(set one in the app: Canvas ▾ → Safety envelope…)")
    return chosen.envelope, chosen.label


async def _pub(url: str, args: argparse.Namespace) -> int:
    envelope, robot_name = None, ""
    if vars(args).get("envelope") is not None:  # only `rcon pub` has the option
        try:
            envelope, robot_name = saved_envelope(args.envelope, args.robot, url)
        except ValueError as exc:
            _err(str(exc))
            return 2
    elif getattr(args, "robot", None):
        _err("--robot goes with --envelope")
        return 2
    reg = _registry()
    if reg is not None and reg.has(args.msg_type):
        from rcon_core.msgs import MessageTextError

        try:
            msg = reg.from_text(args.msg_type, args.msg)
        except MessageTextError as exc:
            _err(f"bad message for {args.msg_type}: {exc}")
            return 2
    else:
        try:
            msg = _parse_text(args.msg)
        except Exception as exc:
            _err(f"MSG is not YAML or JSON: {exc}")
            return 2
        if not isinstance(msg, dict):
            _err("MSG must be a mapping like '{data: 1}'")
            return 2
    if args.rate is not None and args.rate <= 0:
        _err("--rate must be positive")
        return 2
    from rcon_core.bridge.envelope import NO_LIMITS, EnvelopeRefused
    from rcon_core.cli.refusals import StatusErrors, type_refusal

    verdict = (envelope or NO_LIMITS).judge(args.msg_type, msg)
    if verdict.msg is None:
        _err(verdict.refused)
        return 1
    if verdict.clamped:
        _err(f"{verdict.sentence} ({robot_name}: {envelope.describe() if envelope else ''})")
    client = await _connect(url, args)
    if client is None:
        return 1
    client.envelope = envelope  # the client holds every publish to it too
    status = StatusErrors(client, args.topic)
    try:
        refusal = await type_refusal(client, args.msg_type, args.timeout)
        if refusal:
            _err(refusal)
            return 1
        pub = client.node("rcon-pub").advertise(args.topic, args.msg_type, latch=args.latch)
        msg = verdict.msg
        if args.rate is None or args.once:
            pub.publish(msg)
            await asyncio.sleep(0.3)  # let the frame leave before the socket closes (and hear a refusal)
        else:
            period = 1.0 / args.rate
            sent = 0
            while client.connected and not status.errors and (not args.count or sent < args.count):
                pub.publish(msg)
                sent += 1
                await asyncio.sleep(period)
            await asyncio.sleep(0.1)
        if status.errors:
            _err(status.sentence())
            return 1
        if not client.connected:
            _err(f"connection to {url} lost")
            return 1
        return 0
    except EnvelopeRefused as exc:  # judged above already: only a changed message could get here
        _err(str(exc))
        return 1
    finally:
        status.close()
        await client.close()


async def _call(url: str, args: argparse.Namespace) -> int:
    from rcon_core.bridge import ServiceError
    from rcon_core.cli.type_text import typed_request
    from rcon_core.msgs import MessageTextError
    from rcon_core.msgs.text import parse_text

    request: Any = None
    if args.args is not None:
        try:  # read before connecting: a syntax error needs no robot
            parse_text(args.args)
        except MessageTextError as exc:
            _err(f"ARGS is not YAML or JSON: {exc.problem}")
            return 2
    client = await _connect(url, args)
    if client is None:
        return 1
    try:
        if args.args is not None:
            try:  # checked against the request type, as `rcon pub` checks a message
                request = await typed_request(client, args.service, args.args, _registry(), args.timeout)
            except MessageTextError as exc:
                _err(f"bad request for {args.service}: {exc}")
                return 2
        values = await client.call_service(args.service, request, timeout=args.timeout)
    except ServiceError as exc:
        _err(str(exc))
        return 1
    finally:
        await client.close()
    print(_json(values, indent=True) if args.json else _yaml(values).rstrip())
    return 0
