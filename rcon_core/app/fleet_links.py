"""One link per robot of the workspace, all on the window's one bridge thread. No Qt.

::

    links = FleetLinks(first_link)            # the window's RobotConnection: the first robot's (the connection bar's)
    links.sync(workspace.robots)              # a RobotConnection per robot; robots gone are closed
    links.link("r-2")                         # that robot's RobotConnection ("" = the first robot's)
    links.connect_robot("r-2", url=None)      # connect it to its saved URL (or ``url``, not saved)
    links.connect_saved()                     # every robot but the first that has a URL
    links.fleet(OFFLINE)                      # a canvas Fleet of the current clients (offline: OFFLINE)
    links.on_client_changed(fn)               # fn(robot_id, client or None) when a robot's client changes

The first robot keeps the window's own :class:`~rcon_core.app.link.RobotConnection`, which the connection bar's URL
field drives as before; a first robot whose ``url`` is ``""`` (every migrated one-robot layout) follows
that field. Every other robot connects to its own ``url`` with its own connection settings (CA file,
client certificate and key, and the rosauth secret the OS credential store keeps for that URL when
``auth`` is set), reconnects on its own and has its own state, failure and catalogue mailboxes. Every
link holds its robot's motion commands to the robot's safety envelope (``Robot.envelope``, set on the link
by :meth:`FleetLinks.sync`, so an edited envelope applies at once, without reconnecting).
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from functools import partial
from typing import Any

from rcon_core.canvas.fleet import Fleet
from rcon_core.canvas.robots import Robot

from .link import LinkSettings, RobotConnection

log = logging.getLogger(__name__)

__all__ = ["FleetLinks", "robot_link_settings"]


def robot_link_settings(robot: Robot, secret_for: Callable[[str], str | None] | None = None,
                        url: str | None = None, overrides: LinkSettings | None = None) -> LinkSettings:
    """The :class:`LinkSettings` of a robot at ``url`` (default: its own): its TLS files, and its secret
    when it uses rosauth. ``overrides``: the command line's (``--ca-file``..., the secret from
    ``RCON_AUTH_SECRET``), which apply to every robot of the run, before the robot's own."""
    cli = overrides or LinkSettings()
    url = url or robot.url
    secret = cli.secret if robot.auth else None
    if robot.auth and not secret and url and secret_for is not None:
        try:
            secret = secret_for(url)
        except Exception as exc:  # a credential store that fails must not keep the other robots away
            log.warning("no secret for %s: %s", url, exc)
    return LinkSettings(ca_file=cli.ca_file or robot.ca_file or None,
                        client_cert=cli.client_cert or robot.client_cert or None,
                        client_key=cli.client_key or robot.client_key or None, secret=secret)


def _reach(robot: Robot) -> tuple[Any, ...]:
    """What decides how a robot is reached: a change of it means connecting again."""
    return (robot.url, robot.ca_file, robot.client_cert, robot.client_key, robot.auth, robot.recording)


