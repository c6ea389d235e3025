"""Workspace -> canvases -> widget instances: the model, editing with undo/redo, persistence, runtime.

No Qt. ``runtime`` (imported on demand) starts and stops the widget models of a canvas.
"""

from .autosave import AutoSaver
from .document import CanvasLocked, Change, ChangeKind, Command, Document, EditError
from .store import (
    NewerVersionError,
    WorkspaceFileError,
    WorkspaceStore,
    default_path,
    dumps_workspace,
    export_canvas,
    import_canvas,
    loads_workspace,
)
from .workspace import Binding, Canvas, Geometry, WidgetInstance, Workspace, new_id

__all__ = [
    "AutoSaver",
    "Binding",
    "Canvas",
    "CanvasLocked",
    "Change",
    "ChangeKind",
    "Command",
    "Document",
    "EditError",
    "Geometry",
    "NewerVersionError",
    "WidgetInstance",
    "Workspace",
    "WorkspaceFileError",
    "WorkspaceStore",
    "default_path",
    "dumps_workspace",
    "export_canvas",
    "import_canvas",
    "loads_workspace",
    "new_id",
]
