"""The demo layout: canvas "Drive" (two cameras and a teleop pad) and "Sensors" (GPS map, IMU, battery, log).

Widget kinds come from whatever plugins are installed: each slot names the kinds it would like, best
first; the first installed one is used.  When none is installed the first kind is kept, so the canvas
shows its "not installed" placeholder (and the layout still works once the package is installed).
"""

from __future__ import annotations

from rcon_core.canvas import Canvas, Geometry, WidgetInstance, Workspace, new_id
from rcon_core.plugins import Binding, PluginManager, Role

#: (title, wanted kinds best first, topic, type, role, field paths, rect)
DRIVE = [
    ("Front camera", ["sensors.image", "sensors.camera"], "/camera/front/image_raw",
     "sensor_msgs/Image", Role.SUBSCRIBE, (), (16, 16, 480, 320)),
    ("Rear camera", ["sensors.image", "sensors.compressed_image", "sensors.camera"],
     "/camera/rear/image_raw/compressed", "sensor_msgs/CompressedImage", Role.SUBSCRIBE, (), (512, 16, 480, 320)),
    ("Drive", ["sensors.teleop", "std.teleop"], "/cmd_vel", "geometry_msgs/Twist", Role.PUBLISH, (),
     (16, 352, 400, 288)),
]
SENSORS = [
    ("GPS", ["map.gps", "map.map", "std.textview"], "/gps/fix", "sensor_msgs/NavSatFix", Role.SUBSCRIBE, (),
     (16, 16, 480, 400)),
    ("IMU", ["sensors.imu", "std.textview"], "/imu/data", "sensor_msgs/Imu", Role.SUBSCRIBE, (),
     (512, 16, 320, 240)),
    ("Battery", ["sensors.battery", "std.label", "std.textview"], "/battery", "sensor_msgs/BatteryState",
     Role.SUBSCRIBE, ("percentage",), (512, 272, 320, 144)),
    ("Log", ["sensors.log", "std.textview"], "/rosout", "rosgraph_msgs/Log", Role.SUBSCRIBE, (),
     (16, 432, 816, 208)),
]


def pick_kind(plugins: PluginManager, wanted: list[str]) -> str:
    """The first installed kind of ``wanted``, else the first one (shown as a placeholder)."""
    return next((k for k in wanted if plugins.has_widget(k)), wanted[0])


def _canvas(name: str, slots: list, plugins: PluginManager) -> Canvas:
    canvas = Canvas(new_id("c"), name)
    for title, kinds, topic, type_name, role, paths, rect in slots:
        kind = pick_kind(plugins, kinds)
        spec = plugins.widget(kind) if plugins.has_widget(kind) else None
        if spec is not None and role not in spec.roles:
            role = sorted(spec.roles, key=lambda r: list(Role).index(r))[0]
        settings: dict = {}
        if spec is not None:
            try:
                settings = spec.settings_to_dict(spec.make_settings({}))
            except Exception:
                settings = {}
        canvas.widgets.append(
            WidgetInstance(new_id("w"), kind, Binding(topic, type_name, role, paths), Geometry(*rect), settings,
                           title)
        )
    return canvas


def demo_workspace(plugins: PluginManager) -> Workspace:
    canvases = [_canvas("Drive", DRIVE, plugins), _canvas("Sensors", SENSORS, plugins)]
    return Workspace(canvases, canvases[0].id)
