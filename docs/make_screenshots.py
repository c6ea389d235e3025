"""Make the screenshots of docs/using-the-app.md: the add-widget pathway, step by step.

    python docs/make_screenshots.py [--out docs/screenshots]

Starts the embedded simulated robot in a thread, opens the app's main window (1280x800, the installed
widget plugins, a temporary config directory, headless unless QT_QPA_PLATFORM says otherwise), connects,
and drives the window the way a person does (taps, as the app tests do), saving one PNG per step:

1. topics listed; 2. the role chosen for /battery; 3. the compatible widgets, best first;
4. settings not configured (the Label's scale cleared to 0: the preview's warning);
5. settings valid, the Field chooser on ``voltage``; 6. the widget placed on the canvas, live;
7. operator mode; 8. a Compound on /cmd_vel with two children in its children editor.

Then the sensor widgets' pictures of ``plugins/rcon_widgets_sensors/README.md`` into ``OUT/sensors``: each
view built on its model as the app builds it, with no robot (fed frames, the test signal, touches on two
pads whose commands go nowhere). Then the display set: the demo in both themes (``demo.png``,
``demo-night.png``), at 200 % text on a 1024x600 tablet (``text-200-1024x600.png``), and the fleet demo of
three vessels at 1024x600 and 1280x800 (``fleet-3-*.png``). Then the demo's "Video" canvas
(``demo-video.png``: the front camera raw beside the same camera as H.264, each tile saying its bytes per
second; ``demo-video-tile.png``: the H.264 tile alone) and the connection bar's bandwidth details
(``bandwidth-details.png``). ``--only app``, ``--only sensors``, ``--only display`` or ``--only video``
makes one of the sets.
(The tests do not write pictures: a picture generator is not a test.)
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

from qtpy import QtCore, QtWidgets  # noqa: E402
from qtpy.QtTest import QTest  # noqa: E402

SIZE = (1280, 800)
MAX_BYTES = 200_000
TIMEOUT_S = 15.0
LEFT = QtCore.Qt.MouseButton.LeftButton
NO_MOD = QtCore.Qt.KeyboardModifier.NoModifier


def wait_until(cond: Callable[[], bool], what: str, timeout: float = TIMEOUT_S) -> None:
    """Process events until ``cond()`` holds; a clear error naming ``what`` if it never does."""
    end = time.monotonic() + timeout
    while not cond():
        if time.monotonic() > end:
            raise SystemExit(f"make_screenshots: timed out waiting for {what}")
        QTest.qWait(20)


def settle(ms: int = 400) -> None:
    """Let layouts, repaints and live data catch up before a grab."""
    QTest.qWait(ms)


def tap(widget: QtWidgets.QWidget, pos: QtCore.QPoint | None = None) -> None:
    """A finger tap on a visible, enabled widget, at its centre unless told where."""
    if not (widget.isVisible() and widget.isEnabled()):
        raise SystemExit(f"make_screenshots: cannot tap {widget.objectName() or widget!r}: hidden or disabled")
    QTest.mouseClick(widget, LEFT, NO_MOD, pos if pos is not None else widget.rect().center())


def tap_item(view: QtWidgets.QAbstractItemView, index: QtCore.QModelIndex) -> None:
    """Scroll an item into sight and tap it."""
    view.scrollTo(index)
    QTest.mouseClick(view.viewport(), LEFT, NO_MOD, view.visualRect(index).center())


def pick(combo: QtWidgets.QComboBox, text: str) -> None:
    """Open the combo's popup and tap the entry whose text starts with ``text``."""
    rows = [i for i in range(combo.count()) if combo.itemText(i).startswith(text)]
    if not rows:
        raise SystemExit(f"make_screenshots: {text!r} not in {[combo.itemText(i) for i in range(combo.count())]}")
    tap(combo)
    view = combo.view()
    wait_until(view.isVisible, "the popup")
    QTest.qWait(QtWidgets.QApplication.doubleClickInterval() + 50)  # a popup ignores a release at once
    tap_item(view, combo.model().index(rows[0], 0))
    wait_until(lambda: not view.isVisible(), "the popup to close")


def set_number(editor: QtWidgets.QAbstractSpinBox, value: float) -> None:
    """Type a number into a spin box, as a person would."""
    editor.setFocus()
    editor.selectAll()
    QTest.keyClicks(editor, str(value))


