"""The gripper widget's settings and model: pure Python, testable without Qt."""

import attrs

from rcon_core.plugins import WidgetModel


@attrs.define
class GripperSettings:
    max_opening: float = 0.08  # metres: the widest the fingers open

    def problems(self) -> list[str]:
        if self.max_opening <= 0:
            return ["the maximum opening must be more than 0 m"]
        return []


class GripperModel(WidgetModel):
    """Value: (fraction open 0..1, grasping)."""

    def on_message(self, msg):
        fraction = min(1.0, max(0.0, msg["opening"] / self.settings.max_opening))
        self.set_value((fraction, bool(msg["grasping"])), message=msg)
