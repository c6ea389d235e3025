"""The GPS map's Qt view: tiles (or a lat/lon grid), trails, markers, accuracy circles, goal taps.

Paints only the model's prepared :class:`~rcon_widgets_map.model.MapValue`. Tiles come from a
:class:`~rcon_widgets_map.loader.TileLoader` (worker threads decode them into QImages); this view only
asks for the visible ones while painting and repaints when one arrives.

Gestures: drag pans (and turns *follow* off), the wheel or a pinch zooms, a tap opens a confirm bubble
for a goal at that point: nothing is sent until *Send* is pressed. *Fit* (and the setting ``fit_all``)
keeps every marker in view until the map is panned or zoomed by hand (:mod:`.fit_view`). With a
navigation action set, a long press offers *Navigate here* in the same bubble (:mod:`.nav_view`).
"""

from __future__ import annotations

import math
from typing import Any

from qtpy import QtCore, QtGui, QtWidgets

from . import mercator, scale
from .fit_view import FitControls
from .http_tiles import HttpTileSource
from .loader import TileLoader
from .model import MapValue, Track
from .nav_view import NavigateControls
from .settings import MapPluginSettings
from .viewport import Viewport

Qt = QtCore.Qt
#: a press that moves less than this many pixels is a tap, not a drag
TAP_SLOP_PX = 8
BACKGROUND = QtGui.QColor("#dfe6ea")
GRID_COLOUR = QtGui.QColor(90, 110, 125, 110)
#: the same on a dark palette (the app's night theme): a dim chart that does not dazzle
NIGHT_BACKGROUND = QtGui.QColor("#1b242b")
NIGHT_GRID_COLOUR = QtGui.QColor(150, 170, 185, 90)
STALE_COLOUR = QtGui.QColor("#7a7a7a")
NO_FIX_COLOUR = QtGui.QColor("#c00000")


def decode_tile(data: bytes) -> QtGui.QImage | None:
    """PNG/JPEG bytes -> QImage (worker threads; QImage is safe off the GUI thread). None if undecodable."""
    img = QtGui.QImage.fromData(data)
    if img.isNull():
        return None
    return img.convertToFormat(QtGui.QImage.Format.Format_ARGB32_Premultiplied)


class _Bubble(QtWidgets.QFrame):
    """The goal confirmation: where, and Send / Cancel."""

    def __init__(self, parent: QtWidgets.QWidget) -> None:
        super().__init__(parent)
        self.setObjectName("mapGoalBubble")
        self.setAutoFillBackground(True)
        self.setFrameShape(QtWidgets.QFrame.Shape.Box)
        self.setStyleSheet(  # the palette's colours: the app's theme, light or dark
            "#mapGoalBubble { background: palette(base); border: 3px solid palette(window-text); border-radius: 8px; }"
        )
        layout = QtWidgets.QVBoxLayout(self)
        layout.setContentsMargins(10, 8, 10, 8)
        self.label = QtWidgets.QLabel()
        self.label.setObjectName("mapGoalText")
        layout.addWidget(self.label)
        row = QtWidgets.QHBoxLayout()
        self.send = QtWidgets.QPushButton("Send goal")
        self.send.setObjectName("mapGoalSend")
        self.send.setProperty("primary", True)
        self.cancel = QtWidgets.QPushButton("Cancel")
        self.cancel.setObjectName("mapGoalCancel")
        row.addWidget(self.send)
        row.addWidget(self.cancel)
        layout.addLayout(row)
        self.hide()


