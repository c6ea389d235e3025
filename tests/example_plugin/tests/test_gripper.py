from rcon_example_lab.gripper import GripperModel, GripperSettings

from rcon_core.bridge import BridgeClient
from rcon_core.plugins import Binding
from rcon_core.testing import until


async def test_gripper(sim):  # the embedded robot: it knows lab_msgs/Gripper because the plugin is installed
    client = BridgeClient(sim.url, reconnect=False)
    await client.connect()
    model = GripperModel(GripperSettings(max_opening=0.1), Binding("/gripper", "lab_msgs/Gripper", "subscribe"),
                         client.node("test"))
    model.start()  # subscribes to /gripper
    gripper = client.node("robot").advertise("/gripper", "lab_msgs/Gripper", latch=True)  # plays the robot
    gripper.publish({"opening": 0.05, "force": 2.0, "grasping": True, "tool_id": "t1"})
    await until(lambda: model.state.count > 0, what="a gripper message")
    assert model.state.value == (0.5, True)
    assert model.state.error is None
    model.stop()
    await client.close()
