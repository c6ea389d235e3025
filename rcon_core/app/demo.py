"""The demo layout on the embedded robot. Every canvas fits a 1024 x 600 tablet in Operate mode (the side
panel hidden) without scrolling, and a 1280 x 800 window with the side panel shown: "Drive" (the front
camera beside the teleop pad, speed limit, battery, lights, dock, depth), "Cameras" (front and rear side
by side), "Sensors" (GPS map, battery, depth, IMU, log) and "Video" (the front camera raw beside the same
camera as H.264 video, each tile saying the bytes per second it costs the link).

Widget kinds come from whatever plugins are installed: each slot names the kinds it would like, best
first; the first installed one is used, with the settings written for it (each slot's settings are
valid, so no demo widget shows the "not configured" warning). When none is installed the first kind is
kept, so the canvas shows its "not installed" placeholder (and the layout works once it is installed).

The robot has a safety envelope (:data:`DEMO_ENVELOPE`: 1.5 m/s, 1 rad/s), and the Drive pad follows the
robot's speed limit (``/speed_limit``, set by the Speed limit slider, 0..1.5 m/s): the pad shows what is
actually sent, never more than the envelope and the speed limit allow.
"""

from __future__ import annotations

from typing import Any

from rcon_core.bridge.envelope import Envelope
from rcon_core.canvas import Canvas, Geometry, WidgetInstance, Workspace, new_id
from rcon_core.plugins import Binding, PluginManager, Role

#: one slot: title, {kind: settings} best first, topic or service, type, role, field paths, (x, y, w, h)
Slot = tuple[str, dict[str, dict[str, Any]], str, str, Role, tuple[str, ...], tuple[int, int, int, int]]

#: every canvas is at most 880 x 432 with its margin: it fits a 1024 x 600 tablet in Operate mode and a
#: 1280 x 800 window beside the side panel (896 px) with nothing to scroll;: the front camera beside the teleop pad, so the operator watches while driving
DRIVE: list[Slot] = [
    ("Front camera", {"sensors.image": {"max_fps": 15.0}}, "/camera/front/image_raw",
     "sensor_msgs/Image", Role.SUBSCRIBE, (), (16, 16, 400, 304)),
    # the pad follows the robot's speed limit (what the Speed limit slider sets): it shows what is sent
    ("Drive", {"sensors.teleop": {"max_linear": 2.0, "max_angular": 1.0, "speed_limit_topic": "/speed_limit"}},
     "/cmd_vel", "geometry_msgs/Twist", Role.PUBLISH, (), (432, 16, 272, 416)),
    ("Speed limit", {"std.slider": {"minimum": 0.0, "maximum": 1.5, "step": 0.1, "decimals": 1,
                                    "units": "m/s", "initial": 1.5}},
     "/speed_limit", "std_msgs/Float64", Role.PUBLISH, ("data",), (16, 336, 256, 96)),
    ("Battery", {"std.label": {"decimals": 0, "units": "%", "scale": 100.0}}, "/battery",
     "sensor_msgs/BatteryState", Role.SUBSCRIBE, ("percentage",), (720, 16, 144, 96)),
    ("Lights", {"std.switch": {"state_topic": "/lights/state", "state_field": "data"}}, "/lights/set",
     "std_srvs/SetBool", Role.CALL, ("request.data",), (720, 128, 144, 96)),
    ("Dock", {"std.button": {"text": "Dock"}}, "/dock", "std_srvs/Trigger", Role.CALL, (),
     (720, 240, 144, 96)),
    ("Depth", {"std.label": {"decimals": 1, "units": "m"}}, "/depth", "sensor_msgs/Range", Role.SUBSCRIBE,
     ("range",), (288, 336, 128, 96)),
]
CAMERAS: list[Slot] = [
    ("Front camera", {"sensors.image": {"max_fps": 15.0}}, "/camera/front/image_raw",
     "sensor_msgs/Image", Role.SUBSCRIBE, (), (16, 16, 416, 312)),
    ("Rear camera", {"sensors.image": {"max_fps": 15.0}}, "/camera/rear/image_raw/compressed",
     "sensor_msgs/CompressedImage", Role.SUBSCRIBE, (), (448, 16, 416, 312)),
]
#: the same camera twice: raw rgb8 (about 9 MB/s at 10 fps) and H.264 (tens of kB/s), the overlays say so
VIDEO: list[Slot] = [
    ("Front camera · raw", {"sensors.image": {"max_fps": 15.0}}, "/camera/front/image_raw",
     "sensor_msgs/Image", Role.SUBSCRIBE, (), (16, 16, 416, 312)),
    ("Front camera · H.264", {"sensors.image": {}}, "/camera/front/image_raw/foxglove",
     "foxglove_msgs/CompressedVideo", Role.SUBSCRIBE, (), (448, 16, 416, 312)),
]
SENSORS: list[Slot] = [
    ("GPS", {"map.gps": {}}, "/gps/fix", "sensor_msgs/NavSatFix", Role.SUBSCRIBE, (), (16, 16, 416, 416)),
    ("Battery", {"std.label": {"decimals": 0, "units": "%", "scale": 100.0}}, "/battery",
     "sensor_msgs/BatteryState", Role.SUBSCRIBE, ("percentage",), (448, 16, 200, 96)),
    ("Depth", {"std.label": {"decimals": 1, "units": "m"}}, "/depth", "sensor_msgs/Range", Role.SUBSCRIBE,
     ("range",), (664, 16, 200, 96)),
    ("Yaw rate", {"std.label": {"decimals": 2, "units": "rad/s"}}, "/imu/data", "sensor_msgs/Imu",
     Role.SUBSCRIBE, ("angular_velocity.z",), (448, 128, 416, 96)),
    ("Log", {"std.textview": {"min_level": "info"}}, "/rosout", "rosgraph_msgs/Log", Role.SUBSCRIBE, (),
     (448, 240, 416, 192)),
]


