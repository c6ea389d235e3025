"""What the runtime offers a widget model besides its port: :class:`WidgetContext` (no Qt).

A model that needs nothing but its binding and port (most do) never looks at it. Three needs go beyond
the port, and a plugin must not meet them by going around the contract:

* **Other widgets' specs.** A widget that builds other widgets (the standard Compound builds its children)
  asks :meth:`WidgetContext.spec`, i.e. the context's ``catalog``: in the app the app's own plugin manager,
  so a plugin the operator disabled is not found there (``UnknownWidget``), exactly as the app's add panel
  does not offer it.
* **Child widgets.** :meth:`WidgetContext.build_child` builds a child's model the way the runtime builds
  any widget, and keeps it where the runtime and the app find it (focus loss, link state, previews).
* **Per-connection shared resources.** :meth:`WidgetContext.shared` gives one object per key for every
  widget on the same robot link (e.g. one publisher state per robot that several teleop pads feed); two
  robots, or a new link after the robot's client is replaced, get separate objects.

The canvas runtime (``rcon_core.canvas.runtime``) builds one per widget and passes it to the model as
``context=``. There is no process-wide plugin manager: a model built elsewhere without a context (a
plugin's own tests, a script) knows no other kind, and a test passes the catalog it wants
(``WidgetContext(rcon_core.testing.widget_catalog(my_plugin))``: it sees only what it registered).

Threads: :meth:`spec` may be called from any thread; :meth:`shared` is locked, and what the factory makes
is used on the bridge loop thread like everything else a model owns; :meth:`build_child` runs on the
bridge loop thread.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Hashable, Mapping
from typing import TYPE_CHECKING, Any, Protocol, TypeVar, runtime_checkable

from .spec import UnknownWidget

if TYPE_CHECKING:
    from .spec import WidgetSpec

__all__ = ["SpecLookup", "WidgetCatalog", "SharedResources", "WidgetContext"]

T = TypeVar("T")


class SpecLookup(Protocol):
    """Finds the spec of a widget kind, raising ``KeyError`` (``UnknownWidget``) when no enabled plugin
    offers it: ``PluginManager.widget`` is one."""

    def __call__(self, kind: str) -> WidgetSpec: ...


@runtime_checkable
class WidgetCatalog(Protocol):
    """The enabled widget kinds, as the matcher and the children logic read them: ``PluginManager`` is
    one."""

    def widgets(self) -> list[WidgetSpec]: ...

    def widget(self, kind: str) -> WidgetSpec: ...

    def has_widget(self, kind: str) -> bool: ...


_Catalogs = WidgetCatalog


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


class _LookupCatalog:
    """A bare spec lookup (``pm.widget``, what older code passed) as a catalog: it can find a kind, not list
    them."""

    def __init__(self, lookup: SpecLookup) -> None:
        self._lookup = lookup

    def widgets(self) -> list[WidgetSpec]:
        return []

    def widget(self, kind: str) -> WidgetSpec:
        return self._lookup(kind)

    def has_widget(self, kind: str) -> bool:
        try:
            self._lookup(kind)
        except KeyError:
            return False
        return True


class ChildParent(Protocol):
    """What :meth:`WidgetContext.build_child` takes from the parent model (``WidgetModel`` is one)."""

    dry_run: bool

    @property
    def types(self) -> Any: ...
    @property
    def dispatch(self) -> Callable[[Callable[[], Any]], Any]: ...
    @property
    def clock(self) -> Callable[[], float]: ...


class WidgetContext:
    """The runtime's offer to one widget model: ``catalog``, ``spec(kind)``, ``shared(key, factory)`` and
    ``build_child(...)``.

    ``catalog``: the enabled widget kinds (the app passes its plugin manager; a test what it registered,
    ``rcon_core.testing.widget_catalog``; a bare ``pm.widget`` lookup is still taken); None: no kind is
    known. ``link``: the key of the widget's robot link (the same one the port carries as ``port.link``).
    ``resources``: the store shared objects live in (the runtime's; default: a private one).
    """

    def __init__(self, catalog: WidgetCatalog | SpecLookup | None = None, link: Hashable = None,
                 resources: SharedResources | None = None) -> None:
        if catalog is not None and not isinstance(catalog, _Catalogs):
            catalog = _LookupCatalog(catalog)
        #: the enabled widget kinds, or None: a model built without a catalog knows no other kind
        self.catalog: WidgetCatalog | None = catalog
        self.link = link
        self.resources = resources if resources is not None else SharedResources()
        #: the child models built through :meth:`build_child` (the runtime tells them focus loss and link
        #: state like any widget); emptied by :meth:`drop_children`
        self.children: list[Any] = []

    @classmethod
    def standalone(cls) -> WidgetContext:
        """Deprecated (API 1.0): a context with no catalog. Pass ``WidgetContext(catalog)`` instead; there is
        no hidden process-wide plugin manager any more."""
        return cls()

    def spec(self, kind: str) -> WidgetSpec:
        """The spec of ``kind`` from the catalog; ``KeyError`` (``UnknownWidget``) when no enabled plugin
        offers it, or when there is no catalog."""
        if self.catalog is None:
            raise UnknownWidget(f"no widget catalog: {kind!r} is unknown here (build the model with "
                                "context=WidgetContext(catalog) to let it find other kinds; in a test, "
                                "rcon_core.testing.widget_catalog(...))")
        return self.catalog.widget(kind)

    def shared(self, key: Hashable, factory: Callable[[], T]) -> T:
        """One object per ``key`` for all widgets on this widget's link, made by ``factory()`` once."""
        return self.resources.get(self.link, key, factory)

    def child_context(self) -> WidgetContext:
        """The context a child model gets: the same catalog, link and shared objects."""
        return WidgetContext(self.catalog, self.link, self.resources)

    def build_child(self, kind: str, binding: Any, *, port: Any, parent: ChildParent,
                    settings: Mapping[str, Any] | None = None) -> Any:
        """Build the model of a child widget (a Compound's child) exactly as the runtime builds any widget:
        its spec from the catalog (``KeyError`` when unknown), its settings from the stored dict
        (``SettingsError``), the parent's type registry, dispatch and clock, a child context; ``port`` is
        the parent's port for the child. The child is kept in :attr:`children` (the runtime tells it focus
        loss and link state, the app its preview flag) until :meth:`drop_children`. Not started."""
        spec = self.spec(kind)
        if binding.role not in spec.roles:
            roles = ", ".join(sorted(r.value for r in spec.roles))
            raise ValueError(f"{spec.title} cannot {binding.role.value} (it can: {roles})")
        model = spec.load_model()(spec.make_settings(settings), binding, port, types=parent.types,
                                  dispatch=parent.dispatch, clock=parent.clock, context=self.child_context())
        model.dry_run = parent.dry_run
        self.children.append(model)
        return model

    def drop_children(self) -> None:
        """Forget the children built so far (the parent stopped them)."""
        self.children = []
