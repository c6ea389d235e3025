"""One link per robot (rcon_core.app.fleet_links, no Qt): each robot connects to its own URL with its own
settings -- its rosauth secret from the credential store for its URL, or the run's secret -- and a robot
removed from the workspace has its link closed. Real sims on free ports, one with rosauth."""

from __future__ import annotations

import asyncio

from rcon_core.app.fleet_links import FleetLinks, robot_link_settings
from rcon_core.app.link import LinkSettings, RobotConnection
from rcon_core.canvas.robots import Robot
from rcon_core.testing import until

SECRET = "fleet-secret-0123456789"


def state_of(link: RobotConnection) -> str:
    client = link.client
    return getattr(getattr(client, "state", None), "value", "closed") if client is not None else "closed"


async def test_each_robot_connects_with_its_own_settings_and_a_removed_one_is_closed(sim_fleet):
    alpha, bravo = await sim_fleet(2)
    [charlie] = await sim_fleet(1, auth_secret=SECRET)
    first = RobotConnection()  # the links run on their own bridge thread; the sims on the test's loop
    kept = {charlie.url: SECRET}
    links = FleetLinks(first, secret_for=kept.get)
    robots = [Robot("r-1", "Alpha"), Robot("r-2", "Bravo", url=bravo.url),
              Robot("r-3", "Charlie", url=charlie.url, auth=True)]
    try:
        assert links.sync(robots) == ["r-1", "r-2", "r-3"]
        assert links.link("") is first and links.link("r-1") is first
        first.connect_to(alpha.url)
        links.connect_saved()
        for rid in ("r-1", "r-2", "r-3"):
            await until(lambda rid=rid: state_of(links.link(rid)) == "connected", what=f"{rid} connected")
        answered = []

        def charlie_answered():  # Charlie closes a link at its first frame unless it is a valid auth op
            ok, url = links.link("r-3").answered_box.take()
            if ok:
                answered.append(url)
            return bool(answered)

        await until(charlie_answered, what="Charlie answering a call after the signed auth op")
        assert answered == [charlie.url] and len(charlie.connections) == 1
        assert [len(s.connections) for s in (alpha, bravo)] == [1, 1]
        # Bravo leaves the workspace: its link is closed, the others stay
        assert links.sync([robots[0], robots[2]]) == []
        await until(lambda: len(bravo.connections) == 0, what="Bravo's link closed")
        assert links.ids == ["r-1", "r-3"] and state_of(links.link("r-3")) == "connected"
    finally:  # closing waits for the sims, which answer on this loop: not from it
        await asyncio.to_thread(links.shutdown)
        await asyncio.to_thread(first.shutdown)


def test_a_robots_link_settings():
    robot = Robot("r-2", "Bravo", url="wss://bravo:9090", ca_file="/ca.pem", auth=True)
    got = robot_link_settings(robot, {"wss://bravo:9090": "s3"}.get)
    assert (got.ca_file, got.client_cert, got.secret) == ("/ca.pem", None, "s3")
    # the command line's settings apply to every robot, before the robot's own
    cli = LinkSettings(ca_file="/cli-ca.pem", secret="from-env")
    got = robot_link_settings(robot, {"wss://bravo:9090": "s3"}.get, overrides=cli)
    assert (got.ca_file, got.secret) == ("/cli-ca.pem", "from-env")
    # no rosauth: no secret, whatever is kept
    plain = Robot("r-3", url="ws://c:9090")
    assert robot_link_settings(plain, {"ws://c:9090": "x"}.get, overrides=cli).secret is None

    def broken(_url):
        raise OSError("no keyring")

    assert robot_link_settings(robot, broken).secret is None  # logged; the robot still connects (and is refused)
