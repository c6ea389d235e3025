"""What the runtime offers a widget model besides its port: :class:`WidgetContext` (no Qt).

A model that needs nothing but its binding and port (most do) never looks at it. Two needs go beyond
the port, and a plugin must not meet them by going around the contract:

* **Other widgets' specs.** A widget that builds other widgets (the standard Compound builds its children)
  asks :meth:`WidgetContext.spec`, which is the app's own plugin manager: a plugin the operator disabled
  is not found there (``UnknownWidget``), exactly as the app's add panel does not offer it.
* **Per-connection shared resources.** :meth:`WidgetContext.shared` gives one object per key for every
  widget on the same robot link (e.g. one publisher state per robot that several teleop pads feed); two
  robots, or a new link after the robot's client is replaced, get separate objects.

The canvas runtime (``rcon_core.canvas.runtime``) builds one per widget and passes it to the model as
``context=``; a model built elsewhere (a plugin's own tests, a script) gets :meth:`WidgetContext.standalone`:
specs from the installed ``rcon.widgets`` entry points (honouring ``RCON_DISABLE_PLUGINS``) and a private
store of shared objects. A model that builds child models passes its own context on to them.

Threads: :meth:`spec` may be called from any thread; :meth:`shared` is locked, and what the factory makes
is used on the bridge loop thread like everything else a model owns.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Hashable
from typing import TYPE_CHECKING, Any, Protocol, TypeVar

if TYPE_CHECKING:
    from .spec import WidgetSpec

__all__ = ["SpecLookup", "WidgetCatalog", "SharedResources", "WidgetContext"]

T = TypeVar("T")


class SpecLookup(Protocol):
    """Finds the spec of a widget kind, raising ``KeyError`` (``UnknownWidget``) when no enabled plugin
    offers it: ``PluginManager.widget`` is one."""

    def __call__(self, kind: str) -> WidgetSpec: ...


class WidgetCatalog(Protocol):
    """The enabled widget kinds, as the matcher and the children logic read them: ``PluginManager`` is
    one."""

    def widgets(self) -> list[WidgetSpec]: ...

    def widget(self, kind: str) -> WidgetSpec: ...

    def has_widget(self, kind: str) -> bool: ...


class SharedResources:
    """Objects shared by the widgets on one link, by (link, key); the runtime holds one of these."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._objects: dict[tuple[Hashable, Hashable], Any] = {}

    def get(self, link: Hashable, key: Hashable, factory: Callable[[], T]) -> T:
        """The object for ``(link, key)``, made by ``factory()`` the first time it is asked for."""
        with self._lock:
            try:
                return self._objects[(link, key)]  # type: ignore[no-any-return]
            except KeyError:
                made = self._objects[(link, key)] = factory()
                return made

    def forget(self, link: Hashable) -> None:
        """Drop every object of ``link`` (its client was replaced or closed)."""
        with self._lock:
            for k in [k for k in self._objects if k[0] == link]:
                del self._objects[k]


_standalone_lock = threading.Lock()
_standalone_lookup: SpecLookup | None = None


def _entry_point_lookup() -> SpecLookup:
    """One plugin manager per process for models built outside the runtime (tests, scripts)."""
    global _standalone_lookup
    with _standalone_lock:
        if _standalone_lookup is None:
            from .manager import PluginManager

            pm = PluginManager()
            pm.load_entry_points()
            _standalone_lookup = pm.widget
        return _standalone_lookup


class WidgetContext:
    """The runtime's offer to one widget model: ``spec(kind)`` and ``shared(key, factory)``.

    ``specs``: how kinds are looked up (the app passes its manager's ``widget``). ``link``: the key of the
    widget's robot link (the same one the port carries as ``port.link``). ``resources``: the store shared
    objects live in (the runtime's; default: a private one).
    """

    def __init__(self, specs: SpecLookup | None = None, link: Hashable = None,
                 resources: SharedResources | None = None) -> None:
        self._specs = specs
        self.link = link
        self.resources = resources if resources is not None else SharedResources()

    @classmethod
    def standalone(cls) -> WidgetContext:
        """The context of a model built outside the runtime: specs from the installed entry points."""
        return cls()

    def spec(self, kind: str) -> WidgetSpec:
        """The spec of ``kind`` from the plugins the app loaded; ``KeyError`` (``UnknownWidget``) when none
        of the enabled plugins offers it."""
        lookup = self._specs if self._specs is not None else _entry_point_lookup()
        return lookup(kind)

    def shared(self, key: Hashable, factory: Callable[[], T]) -> T:
        """One object per ``key`` for all widgets on this widget's link, made by ``factory()`` once."""
        return self.resources.get(self.link, key, factory)