def visible_button(parent: QtWidgets.QWidget, name: str) -> QtWidgets.QPushButton:
    """The visible button called ``name`` (rebuilt pages keep hidden old ones until deleted)."""
    found = [b for b in parent.findChildren(QtWidgets.QPushButton, name) if b.isVisible()]
    if len(found) != 1:
        raise SystemExit(f"make_screenshots: expected one visible {name!r} button, found {len(found)}")
    return found[0]


def scroll_settings_to(panel: QtWidgets.QWidget, widget: QtWidgets.QWidget, margin: int = 8) -> None:
    """Scroll the add panel's settings page so that ``widget`` starts ``margin`` px below its top."""
    settle(200)  # the page's own scrolling (to its top on opening) first
    scroll = panel.settings_scroll
    top = widget.mapTo(scroll.widget(), QtCore.QPoint(0, 0)).y()
    scroll.verticalScrollBar().setValue(max(0, top - margin))


class Shooter:
    """Saves numbered grabs of the window into ``out``."""

    def __init__(self, window: QtWidgets.QWidget, out: Path) -> None:
        self.window, self.out = window, out
        self.saved: list[Path] = []

    def __call__(self, name: str) -> None:
        settle()
        if (self.window.width(), self.window.height()) != SIZE:
            self.window.resize(*SIZE)
            settle()
        image = self.window.grab().toImage()
        if (image.width(), image.height()) != SIZE:
            raise SystemExit(f"make_screenshots: {name} grabbed at {image.width()}x{image.height()}, not {SIZE}")
        path = self.out / f"{name}.png"
        if not image.save(str(path), "PNG", 0):  # quality 0: the strongest PNG compression
            raise SystemExit(f"make_screenshots: could not write {path}")
        size = path.stat().st_size
        if size >= MAX_BYTES:
            raise SystemExit(f"make_screenshots: {path} is {size} bytes, over {MAX_BYTES}")
        self.saved.append(path)
        print(f"{path}  {size // 1024} KB")


