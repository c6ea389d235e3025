"""Entry point (group ``rcon.widgets``): hooks only, no Qt."""

from importlib.resources import files

from rcon_core.plugins import Accepts, Role, WidgetSpec, hookimpl

GRIPPER_MSG = """\
# State of the lab's two-finger gripper
float64 opening      # metres between the fingers
float64 force        # newtons
bool grasping
string tool_id
"""


@hookimpl
def rcon_register_types(registry):
    registry.add_msg("lab_msgs/Gripper", GRIPPER_MSG)


@hookimpl
def rcon_register_widgets(registry):
    registry.add(
        WidgetSpec(
            kind="lab.gripper",
            title="Gripper",
            description="Shows how far the gripper is open and whether it holds something",
            icon="gripper",
            roles={Role.SUBSCRIBE},
            accepts=Accepts(types=["lab_msgs/Gripper"]),
            settings="rcon_example_lab.gripper:GripperSettings",
            model="rcon_example_lab.gripper:GripperModel",
            view="rcon_example_lab.gripper_view:GripperView",
            api_version="1.1",  # the widget API this package is written against
        )
    )


@hookimpl
def rcon_canvas_templates(registry):  # optional: a ready canvas, under "New canvas from template"
    registry.add("Gripper station", files(__package__) / "gripper_station.json",
                 description="The gripper's state, bound to /gripper")
