"""The map model against the embedded robot over a real loopback WebSocket: trail, goals, extra tracks."""

from __future__ import annotations

import asyncio
import math

import pytest
from rcon_widgets_map import mercator
from rcon_widgets_map.model import MapModel, MapValue
from rcon_widgets_map.settings import MapSettings

from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import Binding
from rcon_core.testing import until

FIX = "sensor_msgs/NavSatFix"


def gps_model(client, **settings):
    return MapModel(MapSettings(**settings), Binding("/gps/fix", FIX, "subscribe"), client.node("map"),
                    types=TypeRegistry.standard())


async def test_trail_follows_the_moving_vessel(sim, client):
    model = gps_model(client, trail_spacing_m=0.3, heading_topic="")
    model.start()
    await until(lambda: sim.topic_subscriber_count("/gps/fix") == 1, what="subscription")
    await until(lambda: model.state.count >= 2, what="first fixes")
    start_lat, start_lon = sim.robot.lat_lon()
    drive = client.node("drive").advertise("/cmd_vel", "geometry_msgs/Twist")

    def moved() -> float:
        main = model.state.value.main
        return mercator.haversine_m(start_lat, start_lon, main.lat, main.lon)

    async def driving():
        while True:
            drive.publish({"linear": {"x": 2.0, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.0}})
            await asyncio.sleep(0.1)

    task = asyncio.create_task(driving())
    try:
        await until(lambda: moved() > 4.0, timeout=15, what="the fix to move 4 m")
    finally:
        task.cancel()
    value: MapValue = model.state.value
    main = value.main
    vessel = sim.robot
    lat, lon = vessel.lat_lon()
    # the latest fix is where the sim's vessel is (GPS noise 0.6 m, plus at most a fix period of travel)
    assert mercator.haversine_m(lat, lon, main.lat, main.lon) < 5.0
    # the trail runs from near the start to the latest fix, in order
    first, last = main.points[0], main.points[-1]
    assert mercator.haversine_m(start_lat, start_lon, *first) < 3.0
    assert last == (main.lat, main.lon)
    assert len(main.points) >= 5
    # the course heading points where the vessel heads (yaw 30 deg ENU = compass 60 deg)
    expected = (90.0 - math.degrees(vessel.yaw)) % 360
    assert main.heading_source == "course"
    assert abs((main.heading_deg - expected + 180) % 360 - 180) < 30
    assert main.accuracy_m == pytest.approx(0.6, abs=1e-6)  # sqrt of the sim's 0.36 m^2 variance
    assert not main.no_fix and main.status == 0
    model.stop()
    await until(lambda: sim.topic_subscriber_count("/gps/fix") == 0, what="unsubscribe")


async def test_confirmed_goal_reaches_the_robot(sim, client):
    model = gps_model(client)
    model.start()
    lat, lon = mercator.offset_m(43.6385, -79.3790, 25.0, -12.0)
    assert model.goal_topic == "/goal/fix"
    assert model.send_goal(lat, lon)
    got = await sim.wait_for_published(
        "/goal/fix", lambda m: abs(m["latitude"] - lat) < 1e-9 and abs(m["longitude"] - lon) < 1e-9, timeout=10)
    assert got["status"]["status"] == 0 and got["header"]["frame_id"] == "map"
    assert got["header"]["stamp"]["secs"] > 1_600_000_000
    value = model.state.value
    assert value.goal.lat == lat and value.goals_sent == 1
    model.stop()
    assert not model.send_goal(lat, lon)  # stopped: nothing sent, and the widget says why
    assert "not running" in model.state.error


async def test_publish_role_sends_goals_on_the_bound_topic(sim, client):
    model = MapModel(MapSettings(goal_topic=""), Binding("/nav/goal_fix", FIX, "publish"), client.node("goal"),
                     types=TypeRegistry.standard())
    model.start()
    assert model.goal_topic == "/nav/goal_fix"
    assert model.send_goal(43.64, -79.38)
    got = await sim.wait_for_published("/nav/goal_fix", timeout=10)
    assert (got["latitude"], got["longitude"]) == (43.64, -79.38)
    model.stop()


async def test_no_goal_topic_sends_nothing(client):
    model = gps_model(client, goal_topic="")
    model.start()
    assert model.goal_topic == ""
    assert not model.send_goal(43.64, -79.38)
    assert "no goal topic" in model.state.error
    model.stop()


async def test_extra_fix_topics_and_imu_heading(sim, client):
    model = gps_model(client, extra_topics="boat2=/boat2/gps/fix, /operator/fix", heading_topic="/imu/data",
                      heading_type="sensor_msgs/Imu")
    other = client.node("others")
    boat2 = other.advertise("/boat2/gps/fix", FIX)
    operator = other.advertise("/operator/fix", FIX)
    model.start()
    for t in ("/gps/fix", "/boat2/gps/fix", "/operator/fix", "/imu/data"):
        await until(lambda t=t: sim.topic_subscriber_count(t) == 1, what=f"subscription to {t}")
    types = TypeRegistry.standard()

    def fix(lat, lon):
        msg = types.default(FIX)
        msg.update(latitude=lat, longitude=lon)
        return msg

    def have_extras():  # the publishers' advertisements have no answer: publish until the map shows both
        v = model.state.value
        if v is not None and v.track("/boat2/gps/fix").count and v.track("/operator/fix").count:
            return True
        boat2.publish(fix(43.6390, -79.3800))
        operator.publish(fix(43.6380, -79.3785))
        return False

    await until(have_extras, what="the other two fixes on the map")
    await until(lambda: (v := model.state.value) is not None and v.main is not None and v.main.count
                and v.main.heading_source == "sensor", what="main fix with IMU heading")
    value = model.state.value
    keys = [t.key for t in value.tracks]
    assert keys == ["", "/boat2/gps/fix", "/operator/fix"]
    b2, op = value.track("/boat2/gps/fix"), value.track("/operator/fix")
    assert (b2.label, b2.lat, b2.lon) == ("boat2", 43.6390, -79.3800)
    assert op.label == "/operator/fix" and (op.lat, op.lon) == (43.6380, -79.3785)
    assert len({t.colour for t in value.tracks}) == 3
    # IMU orientation gives the heading: vessel yaw 30 deg ENU = compass 60 deg
    vessel = sim.robot
    expected = (90.0 - math.degrees(vessel.yaw)) % 360
    assert abs((value.main.heading_deg - expected + 180) % 360 - 180) < 10
    # the extra tracks do not count as values of the bound topic
    assert model.state.count == value.main.count
    model.stop()
    for t in ("/gps/fix", "/boat2/gps/fix", "/operator/fix", "/imu/data"):
        await until(lambda t=t: sim.topic_subscriber_count(t) == 0, what=f"unsubscribe from {t}")
