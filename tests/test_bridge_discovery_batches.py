"""issue 22.6 (the link's side): the catalogue asked one ``service_type`` per service every 5 s, all at once:
10^5 services meant 100k calls in one burst, a 22 s loop stall and the link cut by the watchdog. Types are
now asked only for services not seen before on the connection, a few at a time, and a catalogue that did
not change is not published again. The times at 10^5 names are measured by ``benchmarks/bench_catalog.py``."""

from __future__ import annotations

import asyncio
import time

import pytest

from rcon_core.app import link as link_mod
from rcon_core.app.link import RobotConnection
from rcon_core.bridge import rosapi as rosapi_mod
from rcon_core.bridge.rosapi import Rosapi
from rcon_core.testing import connected, until, until_sync

SERVICES = 1500


def add_services(sim, n: int = SERVICES, prefix: str = "/many/service_") -> None:
    for i in range(n):
        sim.add_service(f"{prefix}{i:05d}", "std_srvs/Trigger", "/many", lambda _req: {"success": True})


class Counting:
    """The client as rosapi sees it, counting the calls in flight at once (the real client answers)."""

    def __init__(self, client) -> None:
        self.client = client
        self.in_flight = 0
        self.most = 0

    async def call_service(self, name, args=None, timeout=None):
        self.in_flight += 1
        self.most = max(self.most, self.in_flight)
        try:
            return await self.client.call_service(name, args, timeout=timeout)
        finally:
            self.in_flight -= 1


async def test_types_are_asked_a_few_at_a_time_and_only_for_new_services(sim):
    add_services(sim)
    async with connected(sim.url) as client:
        counting = Counting(client)
        api = Rosapi(counting)
        known: dict[str, str] = {}
        first = await api.services_with_types(known)
        assert sum(n.startswith("/many/") and t == "std_srvs/Trigger" for n, t in first.items()) == SERVICES
        assert list(first) == sorted(first)
        assert api.calls["service_type"] == len(first)
        assert counting.most <= rosapi_mod.TYPE_CALLS_IN_FLIGHT + 1  # + the services listing itself
        again = await api.services_with_types(known)
        assert again == first and api.calls["service_type"] == len(first)  # nothing asked again
        sim.services.pop("/many/service_00007")
        add_services(sim, 3, prefix="/more/service_")
        third = await api.services_with_types(known)
        assert api.calls["service_type"] == len(first) + 3  # only the new ones
        assert "/many/service_00007" not in third and "/many/service_00007" not in known
        assert third["/more/service_00002"] == "std_srvs/Trigger"


async def test_a_lost_link_ends_the_asking_at_once(sim):
    add_services(sim)
    async with connected(sim.url, reconnect=False) as client:
        api = client.rosapi
        task = asyncio.ensure_future(api.services_with_types({}))
        await until(lambda: api.calls["service_type"] >= 20, what="the type calls under way")
        started = time.monotonic()
        await client.link.close()
        with pytest.raises(Exception) as err:
            await task
        assert type(err.value).__name__ in ("ConnectionLostError", "NotConnectedError")
        assert time.monotonic() - started < 5
        assert api.calls["service_type"] < SERVICES


def test_the_link_lists_again_without_asking_again_and_publishes_only_changes(sim_thread, monkeypatch):
    monkeypatch.setattr(link_mod, "CATALOG_PERIOD", 0.2)
    sim_thread.run_sync(lambda: add_services(sim_thread))
    link = RobotConnection()
    try:
        link.connect_to(sim_thread.url)

        def full_catalog() -> bool:
            ok, got = link.catalog_box.take()
            return ok and any(n == "/many/service_01499" and t for n, t in got["services"])

        until_sync(full_catalog, 30, what="the whole catalogue, types and all")
        assert link.catalog_state == "listed"
        api = link.client.rosapi
        asked, listings = api.calls["service_type"], api.calls["services"]
        until_sync(lambda: api.calls["services"] >= listings + 3, 30, what="three more listings")
        assert api.calls["service_type"] == asked  # ... without one type asked again
        ok, _ = link.catalog_box.take()
        assert not ok  # nothing changed: nothing published again
    finally:
        link.shutdown()


def test_a_long_listing_is_published_as_it_goes(sim_thread, monkeypatch):
    """The names first (types unknown), then the types as they come, then the whole catalogue."""
    monkeypatch.setattr(rosapi_mod, "TYPE_CALLS_PER_S", 300.0)  # 1500 types: about 5 s
    monkeypatch.setattr(link_mod, "CATALOG_PROGRESS_EVERY", 0.5)
    sim_thread.run_sync(lambda: add_services(sim_thread))
    link = RobotConnection()
    try:
        link.connect_to(sim_thread.url)
        known_counts: list[int] = []

        def every_type_known() -> bool:
            ok, got = link.catalog_box.take()
            if ok and got["services"]:
                mine = [t for n, t in got["services"] if n.startswith("/many/")]
                assert len(mine) == SERVICES  # every name, from the first partial catalogue on
                known_counts.append(sum(1 for t in mine if t))
            return bool(known_counts) and known_counts[-1] == SERVICES

        until_sync(every_type_known, 60, what="every service's type")
        assert len(known_counts) >= 3
        assert known_counts[0] < SERVICES and known_counts == sorted(known_counts)
    finally:
        link.shutdown()