class FleetLinks:
    """The links of the workspace's robots, by robot id, in the workspace's order."""

    def __init__(self, first: RobotConnection, *, secret_for: Callable[[str], str | None] | None = None,
                 overrides: Callable[[], LinkSettings] | None = None) -> None:
        self.first = first
        self.thread = first.thread
        self.secret_for = secret_for
        #: the command line's link settings (they apply to every robot of the run), read when connecting
        self.overrides = overrides or LinkSettings
        self.robots: list[Robot] = []
        self._links: dict[str, RobotConnection] = {}
        self._listeners: list[Callable[[str, Any], None]] = []
        #: URLs given at run time (``connect_robot(rid, url)``: the demo's sims), not saved in the layout
        self.run_urls: dict[str, str] = {}
        first.on_client_changed(lambda client: self._changed(first, client))

    # ------------------------------------------------------------------------------------- reading
    @property
    def ids(self) -> list[str]:
        return [r.id for r in self.robots]

    def link(self, robot_id: str = "") -> RobotConnection:
        """The link of ``robot_id`` (``""``: the first robot). KeyError for a robot not synced."""
        if not robot_id and self.robots:
            robot_id = self.robots[0].id
        if not self.robots or robot_id == self.robots[0].id:
            return self.first
        return self._links[robot_id]

    def robot(self, robot_id: str) -> Robot:
        for r in self.robots:
            if r.id == robot_id or (not robot_id and r is self.robots[0]):
                return r
        raise KeyError(robot_id)

    def url_of(self, robot_id: str) -> str | None:
        """Where ``robot_id`` is (or was last) connected: its link's URL, else its run-time or saved URL."""
        link = self.link(robot_id)
        return link.url or self.run_urls.get(robot_id) or self.robot(robot_id).url or None

    def items(self) -> list[tuple[Robot, RobotConnection]]:
        return [(r, self.link(r.id)) for r in self.robots]

    def fleet(self, offline: Any) -> Fleet:
        """The current clients as a canvas :class:`Fleet` (``offline`` for a robot without one)."""
        robots = self.robots or [Robot("r-1", "Robot")]
        return Fleet([(r, self.link(r.id).client or offline) for r in robots])

    # ------------------------------------------------------------------------------------- changing
    def on_client_changed(self, fn: Callable[[str, Any], None]) -> None:
        """``fn(robot_id, client)`` on the GUI thread when a robot's client changes (None: disconnected)."""
        self._listeners.append(fn)

    def _changed(self, link: RobotConnection, client: Any) -> None:
        for r in self.robots:
            if self.link(r.id) is link:
                for fn in self._listeners:
                    fn(r.id, client)
                return

    def sync(self, robots: list[Robot]) -> list[str]:
        """Make a link for each robot not yet linked, close the links of robots that are gone. The first
        robot always has the window's link. Returns the ids of the robots that are new, or whose URL or
        connection settings changed (to be connected again)."""
        old_first = self.robots[0].id if self.robots else None
        before = {r.id: _reach(r) for r in self.robots}
        self.robots = list(robots)
        wanted = {r.id for r in robots[1:]}
        for rid in [rid for rid in self._links if rid not in wanted]:
            self._links.pop(rid).disconnect()  # the close runs on the bridge thread: the GUI never waits
            self.run_urls.pop(rid, None)
        new = []
        for r in robots[1:]:
            if r.id not in self._links:
                link = RobotConnection(self.thread)
                link.on_client_changed(partial(self._changed, link))
                self._links[r.id] = link
                new.append(r.id)
        for r in robots:  # each robot's safety envelope on its link, whatever else changed
            self.link(r.id).set_envelope(r.envelope)
        if robots and robots[0].id != old_first:
            new.insert(0, robots[0].id)
        new += [r.id for r in robots if r.id in before and before[r.id] != _reach(r) and r.id not in new]
        return new

    def connect_robot(self, robot_id: str, url: str | None = None, settings: LinkSettings | None = None) -> None:
        """Connect ``robot_id`` to ``url`` (kept for this run only) or to its saved URL. Raises
        :class:`~rcon_core.app.link.BadUrl` for a URL it cannot use, KeyError for an unknown robot."""
        robot = self.robot(robot_id)
        if url is not None:
            self.run_urls[robot.id] = url
        target = url or self.run_urls.get(robot.id) or robot.url
        if not target:
            return
        self.link(robot.id).connect_to(
            target, settings or robot_link_settings(robot, self.secret_for, target, self.overrides()))

    def disconnect_robot(self, robot_id: str) -> None:
        self.link(robot_id).disconnect()

    def connect_saved(self) -> None:
        """Connect every robot but the first (the connection bar's) that has a URL; a bad URL is logged
        and leaves the others connecting."""
        for r in self.robots[1:]:
            if self.link(r.id).client is None and not r.recording:  # a recording: played first (robot_recordings)
                try:
                    self.connect_robot(r.id)
                except ValueError as exc:
                    log.warning("robot %s: %s", r.label, exc)

    def shutdown(self) -> None:
        """Close every robot's link but the first (the window closes that one itself, and then the bridge
        thread). The closes run on the bridge thread side by side: nothing here waits for a robot."""
        for link in self._links.values():
            link.disconnect()
        self._links.clear()
