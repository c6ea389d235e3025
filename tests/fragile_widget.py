"""A widget whose every hook raises (``problems()``, ``view_only``, ``set_link``, ``state`` on demand,
``shows_every_robot``), for the tests that one such widget leaves the others alone (issue 22.4). Its view
(Qt) is in ``fragile_widget_view``."""

from __future__ import annotations

from typing import Any

from rcon_core.plugins import Accepts, WidgetModel, WidgetSpec, hookimpl


class FragileModel(WidgetModel):
    """Raises from the hooks the app and the runtime call; ``broken`` says which (all by default)."""

    broken = {"problems", "view_only", "set_link", "marks"}

    def problems(self) -> list[str]:
        if "problems" in self.broken:
            raise RuntimeError("problems() blew up")
        return super().problems()

    @property
    def view_only(self) -> str | None:  # type: ignore[override]
        if "view_only" in self.broken:
            raise RuntimeError("view_only blew up")
        return None

    def set_link(self, up: bool) -> None:
        if "set_link" in self.broken:
            raise RuntimeError("set_link blew up")
        super().set_link(up)

    @property
    def shows_every_robot(self) -> bool:
        if "marks" in self.broken:
            raise RuntimeError("shows_every_robot blew up")
        return False


class FragilePlugin:
    """Registers ``test.fragile`` (a subscriber of anything) whose model breaks the hooks in ``broken``."""

    def __init__(self, broken: set[str] | None = None) -> None:
        self.model = type("FragileModel", (FragileModel,), {"broken": broken or FragileModel.broken})

    @hookimpl
    def rcon_register_widgets(self, registry: Any) -> None:
        registry.add(WidgetSpec(kind="test.fragile", title="Fragile", model=self.model,
                                view="fragile_widget_view:FragileView", roles=["subscribe"],
                                accepts=Accepts(messages=["any"]), default_size=(200, 120)))
