"""The simulated vessel over the Foxglove WebSocket protocol (``rcon sim --protocol foxglove``,
``rcon --demo --protocol foxglove``: ``rcon_core/foxglove/gateway.py`` through foxglove-sdk): the CLI finds
the protocol by itself and drives the vessel, and the whole demo runs on the Foxglove link."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
from qtpy.QtTest import QTest

from rcon_core.bridge import ConnectionState
from rcon_core.cli.main import main
from rcon_core.foxglove.gateway import FoxgloveGateway
from rcon_core.sim import SimServer
from rcon_core.testing import TEST_RATE_SCALE

pytestmark = pytest.mark.usefixtures("transport")  # every test runs on each WebSocket transport


@pytest.fixture(scope="module")
def fox_sim_url():
    proc = subprocess.Popen([sys.executable, "-m", "rcon_core.cli.main", "sim", "--port", "0", "--protocol", "foxglove"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env={**os.environ, "PYTHONUNBUFFERED": "1"})
    try:
        line = proc.stdout.readline()
        match = re.search(r"Foxglove WebSocket protocol on (ws://127\.0\.0\.1:\d+)", line)
        assert match, (line, proc.stderr.read() if proc.poll() is not None else "")
        yield match.group(1)
    finally:
        proc.terminate()
        proc.wait(10)


def run(capsys, *argv):
    rc = main(list(argv))
    out, err = capsys.readouterr()
    return rc, out, err


def test_rcon_sim_over_foxglove_is_driven_by_the_cli(fox_sim_url, capsys):
    rc, out, err = run(capsys, "info", "--url", fox_sim_url)
    assert rc == 0, err
    assert "Foxglove WebSocket (foxglove.sdk.v1), server rcon-sim" in out and "encodings     ros1" in out
    rc, out, err = run(capsys, "topics", "--url", fox_sim_url, "--json")
    assert rc == 0, err
    assert json.loads(out)["/cmd_vel"] == "geometry_msgs/msg/Twist"
    rc, out, err = run(capsys, "echo", "/odom", "-n", "1", "--url", fox_sim_url, "--json")
    assert rc == 0, err
    assert json.loads(out)["child_frame_id"] == "base_link"
    rc, out, err = run(capsys, "call", "/dock", "--url", fox_sim_url, "--json")
    assert rc == 0, err
    assert json.loads(out)["success"] is True
    rc, _, err = run(capsys, "pub", "/cmd_vel", "geometry_msgs/Twist", "{linear: {x: 0.5}}", "--url", fox_sim_url)
    assert rc == 0, err


def test_rcon_sim_refuses_rosauth_on_the_foxglove_protocol(capsys, monkeypatch):
    monkeypatch.setenv("RCON_AUTH_SECRET", "secret")  # rcon sim takes no secret on its command line
    assert main(["sim", "--port", "0", "--protocol", "foxglove", "--auth"]) == 2
    assert "has no rosauth" in capsys.readouterr().err


@pytest.fixture
def fox_player_url():
    """``rcon sim --play demo.bag --protocol foxglove --loop --rate 4``: the recording over the Foxglove
    protocol (the player's bare sim on loopback behind the gateway); its URL."""
    bag = Path(__file__).parent / "fixtures" / "recordings" / "demo.bag"
    proc = subprocess.Popen([sys.executable, "-m", "rcon_core.cli.main", "sim", "--port", "0", "--protocol", "foxglove",
                             "--play", str(bag), "--loop", "--rate", "4"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env={**os.environ, "PYTHONUNBUFFERED": "1"})
    try:
        line = proc.stdout.readline()
        match = re.search(r"over the Foxglove WebSocket protocol on (ws://127\.0\.0\.1:\d+)", line)
        assert match and "playing" in line, (line, proc.stderr.read() if proc.poll() is not None else "")
        yield match.group(1)
    finally:
        proc.terminate()
        proc.wait(10)


async def test_a_recording_plays_over_the_foxglove_protocol(fox_player_url):
    """Was refused in words ("over rosbridge only") until the gateway could front the player: now the
    recording's topics are channels with the file's own definitions, each message arrives with the recorded
    bytes (checked by a bare WebSocket client against the file), RCON's Foxglove link decodes them, the latched
    map reaches a late subscriber, and the server time is the recording's."""
    from fox_raw import RawFoxClient, run_of

    from rcon_core.foxglove import FoxgloveClient
    from rcon_core.record.files import open_recording
    from rcon_core.testing import until

    bag = Path(__file__).parent / "fixtures" / "recordings" / "demo.bag"
    with open_recording(bag) as rec:
        recorded: dict[str, list[bytes]] = {}
        for topic, _t, data in rec.messages():
            recorded.setdefault(topic, []).append(data)
        start, end = rec.start_ns, rec.end_ns
    topics = ["/odom", "/gps/fix", "/battery", "/map"]
    async with RawFoxClient(fox_player_url, topics) as raw:
        await until(lambda: all(len(raw.payloads[t]) >= 3 for t in ("/odom", "/gps/fix")) and raw.payloads["/battery"]
                    and raw.payloads["/map"], timeout=30, what="the played messages")
    for topic in topics:
        adv = raw.channels[topic]
        assert (adv["encoding"], adv["schemaEncoding"]) == ("ros1", "ros1msg"), adv
        assert all(p in recorded[topic] for p in raw.payloads[topic]), f"{topic}: not the recorded bytes"
    assert run_of(raw.payloads["/odom"][:3], recorded["/odom"] * 2)  # in the recorded order (it loops)
    client = FoxgloveClient(fox_player_url, call_timeout=5)
    await client.connect(timeout=10)
    try:
        got: list[dict] = []
        client.node("test").subscribe("/gps/fix", got.append)
        await until(lambda: got and client.server_time is not None, timeout=30, what="a fix and the server time")
        assert 40 < got[0]["latitude"] < 70
        assert start <= client.server_time <= end  # the recording's time, not the wall clock
    finally:
        await client.close()


@pytest.mark.usefixtures("qapp")
def test_the_demo_runs_on_the_foxglove_link(qtbot, tmp_path):
    pytest.importorskip("rcon_widgets_std")
    pytest.importorskip("rcon_widgets_sensors")
    pytest.importorskip("rcon_widgets_map")
    from app_helpers import entry_point_plugins

    from rcon_core.app.config import AppConfig
    from rcon_core.app.demo import demo_workspace
    from rcon_core.app.main_window import MainWindow

    plugins = entry_point_plugins()
    with SimServer.in_thread(port=0, plugin_types=True, rate_scale=TEST_RATE_SCALE) as sim, \
            FoxgloveGateway(sim.url, name="rcon-demo") as gateway:
        window = MainWindow(AppConfig(tmp_path), plugins)
        qtbot.addWidget(window)
        window.show()
        QTest.qWaitForWindowExposed(window)
        try:
            window.link.protocol = "foxglove"  # as --protocol foxglove sets it
            window.connect_to(gateway.url)
            qtbot.waitUntil(lambda: window.connection.state is ConnectionState.CONNECTED, timeout=10_000)
            assert window.link.client.protocol == "foxglove"
            window.open_workspace(demo_workspace(plugins))
            for index in range(len(window.controller.workspace.canvases)):
                window.switch_canvas(index)
                hosted = [window.host.hosted[w.id] for w in window.controller.canvas.widgets]
                qtbot.waitUntil(lambda hosted=hosted: all(h.view is not None for h in hosted), timeout=15_000)
                for h in hosted:
                    assert h.model.problems() == [], (h.widget.title, h.model.problems())
                subscribers = [h for h in hosted if h.widget.binding.role.value == "subscribe"]
                try:
                    qtbot.waitUntil(lambda s=subscribers: all(h.model.state.count > 0 for h in s), timeout=15_000)
                except Exception:
                    silent = [(h.widget.title, h.widget.binding.name, h.model.state.error) for h in subscribers
                              if h.model.state.count == 0]
                    raise AssertionError(f"no value on the Foxglove link: {silent}") from None
        finally:
            window.shutdown()
