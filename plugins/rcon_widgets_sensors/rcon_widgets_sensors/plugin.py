"""Entry point of this widget package (group `rcon.widgets`): the module the plugin manager registers.

It must import without Qt: views are referenced lazily as `module:attr` strings.
"""

from __future__ import annotations

from rcon_core.plugins import Accepts, Role, WidgetSpec, hookimpl

from .teleop import TELEOP_TYPES

P = "rcon_widgets_sensors"
#: the widget API this package is written against (rcon_core.plugins.api.API_VERSION when it was written)
API = "1.1"

IMAGE_TYPES = ["sensor_msgs/Image", "sensor_msgs/CompressedImage", "foxglove_msgs/CompressedVideo",
               "ffmpeg_image_transport_msgs/FFMPEGPacket", "sensor_msgs/LaserScan", "nav_msgs/OccupancyGrid"]


def specs() -> list[WidgetSpec]:
    """Every widget of this package."""
    return [
        WidgetSpec(
            kind="sensors.image", title="Image", icon="image", category="Sensors",
            description="Camera images (raw, compressed, depth), H.264/H.265 video, laser scans and "
                        "occupancy grids; pinch to zoom, double-tap to fit",
            roles={Role.SUBSCRIBE},
            accepts=Accepts(types=IMAGE_TYPES, messages=["image", "compressed_image"]),
            settings=f"{P}.image:ImageSettings", model=f"{P}.image:ImageModel",
            view=f"{P}.image_view:ImageView", default_size=(480, 320), priority=10, api_version=API,
        ),
        WidgetSpec(
            kind="sensors.teleop", title="Multi-Touch", icon="gamepad", category="Controls",
            description="A touch pad that drives the robot: Twist and other planar motion commands at a "
                        "steady rate, zero as soon as you let go",
            roles={Role.PUBLISH},
            accepts=Accepts(types=list(TELEOP_TYPES)),
            settings=f"{P}.teleop:TeleopSettings", model=f"{P}.teleop:TeleopModel",
            view=f"{P}.teleop_view:TeleopView", default_size=(320, 320), priority=10, api_version=API,
        ),
        WidgetSpec(
            kind="sensors.camera", title="Camera", icon="camera", category="Sensors",
            description="This device's camera (or a test pattern) shown live and published as JPEG "
                        "(CompressedImage) or rgb8 (Image) at a chosen rate and quality",
            roles={Role.PUBLISH},
            accepts=Accepts(types=["sensor_msgs/CompressedImage", "sensor_msgs/Image"]),
            settings=f"{P}.camera:CameraSettings", model=f"{P}.camera:CameraModel",
            view=f"{P}.camera_view:CameraView", default_size=(360, 280), api_version=API,
        ),
    ] + [
        WidgetSpec(
            kind=f"sensors.{name}", title=title, icon=name, category="Sensors",
            description=f"{what}; publishes it (or shows the robot's) — test signal and manual sources "
                        "for devices without one",
            roles={Role.PUBLISH, Role.SUBSCRIBE},
            accepts=Accepts(types=[main, "geometry_msgs/Vector3Stamped", "geometry_msgs/Vector3"]),
            settings=f"{P}.motion_sensors:MotionSettings", model=f"{P}.motion_sensors:{model}",
            view=f"{P}.motion_view:MotionSensorView", default_size=(260, 150), api_version=API,
        )
        for name, title, what, main, model in (
            ("accelerometer", "Accelerometer", "This device's acceleration (m/s²)", "sensor_msgs/Imu",
             "AccelerometerModel"),
            ("gyroscope", "Gyroscope", "This device's rotation rate (rad/s)", "sensor_msgs/Imu", "GyroscopeModel"),
            ("magnetometer", "Magnetometer", "The magnetic field at this device (tesla)",
             "sensor_msgs/MagneticField", "MagnetometerModel"),
        )
    ]


@hookimpl
def rcon_register_widgets(registry):  # noqa: ANN001 - pluggy hook
    for spec in specs():
        registry.add(spec)
