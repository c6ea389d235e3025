"""The map model's bookkeeping without a network: NO FIX, stale, trail bounds, bad input, settings, geo."""

from __future__ import annotations

import math

import pytest
from rcon_widgets_map import geo
from rcon_widgets_map.model import MapModel
from rcon_widgets_map.settings import MapPluginSettings, MapSettings, parse_extra_topics

from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import Binding, PluginManager
from rcon_core.testing import ManualClock

TYPES = TypeRegistry.standard()


def fix(lat, lon, status=0, cov=(0.25, 0, 0, 0, 0.25, 0, 0, 0, 1), cov_type=2):
    msg = TYPES.default("sensor_msgs/NavSatFix")
    msg.update(latitude=lat, longitude=lon, position_covariance=list(cov), position_covariance_type=cov_type)
    msg["status"]["status"] = status
    return msg


def model(clock=None, **settings):
    """A started model whose messages the test hands in directly (no port is used: nothing to start)."""
    m = MapModel(MapSettings(**settings), Binding("", "sensor_msgs/NavSatFix", "subscribe"), port=None,
                 types=TYPES, clock=clock or ManualClock(1000.0))
    m.start()  # incomplete binding: marks it running without touching the port
    return m


def test_no_fix_is_marked_and_keeps_the_last_position():
    m = model()
    m.on_message(fix(43.0, -79.0))
    m.on_message(fix(float("nan"), None, status=-1))  # rosbridge sends NaN as null
    m.on_message(fix(43.5, -79.5, status=-1))  # a position with status NO_FIX is not trusted either
    main = m.state.value.main
    assert main.no_fix and main.status == -1 and main.count == 3
    assert (main.lat, main.lon) == (43.0, -79.0) and main.points == ((43.0, -79.0),)
    assert main.accuracy_m is None
    m.on_message(fix(43.0001, -79.0))
    main = m.state.value.main
    assert not main.no_fix and main.accuracy_m == pytest.approx(0.5)


def test_stale_after_the_configured_time():
    clock = ManualClock(1000.0)
    m = model(clock, stale_after=3.0)
    m.on_message(fix(43.0, -79.0))
    main = m.state.value.main
    assert not m.is_stale(main) and not m.state.stale
    clock.now += 3.5
    assert m.is_stale(main) and m.state.stale and m.age(main) == pytest.approx(3.5)


def test_trail_is_bounded_and_spaced():
    m = model(trail_length=5, trail_spacing_m=1.0)
    for i in range(20):
        m.on_message(fix(43.0 + i * 1e-5, -79.0))  # 1.1 m apart
        m.on_message(fix(43.0 + i * 1e-5 + 1e-7, -79.0))  # 1 cm later: not added
    points = m.state.value.main.points
    assert len(points) == 5 and points[-1] == pytest.approx((43.00019, -79.0))
    assert m.state.value.main.heading_deg == pytest.approx(0.0, abs=0.5)  # heading north
    m.clear_trails()
    assert m.state.value.main.points == ()
    none = model(trail_length=0)
    none.on_message(fix(43.0, -79.0))
    assert none.state.value.main.points == () and none.state.value.main.lat == 43.0


def test_bad_messages_give_an_error_not_a_crash():
    m = model()
    m.on_message({"data": 1.0})
    assert "no latitude/longitude" in m.state.error
    m2 = MapModel(MapSettings(), Binding("/x", "lab/Boat", "subscribe", ("position",)), port=None, types=TYPES)
    m2.on_message({"other": 1})
    assert "position" in m2.state.error


def test_geo_message_inside_another_message():
    m = MapModel(MapSettings(), Binding("", "lab/Boat", "subscribe", ("position",)), port=None, types=TYPES)
    m.on_message({"name": "b", "position": {"latitude": 10.0, "longitude": 20.0, "altitude": 0.0}})
    main = m.state.value.main
    assert (main.lat, main.lon, main.status, main.accuracy_m) == (10.0, 20.0, None, None)


def test_goal_message_shapes():
    m = model()
    msg = m.goal_message(43.6, -79.3)
    assert msg["latitude"] == 43.6 and msg["position_covariance_type"] == 0 and "secs" in msg["header"]["stamp"]
    ros2 = MapModel(MapSettings(), Binding("", "sensor_msgs/NavSatFix", "subscribe"), None,
                    types=TypeRegistry.standard(ros2=True))
    assert set(ros2.goal_message(1, 2)["header"]["stamp"]) == {"sec", "nanosec"}
    with pytest.raises(ValueError, match="not a valid latitude"):
        m.goal_message(91, 0)
    assert not m.send_goal(95, 0) and "not a valid latitude" in m.state.error


def test_geo_helpers():
    assert geo.accuracy_from_covariance([4, 0, 0, 0, 9, 0, 0, 0, 1], 2) == 3.0
    assert geo.accuracy_from_covariance([4, 0, 0, 0, 9, 0, 0, 0, 1], 0) is None
    assert geo.compass_from_enu_yaw(0.0) == 90.0 and geo.compass_from_enu_yaw(math.pi / 2) == 0.0
    q = {"x": 0.0, "y": 0.0, "z": math.sin(math.pi / 4), "w": math.cos(math.pi / 4)}  # yaw 90 deg ENU
    assert geo.heading_from_message({"orientation": q, "orientation_covariance": [0] * 9},
                                    "sensor_msgs/Imu") == pytest.approx(0.0, abs=1e-9)
    assert geo.heading_from_message({"orientation": q, "orientation_covariance": [-1] + [0] * 8},
                                    "sensor_msgs/Imu") is None
    assert geo.heading_from_message({"pose": {"pose": {"orientation": q}}}, "nav_msgs/Odometry") == \
        pytest.approx(0.0, abs=1e-9)
    assert geo.fix_from_message({"latitude": 1, "longitude": 359.0}).lon == -1.0
    with pytest.raises(geo.GeoError, match="expected a message"):
        geo.fix_from_message([1, 2])


def test_settings_problems_and_validators(tmp_path):
    assert MapSettings().problems() == []
    s = MapSettings(goal_topic="not a topic", extra_topics="/a/fix, /a/fix", heading_topic="9x",
                    mbtiles_path=str(tmp_path / "none.mbtiles"), tile_url="ftp://x")
    problems = "\n".join(s.problems())
    for needle in ("goal topic 'not a topic'", "listed twice", "heading topic '9x'", "does not exist",
                   "must start with http"):
        assert needle in problems
    with pytest.raises(ValueError):
        MapSettings(zoom=40)
    with pytest.raises(ValueError):
        MapSettings(heading_type="std_msgs/Float64")
    with pytest.raises(ValueError, match="stale_after"):
        MapSettings(stale_after=0)
    assert parse_extra_topics("boat=/b/fix;\n/c/fix") == [("boat", "/b/fix"), ("/c/fix", "/c/fix")]
    with pytest.raises(ValueError, match="'bad topic'"):
        parse_extra_topics("x=bad topic")
    assert MapPluginSettings().resolved_cache_dir().endswith("tiles")
    assert MapPluginSettings(cache_dir=str(tmp_path)).resolved_cache_dir() == str(tmp_path)


def test_spec_builds_settings_from_stored_dicts():
    pm = PluginManager(environ={})
    pm.load_entry_points()
    spec = pm.widget("map.gps")
    assert spec.settings_problems({}) == []
    assert spec.settings_problems({"zoom": "far"})  # wrong type: a sentence, not a crash
    s = spec.make_settings({"extra_topics": "/b/fix", "unknown": 1})
    assert s.extra_topics == "/b/fix" and spec.settings_to_dict(s)["goal_topic"] == "/goal/fix"