def run(out: Path) -> list[Path]:
    """Drive the window through the add-widget pathway and save each step in ``out``."""
    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication(sys.argv[:1])
    app.setApplicationName("RCON")

    from rcon_core.app import theme
    from rcon_core.app.config import AppConfig
    from rcon_core.app.main_window import MainWindow
    from rcon_core.bridge import ConnectionState
    from rcon_core.plugins import PluginManager, Role
    from rcon_core.sim import SimServer

    theme.apply(app)
    plugins = PluginManager(environ={})
    plugins.load_entry_points()
    out.mkdir(parents=True, exist_ok=True)

    with tempfile.TemporaryDirectory(prefix="rcon-shots-") as tmp, SimServer.in_thread(port=0) as robot:
        win = MainWindow(AppConfig(Path(tmp) / "config"), plugins)
        win.resize(*SIZE)
        win.show()
        QTest.qWaitForWindowExposed(win)
        shoot = Shooter(win, out)
        try:
            win.connect_to(robot.url, remember=False)
            wait_until(lambda: win.connection.state is ConnectionState.CONNECTED, "the connection")
            for topic in ("/battery", "/cmd_vel"):
                wait_until(lambda topic=topic: win.topics.item(topic) is not None, f"{topic} to be listed")
            win.side.setCurrentWidget(win.topics)
            settle(1000)  # the round-trip time shows
            shoot("1-topics")

            # 2: tap /battery, choose "show it" (subscribe)
            tree = win.topics.tree
            tap_item(tree, tree.indexFromItem(win.topics.item("/battery")))
            panel = win.add_panel
            wait_until(lambda: panel.stack.currentWidget() is panel.role_page, "the role page")
            shoot("2-role")

            # 3: the compatible widgets, best first
            tap(panel.role_buttons[Role.SUBSCRIBE])
            wait_until(lambda: panel.stack.currentWidget() is panel.widgets_page, "the widget list")
            shoot("3-compatible-widgets")

            # 4: a Label, its scale cleared to 0: not configured, the preview warns
            kinds = [panel.candidates.item(i).data(QtCore.Qt.ItemDataRole.UserRole).spec.kind
                     for i in range(panel.candidates.count())]
            tap_item(panel.candidates, panel.candidates.model().index(kinds.index("std.label"), 0))
            wait_until(lambda: panel.stack.currentWidget() is panel.settings_page, "the settings page")
            scale = panel.form.editor("scale")
            set_number(scale, 0)
            wait_until(lambda: not panel.place_button.isEnabled(), "the scale problem to block placing")
            wait_until(lambda: panel.preview_frame is not None and "scale" in panel.preview_frame.problems.text(),
                       "the preview's warning")
            scroll_settings_to(panel, panel.preview_slot, margin=40)  # the warning and the scale of 0
            shoot("4-settings-not-configured")

            # 5: scale back to 1, the Field chooser on voltage: valid
            set_number(scale, 1)
            pick(panel.field_combo, "voltage")
            wait_until(panel.place_button.isEnabled, "the settings to be valid")
            panel.settings_scroll.verticalScrollBar().setValue(0)
            win.setFocus()
            settle(1500)  # the preview shows the robot's live voltage
            shoot("5-settings-valid")

            # 6: placed on the canvas, live
            tap(panel.place_button)
            [inst] = win.controller.canvas.widgets
            hosted = win.host.hosted[inst.id]
            wait_until(lambda: hosted.model is not None and hosted.model.state.count > 0, "live data on the canvas")
            settle(800)
            shoot("6-placed")

            # 7: operator mode
            tap(win.lock_button)
            wait_until(lambda: win.controller.canvas.locked, "operator mode")
            shoot("7-operator-mode")

            # 8: back to Edit, a Compound on /cmd_vel with a slider and a stepper
            tap(win.edit_button)
            wait_until(lambda: not win.controller.canvas.locked, "edit mode")
            win.side.setCurrentWidget(win.topics)
            tap_item(tree, tree.indexFromItem(win.topics.item("/cmd_vel")))
            tap(panel.role_buttons[Role.PUBLISH])
            kinds = [panel.candidates.item(i).data(QtCore.Qt.ItemDataRole.UserRole).spec.kind
                     for i in range(panel.candidates.count())]
            tap_item(panel.candidates, panel.candidates.model().index(kinds.index("std.compound"), 0))
            editor = panel.form.children_editors["children"]
            for path, kind, numbers, title in (
                ("linear.x", "std.slider", (("minimum", 0.0), ("maximum", 2.0), ("step", 0.5)), ""),
                ("angular.z", "std.stepper", (("minimum", -1.0), ("maximum", 1.0), ("step", 0.25)), "Turn"),
            ):
                tap(editor.add_button)
                wait_until(lambda: editor.current_page == "fields", "the fields of /cmd_vel")
                tap(editor.field_buttons[path])
                tap(editor.kind_buttons[kind])
                for name, value in numbers:
                    set_number(editor.child_form.editor(name), value)
                if title:
                    QTest.keyClicks(editor.child_title, title)
                tap(visible_button(editor, "childDone"))
                wait_until(lambda: editor.current_page == "list", "the children list")
            wait_until(panel.place_button.isEnabled, "the Compound to be valid")
            win.setFocus()
            settle(200)
            panel.settings_scroll.ensureWidgetVisible(editor.add_button)  # both children and "+ Add child"
            shoot("8-compound-children")
        finally:
            win.shutdown()
            win.close()
    return shoot.saved


def video(out: Path) -> list[Path]:
    """The demo's Video canvas on the sim, in operator mode, once both tiles show their rates."""
    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication(sys.argv[:1])
    from rcon_core.app import theme
    from rcon_core.app.config import AppConfig
    from rcon_core.app.demo import demo_workspace
    from rcon_core.app.main_window import MainWindow
    from rcon_core.bridge import ConnectionState
    from rcon_core.plugins import PluginManager
    from rcon_core.sim import SimServer

    theme.apply(app)
    plugins = PluginManager(environ={})
    plugins.load_entry_points()
    out.mkdir(parents=True, exist_ok=True)
    saved = []
    with tempfile.TemporaryDirectory(prefix="rcon-shots-") as tmp, SimServer.in_thread(port=0) as robot:
        win = MainWindow(AppConfig(Path(tmp) / "config"), plugins, demo=lambda: demo_workspace(plugins))
        win.resize(*SIZE)
        win.show()
        QTest.qWaitForWindowExposed(win)
        try:
            win.connect_to(robot.url, remember=False)
            wait_until(lambda: win.connection.state is ConnectionState.CONNECTED, "the connection")
            names = [c.name for c in win.controller.workspace.canvases]
            win.switch_canvas(names.index("Video"))
            hosted = [win.host.hosted[w.id] for w in win.controller.canvas.widgets]
            wait_until(lambda: all(h.view is not None and getattr(h.view, "frame", None) is not None
                                   and h.view.frame.byte_rate > 0 for h in hosted), "both tiles' pictures")
            settle(3000)  # the rates over their 2 s window, the bandwidth readout's too
            path = out / "demo-video.png"
            win.grab().save(str(path), "PNG", 0)
            saved.append(path)
            tile = next(h for h in hosted if "H.264" in h.widget.title)
            saved.append(save_view(tile.frame, out / "demo-video-tile.png"))
            button = win.connection.bandwidth
            button.show_details()
            settle(600)
            popup = button.popup
            assert popup is not None
            saved.append(save_view(popup, out / "bandwidth-details.png"))
            popup.close()
        finally:
            win.shutdown()
            win.close()
    for path in saved:
        print(f"{path}  {path.stat().st_size // 1024} KB")
    return saved


