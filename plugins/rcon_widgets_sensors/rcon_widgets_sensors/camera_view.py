"""The Camera widget's Qt view: the Image view showing the preview of what is being published."""

from __future__ import annotations

from .image_view import ImageView


class CameraView(ImageView):
    """Same painting, zoom and overlay as the Image widget; the model's preview frames are the frames."""
