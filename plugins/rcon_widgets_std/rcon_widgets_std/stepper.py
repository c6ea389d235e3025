"""Stepper: publishes a number with − and + buttons (min, max, step, update rate). Publish only: the
robot does not answer, so the stepper shows the value it last asked for, not a measured one."""

from __future__ import annotations

from typing import Any

import attrs

from .slider import NumericModel, numeric_commands, range_problems

__all__ = ["StepperSettings", "StepperModel"]


@attrs.define
class StepperSettings:
    minimum: float = attrs.field(default=0.0, metadata={"label": "Minimum"})
    maximum: float = attrs.field(default=10.0, metadata={"label": "Maximum"})
    step: float = attrs.field(default=1.0, metadata={"label": "Step"})
    initial: float = attrs.field(default=0.0, metadata={"label": "Start at", "help": "shown before the first step"})
    rate_hz: float = attrs.field(default=5.0, metadata={"label": "Update rate (Hz)", "min": 0.1, "max": 100.0,
                                                        "help": "holding a button sends at most this often"})
    decimals: int = attrs.field(default=2, metadata={"label": "Decimals", "min": 0, "max": 9})
    units: str = attrs.field(default="", metadata={"label": "Units"})

    def problems(self) -> list[str]:
        out = range_problems(self.minimum, self.maximum, self.step, self.rate_hz)
        if not out and not self.minimum <= self.initial <= self.maximum:
            out.append(f"start value {self.initial:g} is outside {self.minimum:g}..{self.maximum:g}")
        return out

    def commands(self, binding: Any) -> list[tuple[str, float]]:
        """(field path, the largest value it may send there): checked against the robot's safety envelope."""
        return numeric_commands(self, binding)


class StepperModel(NumericModel):
    """``up()``/``down()``/``set_to(v)`` change the value at once (shown) and publish it, rate-limited."""

    stale_after = None

    def __init__(self, settings: StepperSettings | None, *args: Any, **kwargs: Any) -> None:
        super().__init__(settings if settings is not None else StepperSettings(), *args, **kwargs)
        self._current: float | int | None = None

    @property
    def current(self) -> float | int:
        if self._current is None:
            return self.range.coerce(self.settings.initial)
        return self._current

    def shown_number(self) -> float | int:
        return self.current

    @property
    def in_compound(self) -> bool:
        """A Compound's child: it shows the number the compound will send (the start value until stepped)."""
        return self.port.composes

    def up(self) -> float | int:
        return self.set_to(self.current + self.range.step)

    def down(self) -> float | int:
        return self.set_to(self.current - self.range.step)

    def set_to(self, value: float) -> float | int:
        v = self.range.coerce(value)
        self._current = v
        self.set_value(v)
        self.offer(v)
        return v

    def _send(self, value: float | int) -> None:
        self.publish_value(value)