def save_view(widget: QtWidgets.QWidget, path: Path) -> Path:
    """Grab ``widget`` as it is now into ``path`` (PNG, under :data:`MAX_BYTES`)."""
    settle(150)
    path.parent.mkdir(parents=True, exist_ok=True)
    if not widget.grab().save(str(path), "PNG", 0):
        raise SystemExit(f"make_screenshots: could not write {path}")
    size = path.stat().st_size
    if size >= MAX_BYTES:
        raise SystemExit(f"make_screenshots: {path} is {size} bytes, over {MAX_BYTES}")
    print(f"{path}  {size // 1024} KB")
    return path


def sensors(out: Path) -> list[Path]:
    """The sensor widgets' views, each on its own model with no robot, saved in ``out``."""
    import math

    import numpy as np
    from rcon_widgets_sensors.camera import CameraModel, CameraSettings, TestPattern
    from rcon_widgets_sensors.camera_view import CameraView
    from rcon_widgets_sensors.image import Frame, ImageModel, ImageSettings
    from rcon_widgets_sensors.image_view import ImageView
    from rcon_widgets_sensors.motion_sensors import AccelerometerModel, MagnetometerModel, MotionSettings
    from rcon_widgets_sensors.motion_view import MotionSensorView
    from rcon_widgets_sensors.teleop import TeleopModel, TeleopSettings
    from rcon_widgets_sensors.teleop_view import TeleopView

    from rcon_core.msgs import TypeRegistry
    from rcon_core.plugins import Binding
    from rcon_core.sim import world
    from rcon_core.sim.camera import CameraRenderer, encode_jpeg
    from rcon_core.sim.vessel import Vessel
    from rcon_core.testing import ManualClock, RecordingPort

    QtWidgets.QApplication.instance() or QtWidgets.QApplication(sys.argv[:1])  # Qt's own look, as in the READMEs
    types = TypeRegistry.standard()
    saved: list[Path] = []
    keep: list[QtWidgets.QWidget] = []

    def shown(widget: QtWidgets.QWidget, w: int, h: int) -> QtWidgets.QWidget:
        widget.resize(w, h)
        widget.show()
        QTest.qWaitForWindowExposed(widget)
        keep.append(widget)
        return widget

    def fed(model: ImageModel, msg: dict) -> Frame:
        before = model.state.value.index if isinstance(model.state.value, Frame) else 0
        model.on_message(msg)
        return model.wait_frame(before, 10.0)

    # the phone's camera: the test pattern as the capture thread shows it
    cam = CameraModel(CameraSettings(source="test pattern"),
                      Binding("/phone/camera/compressed", "sensor_msgs/CompressedImage", "publish"), None)
    now = time.time()
    cam.set_value(Frame(rgb=TestPattern(640, 480).read(), kind="camera", stamp=now, received=now, decoded=now,
                        info="640×480 jpeg q80, 38 KiB → /phone/camera/compressed", index=1, fps=10.0))
    view = shown(CameraView(cam), 360, 280)
    view.refresh(cam.state)
    saved.append(save_view(view, out / "camera.png"))

    # an image topic: the sim's front camera, then zoomed in; a laser scan
    image = ImageModel(ImageSettings(), Binding("/camera/front/image_raw/compressed",
                                                "sensor_msgs/CompressedImage", "subscribe"), None)
    stamp = time.time()
    fed(image, {"header": {"stamp": {"secs": int(stamp), "nsecs": int(stamp % 1 * 1e9)}, "frame_id": "cam"},
                "format": "jpeg", "data": encode_jpeg(CameraRenderer("front").frame(Vessel(), stamp))})
    iview = shown(ImageView(image), 480, 320)
    iview.refresh(image.state)
    saved.append(save_view(iview, out / "image-camera.png"))
    iview.viewport.zoom_at(3.0, 240, 160)
    iview.viewport.pan_by(30, 20)
    iview.update()
    saved.append(save_view(iview, out / "image-zoomed.png"))
    image.on_stop()
    scan = ImageModel(None, Binding("/scan", "sensor_msgs/LaserScan", "subscribe"), None)
    lidar = world.Lidar()
    ranges = lidar.scan(0.0, 0.0, math.radians(30)).astype(np.float64)
    fed(scan, {"header": {"stamp": {"secs": int(time.time()), "nsecs": 0}}, "angle_min": lidar.angle_min,
               "angle_max": lidar.angle_max, "angle_increment": lidar.angle_increment,
               "range_min": lidar.range_min, "range_max": lidar.range_max,
               "ranges": [float(r) if np.isfinite(r) else None for r in ranges]})
    sview = shown(ImageView(scan), 360, 360)
    sview.refresh(scan.state)
    saved.append(save_view(sview, out / "image-scan.png"))
    scan.on_stop()

    # motion sensors: the manual source, and a device without the sensor
    for cls, source, type_name, name, values in (
        (AccelerometerModel, "manual", "sensor_msgs/Imu", "accelerometer", (3.2, -1.1, 9.81)),
        (MagnetometerModel, "manual", "sensor_msgs/MagneticField", "magnetometer", (1.8e-5, -0.4e-5, -5e-5)),
        (AccelerometerModel, "device", "sensor_msgs/Imu", "accelerometer-no-sensor", (0.0, 0.0, 0.0)),
    ):
        x, y, z = values
        model = cls(MotionSettings(source=source, manual_x=x, manual_y=y, manual_z=z),
                    Binding("/phone/imu", type_name, "publish"), None, types=types)
        mview = shown(MotionSensorView(model), 280, 150)
        mview.refresh(model.state)
        saved.append(save_view(mview, out / f"{name}.png"))

    # teleop: an idle pad; two thumbs on two pads at once (their commands go to a recording port, their
    # rate ticker on a clock that stands still)
    port, still = RecordingPort(), ManualClock()
    pads = []
    for settings in (TeleopSettings(), TeleopSettings(horizontal="", vertical="linear.x", dead_zone=0),
                     TeleopSettings(horizontal="-angular.z", vertical="", dead_zone=0)):
        model = TeleopModel(settings, Binding("/cmd_vel", "geometry_msgs/Twist", "publish"), port, types=types,
                            ticker_clock=still)
        model.start()
        pads.append((model, TeleopView(model)))
    idle = shown(pads[0][1], 300, 300)
    idle.refresh(pads[0][0].state)
    saved.append(save_view(idle, out / "teleop-idle.png"))
    win = QtWidgets.QWidget()
    row = QtWidgets.QHBoxLayout(win)
    (left_m, left), (right_m, right) = pads[1], pads[2]
    row.addWidget(left)
    row.addWidget(right)
    shown(win, 640, 300)
    dev = QTest.createTouchDevice()
    (lc, lr), (rc, rr) = left.pad(), right.pad()
    lc, rc = lc.toPoint(), rc.toPoint()
    up, side = lc - QtCore.QPoint(0, int(lr * 0.8)), rc + QtCore.QPoint(int(rr * 0.5), 0)
    QTest.touchEvent(win, dev).press(0, left.mapTo(win, lc), win).press(1, right.mapTo(win, rc), win).commit()
    QTest.touchEvent(win, dev).move(0, left.mapTo(win, up), win).move(1, right.mapTo(win, side), win).commit()
    wait_until(lambda: left_m.active and right_m.active, "both pads driving")
    left.refresh(left_m.state)
    right.refresh(right_m.state)
    saved.append(save_view(win, out / "teleop-two-pads.png"))
    QTest.touchEvent(win, dev).release(0, left.mapTo(win, up), win).release(1, right.mapTo(win, side), win).commit()
    for model, _view in pads:
        model.stop()
    for widget in keep:
        widget.close()
    return saved