def pick_kind(plugins: PluginManager, wanted: list[str]) -> str:
    """The first installed kind of ``wanted``, else the first one (shown as a placeholder)."""
    return next((k for k in wanted if plugins.has_widget(k)), wanted[0])


def _canvas(name: str, slots: list[Slot], plugins: PluginManager) -> Canvas:
    # opened in operator mode: the widgets take touches at once (drive, switch the lights); the mode
    # button unlocks a canvas for editing
    canvas = Canvas(new_id("c"), name, locked=True)
    for title, kinds, target, type_name, role, paths, rect in slots:
        kind = pick_kind(plugins, list(kinds))
        settings = dict(kinds[kind])
        if plugins.has_widget(kind):
            spec = plugins.widget(kind)
            try:  # the stored form of the settings object: every field, defaults filled in
                settings = spec.settings_to_dict(spec.make_settings(settings))
            except Exception:
                pass  # kept as written; the widget shows what is wrong with it
        canvas.widgets.append(
            WidgetInstance(new_id("w"), kind, Binding(target, type_name, role, paths), Geometry(*rect),
                           settings, title)
        )
    return canvas


#: the demo robot's safety envelope: every motion command is held to it, whichever widget sends it (the pad
#: reaches 2 m/s at its edge on its own; the envelope holds it to 1.5, and the pad says so)
DEMO_ENVELOPE = Envelope(max_linear=1.5, max_angular=1.0)


def demo_workspace(plugins: PluginManager) -> Workspace:
    canvases = [_canvas("Drive", DRIVE, plugins), _canvas("Cameras", CAMERAS, plugins),
                _canvas("Sensors", SENSORS, plugins), _canvas("Video", VIDEO, plugins)]
    ws = Workspace(canvases, canvases[0].id)
    ws.robots[0].envelope = DEMO_ENVELOPE
    return ws