class MapView(QtWidgets.QWidget):
    """``MapView(model)``; the app calls :meth:`refresh` with each new state."""

    tilesArrived = QtCore.Signal()

    def __init__(self, model: Any, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        self.settings = model.settings
        plugin = model.plugin_settings if model.plugin_settings is not None else MapPluginSettings()
        self.setMinimumSize(160, 120)
        self.setMouseTracking(False)
        self.setFocusPolicy(Qt.FocusPolicy.ClickFocus)
        self.setAttribute(Qt.WidgetAttribute.WA_OpaquePaintEvent)
        self.setAttribute(Qt.WidgetAttribute.WA_AcceptTouchEvents)
        self.grabGesture(Qt.GestureType.PinchGesture)
        self.setProperty("accessibleRole", "Canvas")  # a chart to pan, zoom and tap (the app names it)
        self.viewport = Viewport(zoom=self.settings.zoom, width=max(1, self.width()), height=max(1, self.height()))
        self.value: MapValue | None = None
        self.state: Any = None
        self.pending: tuple[float, float] | None = None  # goal waiting for confirmation
        self._press: QtCore.QPointF | None = None
        self._last_drag: QtCore.QPointF | None = None
        self._dragging = False
        self._centred_once = False
        self.tiles_drawn = 0  # tiles painted in the last frame (tests and the status line)
        self.loader: TileLoader | None = self._make_loader(plugin)

        self.follow_button = QtWidgets.QToolButton(self)
        self.follow_button.setObjectName("mapFollow")
        self.follow_button.setCheckable(True)
        self.follow_button.setChecked(bool(self.settings.follow))
        self.follow_button.setToolTip("Follow: keep the robot in the middle (dragging the map turns this off)")
        self.follow_button.setAccessibleName("Follow the robot")
        self.follow_button.toggled.connect(self._follow_toggled)
        self.zoom_in = QtWidgets.QToolButton(self)
        self.zoom_in.setObjectName("mapZoomIn")
        self.zoom_in.setText("+")
        self.zoom_in.setToolTip("Zoom in")
        self.zoom_in.setAccessibleName("Zoom in")
        self.zoom_in.clicked.connect(lambda: self.zoom_by(1.0))
        self.zoom_out = QtWidgets.QToolButton(self)
        self.zoom_out.setObjectName("mapZoomOut")
        self.zoom_out.setText("\u2212")
        self.zoom_out.setToolTip("Zoom out")
        self.zoom_out.setAccessibleName("Zoom out")
        self.zoom_out.clicked.connect(lambda: self.zoom_by(-1.0))
        self.bubble = _Bubble(self)
        self.nav = NavigateControls(self)
        self.fit = FitControls(self)
        self._paint_icons()
        if self.fit.fitting:  # every marker in view, not one robot in the middle
            self.follow_button.setChecked(False)
        self.bubble.send.clicked.connect(lambda: self.nav.confirm() if self.nav.pending else self.confirm_goal())
        self.bubble.cancel.clicked.connect(self.cancel_goal)

        self.tilesArrived.connect(self._tiles_arrived, Qt.ConnectionType.QueuedConnection)
        self._ager = QtCore.QTimer(self)  # ages "stale 12 s" labels between messages
        self._ager.setInterval(1000)
        self._ager.timeout.connect(self._age)
        self._ager.start()
        self.place_controls()

    # -- tiles ----------------------------------------------------------------------------------------
    def _make_loader(self, plugin: MapPluginSettings) -> TileLoader | None:
        path = self.settings.mbtiles_path.strip()
        url = self.settings.tile_url.strip()
        if not path and not url:
            return None
        http = None
        if url:
            try:
                http = HttpTileSource(url, plugin.resolved_cache_dir(), timeout=plugin.timeout_s)
            except ValueError:
                http = None  # shown by the settings' problems()
        if not path and http is None:
            return None
        loader = TileLoader(
            decode_tile, lambda _key: self.tilesArrived.emit(), mbtiles=path or None, http=http,
            memory_tiles=plugin.memory_tiles,
        )
        self.destroyed.connect(loader.close)
        return loader

    def _tiles_arrived(self) -> None:
        if not self._centred_once and self.loader is not None and self.loader.center is not None:
            lat, lon, _zoom = self.loader.center  # no fix yet: show the offline map's own centre
            self.viewport.centre_on(lat, lon)
            self._centred_once = True
            self._place_bubble()
        self.update()

    def close_loader(self) -> None:
        """Stop the tile workers (also done when the view is destroyed)."""
        if self.loader is not None:
            self.loader.close()

    # -- state ----------------------------------------------------------------------------------------
    def refresh(self, state: Any) -> None:
        """A new model state: keep the value, follow the robot, repaint."""
        self.state = state
        value = state.value if isinstance(state.value, MapValue) else None
        self.value = value
        self.nav.sync(value)
        target = self._follow_target()
        if self.fit.sync(value):
            self._centred_once = True
        elif target is not None and not self.fit.fitting and (self.following or not self._centred_once):
            self.viewport.centre_on(target.lat, target.lon)  # type: ignore[arg-type]
            self._centred_once = True
        self.viewport_changed()

    def _age(self) -> None:
        if self.value is not None and self.isVisible():
            self.update()

    def _follow_target(self) -> Track | None:
        if self.value is None:
            return None
        main = self.value.main
        if main is not None and main.has_position:
            return main
        return next((t for t in self.value.tracks if t.has_position), None)

    # -- viewport changes -----------------------------------------------------------------------------
    def viewport_changed(self) -> None:
        """The viewport moved: place the bubble again and repaint."""
        self._place_bubble()
        self.update()

    def _follow_toggled(self, on: bool) -> None:
        if on:
            self.fit.stop()  # one robot in the middle, not every marker
            target = self._follow_target()
            if target is not None:
                self.viewport.centre_on(target.lat, target.lon)  # type: ignore[arg-type]
        self.viewport_changed()

    def set_follow(self, on: bool) -> None:
        self.follow_button.setChecked(on)

    @property
    def following(self) -> bool:
        return self.follow_button.isChecked()

    def zoom_by(self, steps: float, at: QtCore.QPointF | None = None) -> None:
        """Zoom in (``steps`` > 0) or out, about ``at`` (screen) or the centre when following. By hand: the
        map stops fitting every marker."""
        self.fit.stop()
        if at is None or self.following:
            self.viewport.zoom_at(self.viewport.zoom + steps)
        else:
            self.viewport.zoom_at(self.viewport.zoom + steps, at.x(), at.y())
        self.viewport_changed()

    def pan_by(self, dx: float, dy: float) -> None:
        """Drag the map by (dx, dy) pixels; turns follow and fitting off."""
        self.set_follow(False)
        self.fit.stop()
        self.viewport.pan(dx, dy)
        self.viewport_changed()

    def resizeEvent(self, event: QtGui.QResizeEvent) -> None:  # noqa: N802 - Qt API
        self.viewport.width, self.viewport.height = max(1, self.width()), max(1, self.height())
        self.place_controls()
        if self.fit.fitting:
            self.fit.fit(self.value)
        self._place_bubble()
        super().resizeEvent(event)

    def control_buttons(self) -> list[QtWidgets.QToolButton]:
        """The buttons in the top right corner: zoom in and out (right column), follow and fit (left)."""
        return [self.zoom_in, self.zoom_out, self.follow_button, self.fit.button]

    def button_side(self) -> int:
        """The buttons' side, one symbol each: the app's touch size (RCON sets it on the application), else
        what the style asks for; taller when the text is larger."""
        app = QtWidgets.QApplication.instance()
        touch = app.property("rcon_touch_px") if app is not None else None
        text = self.zoom_in.fontMetrics().height() + 16
        if touch:
            return max(int(touch), text)
        return max(max(b.minimumSizeHint().height(), 32) for b in self.control_buttons())

    def place_controls(self) -> None:
        """A compact 2x2 block in the top right corner: + and − on the right, Follow and Fit left of them;
        the map keeps the rest (the markers are fitted beside or below the block)."""
        m, gap = 8, 6
        side = self.button_side()
        right_col, left_col = [self.zoom_in, self.zoom_out], [self.follow_button, self.fit.button]
        for col, buttons in enumerate((right_col, left_col)):
            x = self.width() - m - side - col * (side + gap)
            row = 0
            for b in buttons:
                b.setFixedSize(side, side)
                if not b.isVisibleTo(self):
                    continue
                b.move(x, m + row * (side + gap))
                row += 1
        self.nav.place()

    def controls_rect(self) -> QtCore.QRect:
        """The corner the buttons take (empty when none shows)."""
        out = QtCore.QRect()
        for b in self.control_buttons():
            if b.isVisibleTo(self):
                out = out.united(b.geometry())
        return out

    def _paint_icons(self) -> None:
        """Follow (a crosshair) and Fit (four corners) drawn in the button's text colour (white when on), so
        they follow the theme; + and − are text."""
        side = max(16, round(self.button_side() * 0.55))
        for button, draw in ((self.follow_button, _draw_follow), (self.fit.button, _draw_fit)):
            icon = QtGui.QIcon()
            for state, colour in ((QtGui.QIcon.State.Off, button.palette().color(QtGui.QPalette.ColorRole.ButtonText)),
                                  (QtGui.QIcon.State.On, QtGui.QColor("#ffffff"))):
                pm = QtGui.QPixmap(side * 2, side * 2)
                pm.setDevicePixelRatio(2.0)
                pm.fill(Qt.GlobalColor.transparent)
                p = QtGui.QPainter(pm)
                p.setRenderHint(QtGui.QPainter.RenderHint.Antialiasing)
                p.setPen(QtGui.QPen(colour, max(2.0, side / 9), Qt.PenStyle.SolidLine, Qt.PenCapStyle.RoundCap))
                draw(p, float(side))
                p.end()
                icon.addPixmap(pm, QtGui.QIcon.Mode.Normal, state)
            button.setIcon(icon)
            button.setIconSize(QtCore.QSize(side, side))
            button.setText("")

    def night(self) -> bool:
        """Whether the map sits on a dark palette (the app's night theme): a dim chart, light ink."""
        return self.palette().color(QtGui.QPalette.ColorRole.Window).lightness() < 128

    def ink(self) -> QtGui.QColor:
        """The colour of the map's own writing (coordinates, the scale bar): the palette's text."""
        return self.palette().color(QtGui.QPalette.ColorRole.WindowText)

    def halo(self) -> QtGui.QColor:
        """The halo around writing on the map: the palette's background, nearly opaque."""
        colour = QtGui.QColor(self.palette().color(QtGui.QPalette.ColorRole.Window))
        colour.setAlpha(230)
        return colour

    def changeEvent(self, event: QtCore.QEvent) -> None:  # noqa: N802 - Qt API
        super().changeEvent(event)
        if event.type() in (QtCore.QEvent.Type.StyleChange, QtCore.QEvent.Type.PaletteChange,
                            QtCore.QEvent.Type.FontChange):
            self._paint_icons()  # another theme or text size
            self.place_controls()

    # -- goals ----------------------------------------------------------------------------------------
    def tap(self, pos: QtCore.QPointF) -> None:
        """A tap on the map: propose a goal there (nothing is sent until confirmed)."""
        if not self.model.goal_topic:
            return
        self.nav.close()  # a navigation proposal gives way to this one
        self.pending = self.viewport.to_latlon(pos.x(), pos.y())
        lat, lon = self.pending
        self.bubble.label.setText(f"Goal {lat:.6f}, {lon:.6f}\non {self.model.goal_topic}")
        self.bubble.adjustSize()
        self.bubble.show()
        self.bubble.raise_()
        self.viewport_changed()

    def confirm_goal(self) -> bool:
        """Send the pending goal; returns whether something was published."""
        if self.pending is None:
            return False
        lat, lon = self.pending
        self.pending = None
        self.bubble.hide()
        sent = bool(self.model.send_goal(lat, lon))
        self.update()
        return sent

    def cancel_goal(self) -> None:
        self.pending = None
        self.nav.close()

    def place_bubble(self) -> None:
        self._place_bubble()

    def _place_bubble(self) -> None:
        """Beside the proposed goal (right of it, or left when there is no room), below the map's buttons."""
        point = self.pending or self.nav.pending
        if point is None or not self.bubble.isVisible():
            return
        sx, sy = self.viewport.to_screen(*point)
        w, h = self.bubble.width(), self.bubble.height()
        top = max(b.geometry().bottom() for b in self.control_buttons() if b.isVisibleTo(self)) + 6
        if sx + 24 + w <= self.width() - 4:
            x, y = sx + 24, sy - h / 2
        elif sx - 24 - w >= 4:
            x, y = sx - 24 - w, sy - h / 2
        else:  # too narrow beside it: above the point, or below
            x = sx - w / 2
            y = sy - 24 - h if sy - 24 - h >= top else sy + 24
        x = min(max(4, x), self.width() - w - 4)
        y = min(max(top, y), self.height() - h - 4)
        self.bubble.move(int(x), int(max(4, y)))

    # -- input ----------------------------------------------------------------------------------------
    def mousePressEvent(self, event: QtGui.QMouseEvent) -> None:  # noqa: N802
        if event.button() == Qt.MouseButton.LeftButton:
            self._press = self._last_drag = event.position()
            self._dragging = False
            self.nav.pressed(event.position())
        super().mousePressEvent(event)

    def mouseMoveEvent(self, event: QtGui.QMouseEvent) -> None:  # noqa: N802
        if self._press is None or self._last_drag is None:
            return
        pos = event.position()
        if not self._dragging and (pos - self._press).manhattanLength() > TAP_SLOP_PX:
            self._dragging = True
            self.nav.moved()
        if self._dragging:
            delta = pos - self._last_drag
            self._last_drag = pos
            self.pan_by(delta.x(), delta.y())

    def mouseReleaseEvent(self, event: QtGui.QMouseEvent) -> None:  # noqa: N802
        if event.button() == Qt.MouseButton.LeftButton and self._press is not None:
            if not self.nav.released() and not self._dragging:
                self.tap(event.position())
            self._press = self._last_drag = None
            self._dragging = False
        super().mouseReleaseEvent(event)

    def wheelEvent(self, event: QtGui.QWheelEvent) -> None:  # noqa: N802
        steps = event.angleDelta().y() / 120.0 * 0.5
        if steps:
            self.zoom_by(steps, event.position())
        event.accept()

    def keyPressEvent(self, event: QtGui.QKeyEvent) -> None:  # noqa: N802
        if event.key() == Qt.Key.Key_Escape and self.pending is not None:
            self.cancel_goal()
            return
        super().keyPressEvent(event)

    def event(self, event: QtCore.QEvent) -> bool:
        if event.type() == QtCore.QEvent.Type.Gesture:
            pinch = event.gesture(Qt.GestureType.PinchGesture)  # type: ignore[attr-defined]
            if pinch is not None:
                self.pinch(pinch.scaleFactor(), self.mapFromGlobal(pinch.centerPoint().toPoint()))
                event.accept()
                return True
        return super().event(event)

    def pinch(self, factor: float, centre: QtCore.QPointF | QtCore.QPoint) -> None:
        """Pinch by ``factor`` (2.0 = fingers twice as far apart = one zoom level in) about ``centre``."""
        if factor > 0 and math.isfinite(factor):
            self.zoom_by(math.log2(factor), QtCore.QPointF(centre))

    # -- painting -------------------------------------------------------------------------------------
    def paintEvent(self, _event: QtGui.QPaintEvent) -> None:  # noqa: N802
        vp = self.viewport
        vp.width, vp.height = max(1, self.width()), max(1, self.height())
        p = QtGui.QPainter(self)
        p.setRenderHint(QtGui.QPainter.RenderHint.Antialiasing)
        p.fillRect(self.rect(), NIGHT_BACKGROUND if self.night() else BACKGROUND)
        self.tiles_drawn = self._paint_tiles(p) if self.loader is not None else 0
        if self.tiles_drawn == 0:
            self._paint_grid(p)
        if self.value is not None:
            for track in self.value.tracks:
                self._paint_trail(p, track)
            if self.value.goal is not None:
                self._paint_goal(p, self.value.goal.lat, self.value.goal.lon, sent=True)
            for track in self.value.tracks:
                self._paint_marker(p, track, labelled=len(self.value.tracks) > 1)
        if self.pending is not None:
            self._paint_goal(p, *self.pending, sent=False)
        self.nav.paint(p, self.value, _chip)
        self._paint_status(p)
        self._paint_scale(p)
        p.end()

    def _paint_tiles(self, p: QtGui.QPainter) -> int:
        assert self.loader is not None
        loader = self.loader
        max_z = loader.max_zoom if loader.max_zoom is not None else 19
        p.setRenderHint(QtGui.QPainter.RenderHint.SmoothPixmapTransform, True)
        view = QtCore.QRectF(self.rect())
        drawn = 0
        for t in self.viewport.tiles(max_tile_zoom=max_z, min_tile_zoom=0):
            target = QtCore.QRectF(t.left, t.top, t.size, t.size)
            for up in range(t.z + 1):
                key = (t.z - up, t.x >> up, t.y >> up)
                img = loader.get(key)
                if img is not None:
                    sub = mercator.TILE_SIZE / (1 << up)
                    src = QtCore.QRectF((t.x - (key[1] << up)) * sub, (t.y - (key[2] << up)) * sub, sub, sub)
                    _draw_clipped(p, img, target, src, view)
                    drawn += 1
                    break
                if not loader.is_absent(key):
                    break  # on its way: draw it when it arrives
        return drawn

    def _paint_grid(self, p: QtGui.QPainter) -> None:
        vp = self.viewport
        north, west = vp.to_latlon(0, 0)
        south, east = vp.to_latlon(vp.width, vp.height)
        if east < west:  # across the antimeridian: keep it simple, draw latitude lines only
            east = west
        step = scale.grid_step(max(north - south, east - west, 1e-9), target_lines=4)
        pen = QtGui.QPen(NIGHT_GRID_COLOUR if self.night() else GRID_COLOUR, 1)
        p.setPen(pen)
        font = p.font()  # the grid's labels: 0.8 times the widget's font (it follows the app's text size)
        px = font.pixelSize() if font.pixelSize() > 0 else QtGui.QFontInfo(font).pixelSize()
        font.setPixelSize(max(10, round(px * 0.8)))
        p.setFont(font)
        try:
            lats = scale.grid_lines(south, north, step)
            lons = scale.grid_lines(west, east, step)
        except ValueError:
            return
        for lat in lats:
            _, y = vp.to_screen(lat, vp.lon)
            p.drawLine(QtCore.QPointF(0, y), QtCore.QPointF(vp.width, y))
            p.drawText(QtCore.QPointF(4, y - 3), scale.format_degrees(lat, step, "N", "S"))
        for lon in lons:
            x, _ = vp.to_screen(vp.lat, lon)
            p.drawLine(QtCore.QPointF(x, 0), QtCore.QPointF(x, vp.height))
            p.drawText(QtCore.QPointF(x + 3, vp.height - 26), scale.format_degrees(lon, step, "E", "W"))

    def _colour(self, track: Track) -> QtGui.QColor:
        if track.no_fix or self.model.is_stale(track):
            return QtGui.QColor(STALE_COLOUR)
        return QtGui.QColor(track.colour)

    def _paint_trail(self, p: QtGui.QPainter, track: Track) -> None:
        if len(track.points) < 2:
            return
        colour = self._colour(track)
        colour.setAlpha(200)
        pen = QtGui.QPen(colour, 3)
        pen.setCapStyle(Qt.PenCapStyle.RoundCap)
        pen.setJoinStyle(Qt.PenJoinStyle.RoundJoin)
        p.setPen(pen)
        p.setBrush(Qt.BrushStyle.NoBrush)
        for line in self.trail_lines(track):
            p.drawPolyline(line)

    def trail_lines(self, track: Track) -> list[QtGui.QPolygonF]:
        """The trail on screen: one line per unbroken piece (never a line across a jump or a lost link)."""
        to_screen = self.viewport.to_screen
        return [QtGui.QPolygonF([QtCore.QPointF(*to_screen(lat, lon)) for lat, lon in piece])
                for piece in track.segments() if len(piece) >= 2]

    def _paint_marker(self, p: QtGui.QPainter, track: Track, labelled: bool) -> None:
        if not track.has_position:
            return
        x, y = self.viewport.to_screen(track.lat, track.lon)  # type: ignore[arg-type]
        colour = self._colour(track)
        if track.accuracy_m is not None and not track.no_fix:
            r = track.accuracy_m / self.viewport.metres_per_pixel()
            fill = QtGui.QColor(colour)
            fill.setAlpha(50)
            edge = QtGui.QColor(colour)
            edge.setAlpha(160)
            p.setPen(QtGui.QPen(edge, 1.5))
            p.setBrush(fill)
            p.drawEllipse(QtCore.QPointF(x, y), r, r)
        p.setPen(QtGui.QPen(QtGui.QColor("#ffffff"), 2.5))
        p.setBrush(colour)
        if track.heading_deg is not None:
            p.save()
            p.translate(x, y)
            p.rotate(track.heading_deg)  # compass: clockwise from north = screen up
            p.drawPolygon(QtGui.QPolygonF([QtCore.QPointF(0, -15), QtCore.QPointF(10, 11),
                                           QtCore.QPointF(0, 5), QtCore.QPointF(-10, 11)]))
            p.restore()
        else:
            p.drawEllipse(QtCore.QPointF(x, y), 8, 8)
        if labelled or track.no_fix:
            text = track.label + ("  NO FIX" if track.no_fix else "")
            _label(p, QtCore.QPointF(x + 14, y + 4), text, colour, self.halo())

    def _paint_goal(self, p: QtGui.QPainter, lat: float, lon: float, sent: bool) -> None:
        x, y = self.viewport.to_screen(lat, lon)
        colour = self.ink() if sent else QtGui.QColor("#c05000")
        p.setPen(QtGui.QPen(colour, 3))
        p.setBrush(Qt.BrushStyle.NoBrush)
        p.drawEllipse(QtCore.QPointF(x, y), 10, 10)
        p.drawLine(QtCore.QPointF(x - 15, y), QtCore.QPointF(x - 5, y))
        p.drawLine(QtCore.QPointF(x + 5, y), QtCore.QPointF(x + 15, y))
        p.drawLine(QtCore.QPointF(x, y - 15), QtCore.QPointF(x, y - 5))
        p.drawLine(QtCore.QPointF(x, y + 5), QtCore.QPointF(x, y + 15))
        if sent:
            p.setBrush(colour)
            p.drawEllipse(QtCore.QPointF(x, y), 3, 3)

    def status_text(self) -> tuple[str, QtGui.QColor] | None:
        """The chip shown at the top left: NO FIX, STALE, waiting... (None when all is well)."""
        value = self.value
        main = value.main if value is not None else None
        if self.model.binding.role.value != "subscribe":
            return None
        if main is None or main.count == 0:
            return "Waiting for a fix\u2026", STALE_COLOUR
        if main.no_fix:
            return "NO FIX", NO_FIX_COLOUR
        if self.model.is_stale(main):
            age = self.model.age(main)
            return f"STALE  {age:.0f} s", QtGui.QColor("#a05a00")
        return None

    def _paint_status(self, p: QtGui.QPainter) -> None:
        font = p.font()
        font.setBold(True)
        p.setFont(font)
        chip = self.status_text()
        if chip is not None:
            fm_bold = QtGui.QFontMetricsF(font)
            at = QtCore.QPointF(8, 8)
            room = QtCore.QRectF(at.x(), at.y(), fm_bold.horizontalAdvance(chip[0]) + 20, fm_bold.height() + 10)
            block = QtCore.QRectF(self.controls_rect())
            if room.intersects(block):  # a narrow map: the chip goes below the buttons' corner
                at = QtCore.QPointF(8, block.bottom() + 8)
            _chip(p, at, chip[0], chip[1])
        main = self._follow_target()
        y = float(self.height() - 8)
        lines = []
        if main is not None:
            lines.append(f"{main.lat:.6f}, {main.lon:.6f}"
                         + (f"  \u00b1{main.accuracy_m:.1f} m" if main.accuracy_m is not None else "")
                         + (f"  {main.heading_deg:.0f}\u00b0" if main.heading_deg is not None else ""))
        if self.loader is not None and (self.loader.error or self.loader.net_error):
            lines.append("tiles: " + (self.loader.error or self.loader.net_error or ""))
        if self.model.state.error:
            lines.append(self.model.state.error)
        font.setBold(False)
        p.setFont(font)
        fm = QtGui.QFontMetricsF(font)
        for line in reversed(lines):
            _label(p, QtCore.QPointF(self.width() - fm.horizontalAdvance(line) - 12, y - 4), line,
                   self.ink(), self.halo())
            y -= fm.height() + 6

    def _paint_scale(self, p: QtGui.QPainter) -> None:
        try:
            metres, px, text = scale.scale_bar(self.viewport.metres_per_pixel(), max(40.0, self.width() / 4))
        except ValueError:
            return
        x0, y0 = 10.0, self.height() - 12.0
        p.setPen(QtGui.QPen(self.halo(), 6))
        p.drawLine(QtCore.QPointF(x0, y0), QtCore.QPointF(x0 + px, y0))
        p.setPen(QtGui.QPen(self.ink(), 3))
        p.drawLine(QtCore.QPointF(x0, y0), QtCore.QPointF(x0 + px, y0))
        p.drawLine(QtCore.QPointF(x0, y0 - 6), QtCore.QPointF(x0, y0))
        p.drawLine(QtCore.QPointF(x0 + px, y0 - 6), QtCore.QPointF(x0 + px, y0))
        _label(p, QtCore.QPointF(x0, y0 - 10), text, self.ink(), self.halo())


def _draw_follow(p: QtGui.QPainter, side: float) -> None:
    """A crosshair: "keep the robot in the middle"."""
    c, r = side / 2, side * 0.3
    p.drawEllipse(QtCore.QPointF(c, c), r, r)
    for a, b in (((c, 0.5), (c, c - r * 0.5)), ((c, side - 0.5), (c, c + r * 0.5)),
                 ((0.5, c), (c - r * 0.5, c)), ((side - 0.5, c), (c + r * 0.5, c))):
        p.drawLine(QtCore.QPointF(*a), QtCore.QPointF(*b))


def _draw_fit(p: QtGui.QPainter, side: float) -> None:
    """Four corners: "every marker in view"."""
    e, arm = 1.5, side * 0.32
    for x, dx in ((e, 1), (side - e, -1)):
        for y, dy in ((e, 1), (side - e, -1)):
            p.drawLine(QtCore.QPointF(x, y), QtCore.QPointF(x + dx * arm, y))
            p.drawLine(QtCore.QPointF(x, y), QtCore.QPointF(x, y + dy * arm))


def _draw_clipped(p: QtGui.QPainter, img: QtGui.QImage, target: QtCore.QRectF, src: QtCore.QRectF,
                  view: QtCore.QRectF) -> None:
    """Draw ``src`` of ``img`` into ``target``, cutting both to the visible part first (overzoomed tiles
    can be millions of pixels wide)."""
    visible = target.intersected(view)
    if visible.isEmpty():
        return
    sx = src.width() / target.width()
    sy = src.height() / target.height()
    cut = QtCore.QRectF(
        src.x() + (visible.x() - target.x()) * sx, src.y() + (visible.y() - target.y()) * sy,
        visible.width() * sx, visible.height() * sy,
    )
    p.drawImage(visible, img, cut)


def _label(p: QtGui.QPainter, at: QtCore.QPointF, text: str, colour: QtGui.QColor,
           halo: QtGui.QColor | None = None) -> None:
    """Text with a halo (white, or the night's dark) so it reads on any tile."""
    path = QtGui.QPainterPath()
    path.addText(at, p.font(), text)
    p.setPen(QtGui.QPen(halo if halo is not None else QtGui.QColor(255, 255, 255, 230), 4, Qt.PenStyle.SolidLine,
                        Qt.PenCapStyle.RoundCap, Qt.PenJoinStyle.RoundJoin))
    p.setBrush(Qt.BrushStyle.NoBrush)
    p.drawPath(path)
    p.setPen(Qt.PenStyle.NoPen)
    p.setBrush(colour)
    p.drawPath(path)


def _chip(p: QtGui.QPainter, at: QtCore.QPointF, text: str, colour: QtGui.QColor) -> None:
    fm = QtGui.QFontMetricsF(p.font())
    rect = QtCore.QRectF(at.x(), at.y(), fm.horizontalAdvance(text) + 20, fm.height() + 10)
    p.setPen(Qt.PenStyle.NoPen)
    p.setBrush(colour)
    p.drawRoundedRect(rect, 6, 6)
    p.setPen(QtGui.QColor("#ffffff"))
    p.drawText(rect, int(Qt.AlignmentFlag.AlignCenter), text)