def save_window(window: QtWidgets.QWidget, path: Path, size: tuple[int, int]) -> Path:
    """Grab the whole window (at ``size``) into ``path``."""
    settle()
    if (window.width(), window.height()) != size:
        raise SystemExit(f"make_screenshots: {path.name}: the window is {window.width()}x{window.height()}, "
                         f"not {size}")
    return save_view(window, path)


def display(out: Path) -> list[Path]:
    """The demo in both themes and at the largest text size, and the fleet demo of three vessels on a
    1024x600 tablet and in a 1280x800 window (laid out for each, as ``rcon --demo --robots 3`` does)."""
    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication(sys.argv[:1])
    app.setApplicationName("RCON")

    from rcon_core.app import theme
    from rcon_core.app.config import AppConfig
    from rcon_core.app.demo import demo_workspace
    from rcon_core.app.display_settings import set_display
    from rcon_core.app.fleet_demo import connect_fleet, fit_fleet, fleet_sims, fleet_workspace
    from rcon_core.app.main_window import MainWindow
    from rcon_core.bridge import ConnectionState
    from rcon_core.plugins import PluginManager
    from rcon_core.sim import SimServer

    plugins = PluginManager(environ={})
    plugins.load_entry_points()
    saved: list[Path] = []
    shots = (("demo", "sunlight", 100, (1280, 800)), ("demo-night", "night", 100, (1280, 800)),
             ("text-200-1024x600", "sunlight", 200, (1024, 600)))
    for name, look, text_size, size in shots:
        with tempfile.TemporaryDirectory(prefix="rcon-shots-") as tmp, SimServer.in_thread(port=0) as robot:
            win = MainWindow(AppConfig(Path(tmp) / "config"), plugins, layout_path=Path(tmp) / "demo.json",
                             demo=lambda: demo_workspace(plugins))
            win.resize(*size)
            win.show()
            QTest.qWaitForWindowExposed(win)
            try:
                set_display(win.config, win.notice, look, text_size)
                win.connect_to(robot.url, remember=False)
                wait_until(lambda win=win: win.connection.state is ConnectionState.CONNECTED, "the connection")
                shown = {w.id for w in win.controller.canvas.widgets}
                hosted = [h for h in win.host.hosted.values() if h.widget.id in shown]
                wait_until(lambda hosted=hosted: all(h.model is not None and h.model.state.count > 0 for h in hosted
                                                     if h.widget.binding.role.value == "subscribe"), "live data")
                settle(1500)
                saved.append(save_window(win, out / f"{name}.png", size))
            finally:
                win.shutdown()
                win.close()
    theme.apply(app, theme.DEFAULT_THEME, 100)
    for size in ((1024, 600), (1280, 800)):
        with tempfile.TemporaryDirectory(prefix="rcon-shots-") as tmp, fleet_sims(3) as sims:
            win = MainWindow(AppConfig(Path(tmp) / "config"), plugins, layout_path=Path(tmp) / "fleet.json",
                             demo=lambda: fleet_workspace(3, plugins))
            win.resize(*size)
            win.show()
            QTest.qWaitForWindowExposed(win)
            try:
                fit_fleet(win, 3, plugins)
                connect_fleet(win, [s.url for s in sims])
                shown = {w.id for w in win.controller.canvas.widgets}
                hosted = [h for h in win.host.hosted.values() if h.widget.id in shown]
                wait_until(lambda hosted=hosted: all(h.model is not None and h.model.state.count > 0 for h in hosted
                                                     if h.widget.binding.role.value == "subscribe"),
                           "every vessel's data")
                wait_until(lambda hosted=hosted: all(not h.frame.badge.isVisible() for h in hosted), "no badge left")
                settle(1500)
                saved.append(save_window(win, out / f"fleet-3-{size[0]}x{size[1]}.png", size))
            finally:
                win.shutdown()
                win.close()
    return saved


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="Make the screenshots of docs/using-the-app.md and of the "
                                                 "sensor widgets.")
    parser.add_argument("--out", type=Path, default=Path(__file__).resolve().parent / "screenshots",
                        help="where to write the PNGs (default: docs/screenshots)")
    parser.add_argument("--only", choices=("app", "sensors", "display", "video"), help="make only one of the sets")
    args = parser.parse_args(argv)
    if args.only in (None, "sensors"):  # first: the app's theme, once applied, stays on the application
        sensors(args.out / "sensors")
    if args.only in (None, "app"):
        run(args.out)
    if args.only in (None, "display"):
        display(args.out)
    if args.only in (None, "video"):
        video(args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
