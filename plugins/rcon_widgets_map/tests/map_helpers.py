"""Shared helpers for this package's tests (imported by basename: keep the name unique)."""

from __future__ import annotations


def make_view(qtbot, model, size=(480, 400)):
    """A shown map view of ``model`` at ``size``, exposed, with the model's current state."""
    from rcon_widgets_map.view import MapView

    view = MapView(model)
    qtbot.addWidget(view)
    view.resize(*size)
    view.show()
    qtbot.waitExposed(view)
    view.refresh(model.state)
    return view
