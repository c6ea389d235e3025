"""``rcon`` on a Linux desktop whose X11 libraries are incomplete (issue 21.9): Qt's xcb plugin would abort
the process, so the app reads what the plugin links, asks the loader for each library and prints the
packages to install (Debian/Ubuntu and Fedora names), then exits 1. Tested with fake library lists, on the
real plugin file, and through the real ``rcon`` command where this machine lacks a library."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from rcon_core.app.platform_check import (
    PACKAGES,
    advice,
    elf_needed,
    missing_libraries,
    uses_xcb,
    xcb_plugin,
    xcb_problem,
)

#: what Qt 6.11's libqxcb.so links (readelf -d), the X11 part
QT_XCB = ["libQt6XcbQpa.so.6", "libQt6Gui.so.6", "libGL.so.1", "libQt6Core.so.6", "libxkbcommon.so.0",
          "libxkbcommon-x11.so.0", "libxcb-cursor.so.0", "libxcb-icccm.so.4", "libxcb-util.so.1",
          "libxcb-image.so.0", "libxcb-keysyms.so.1", "libxcb-randr.so.0", "libxcb-render-util.so.0",
          "libxcb-shm.so.0", "libxcb-sync.so.1", "libxcb-xfixes.so.0", "libxcb-render.so.0", "libxcb-shape.so.0",
          "libxcb-xkb.so.1", "libxcb.so.1", "libX11-xcb.so.1", "libX11.so.6", "libstdc++.so.6", "libc.so.6"]
DESKTOP = {"DISPLAY": ":0"}


def fresh_debian(name: str) -> bool:
    """A fresh Debian desktop's loader: xcb-cursor0 is there, icccm4 and keysyms1 are not."""
    return name not in ("libxcb-icccm.so.4", "libxcb-keysyms.so.1")


def test_the_missing_libraries_and_their_packages_are_named():
    missing = missing_libraries(QT_XCB, fresh_debian)
    assert missing == ["libxcb-icccm.so.4", "libxcb-keysyms.so.1"]  # Qt's own libraries never asked for
    text = advice(missing)
    assert "sudo apt install libxcb-icccm4 libxcb-keysyms1" in text
    assert "sudo dnf install xcb-util-keysyms xcb-util-wm" in text
    assert "libxcb-icccm.so.4, libxcb-keysyms.so.1" in text and "xcb-cursor0" not in text
    # every library the plugin may link has both names
    for soname in QT_XCB:
        if not soname.startswith(("libQt6", "libstdc++", "libc.")):
            assert soname in PACKAGES, soname
    assert "libxcb-cursor0" in advice(missing_libraries(QT_XCB, lambda n: n != "libxcb-cursor.so.0"))
    assert "whatever package provides libweird.so.9" in advice(["libweird.so.9"])


def test_it_looks_only_when_qt_would_use_xcb():
    assert uses_xcb(DESKTOP, "linux")
    assert uses_xcb({**DESKTOP, "QT_QPA_PLATFORM": "xcb"}, "linux")
    assert not uses_xcb({**DESKTOP, "QT_QPA_PLATFORM": "offscreen"}, "linux")
    assert not uses_xcb({**DESKTOP, "QT_QPA_PLATFORM": "wayland"}, "linux")
    assert not uses_xcb({}, "linux")  # no display: headless, Qt says so itself
    assert not uses_xcb(DESKTOP, "win32")
    assert not uses_xcb({**DESKTOP, "WAYLAND_DISPLAY": "wayland-0", "XDG_SESSION_TYPE": "wayland"}, "linux")
    assert uses_xcb({**DESKTOP, "WAYLAND_DISPLAY": "wayland-0", "XDG_SESSION_TYPE": "x11"}, "linux")


def test_the_plugin_file_is_read_for_what_it_links(tmp_path):
    plugin = xcb_plugin()
    if plugin is None or not sys.platform.startswith("linux"):
        pytest.skip("PySide6 ships libqxcb.so on Linux only")
    needed = elf_needed(plugin)
    assert "libxcb.so.1" in needed and "libxcb-icccm.so.4" in needed and "libQt6Gui.so.6" in needed
    problem = xcb_problem(DESKTOP, platform="linux", plugin=plugin, loads=fresh_debian)
    assert problem is not None and "libxcb-icccm4" in problem
    assert xcb_problem(DESKTOP, platform="linux", plugin=plugin, loads=lambda _n: True) is None
    assert xcb_problem({"QT_QPA_PLATFORM": "offscreen", **DESKTOP}, platform="linux", plugin=plugin,
                       loads=fresh_debian) is None
    not_elf = tmp_path / "libqxcb.so"
    not_elf.write_text("#!/bin/sh\n")
    with pytest.raises(ValueError, match="not an ELF"):
        elf_needed(not_elf)
    assert xcb_problem(DESKTOP, platform="linux", plugin=not_elf, loads=fresh_debian) is None  # Qt says


def test_rcon_prints_the_packages_and_exits_instead_of_aborting(tmp_path):
    problem = xcb_problem(DESKTOP, platform=sys.platform)
    if problem is None:
        pytest.skip("this machine has every library Qt's xcb plugin links (the fake lists above cover it)")
    env = {k: v for k, v in os.environ.items() if k not in ("QT_QPA_PLATFORM", "WAYLAND_DISPLAY")}
    env.update(DISPLAY=":0", RCON_CONFIG_DIR=str(tmp_path))
    done = subprocess.run([sys.executable, "-m", "rcon_core", "--demo", "--quit-after", "1"], env=env,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 1, done.stderr
    assert "sudo apt install" in done.stderr and "sudo dnf install" in done.stderr
    assert "Aborted" not in done.stderr and "could not load the Qt platform plugin" not in done.stderr.lower()
