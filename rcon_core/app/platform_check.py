"""Before the window opens on a Linux desktop: can Qt's X11 platform plugin (xcb) load at all?

Qt's xcb plugin (``PySide6/Qt/plugins/platforms/libqxcb.so``) links a dozen X11 client libraries that a
fresh desktop may lack (``libxcb-icccm4``, ``libxcb-keysyms1``, ...). When one is missing Qt aborts the
process with "Could not load the Qt platform plugin "xcb"" and names ``xcb-cursor0``, often already
installed. So ``rcon`` looks first: it reads the libraries the plugin needs from the plugin file itself
(its ELF ``DT_NEEDED`` entries), asks the system loader for each one (the libraries PySide6 bundles are
left out), and when any is missing prints which packages to install, with their Debian/Ubuntu and Fedora
names, and exits. No Qt here: this runs before Qt loads a platform plugin.

It looks only when Qt would use xcb: on Linux, with ``QT_QPA_PLATFORM`` unset (and no Wayland session)
or ``xcb``, and an X display (``DISPLAY``).
"""

from __future__ import annotations

import ctypes
import importlib.util
import os
import struct
import sys
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path

__all__ = ["PACKAGES", "advice", "elf_needed", "missing_libraries", "xcb_problem"]

#: soname -> (Debian/Ubuntu package, Fedora package) for what Qt 6's xcb plugin links
PACKAGES: dict[str, tuple[str, str]] = {
    "libxcb-cursor.so.0": ("libxcb-cursor0", "xcb-util-cursor"),
    "libxcb-icccm.so.4": ("libxcb-icccm4", "xcb-util-wm"),
    "libxcb-keysyms.so.1": ("libxcb-keysyms1", "xcb-util-keysyms"),
    "libxcb-image.so.0": ("libxcb-image0", "xcb-util-image"),
    "libxcb-render-util.so.0": ("libxcb-render-util0", "xcb-util-renderutil"),
    "libxcb-util.so.1": ("libxcb-util1", "xcb-util"),
    "libxcb-xinerama.so.0": ("libxcb-xinerama0", "libxcb"),
    "libxcb-xkb.so.1": ("libxcb-xkb1", "libxcb"),
    "libxcb-randr.so.0": ("libxcb-randr0", "libxcb"),
    "libxcb-shape.so.0": ("libxcb-shape0", "libxcb"),
    "libxcb-shm.so.0": ("libxcb-shm0", "libxcb"),
    "libxcb-sync.so.1": ("libxcb-sync1", "libxcb"),
    "libxcb-xfixes.so.0": ("libxcb-xfixes0", "libxcb"),
    "libxcb-render.so.0": ("libxcb-render0", "libxcb"),
    "libxcb.so.1": ("libxcb1", "libxcb"),
    "libxkbcommon-x11.so.0": ("libxkbcommon-x11-0", "libxkbcommon-x11"),
    "libxkbcommon.so.0": ("libxkbcommon0", "libxkbcommon"),
    "libX11-xcb.so.1": ("libx11-xcb1", "libX11-xcb"),
    "libX11.so.6": ("libx11-6", "libX11"),
    "libGL.so.1": ("libgl1", "libglvnd-glx"),
    "libEGL.so.1": ("libegl1", "libglvnd-egl"),
    "libfontconfig.so.1": ("libfontconfig1", "fontconfig"),
    "libfreetype.so.6": ("libfreetype6", "freetype"),
    "libdbus-1.so.3": ("libdbus-1-3", "dbus-libs"),
    "libglib-2.0.so.0": ("libglib2.0-0", "glib2"),
}
#: what PySide6 ships beside the plugin (found through its own RUNPATH, never by the system loader)
BUNDLED_PREFIXES = ("libQt6", "libicu", "libpyside6", "libshiboken6")
DT_NEEDED = 1
SHT_DYNAMIC = 6


def elf_needed(path: Path | str) -> list[str]:
    """The ``DT_NEEDED`` entries (sonames) of an ELF shared object, in order. Raises ValueError for a file
    that is not one (or one this small reader does not understand)."""
    data = Path(path).read_bytes()
    if data[:4] != b"\x7fELF":
        raise ValueError(f"{path}: not an ELF file")
    bits, order = data[4], {1: "<", 2: ">"}.get(data[5])
    if bits not in (1, 2) or order is None:
        raise ValueError(f"{path}: unknown ELF class or byte order")
    wide = bits == 2
    if wide:
        shoff, = struct.unpack_from(order + "Q", data, 0x28)
        shentsize, shnum = struct.unpack_from(order + "HH", data, 0x3A)
        section = order + "IIQQQQIIQQ"
        entry = order + "qQ"
    else:
        shoff, = struct.unpack_from(order + "I", data, 0x20)
        shentsize, shnum = struct.unpack_from(order + "HH", data, 0x2E)
        section = order + "IIIIIIIIII"
        entry = order + "iI"
    headers = [struct.unpack_from(section, data, shoff + k * shentsize) for k in range(shnum)]
    for _name, kind, _flags, _addr, offset, size, link, _info, _align, _entsize in headers:
        if kind != SHT_DYNAMIC:
            continue
        strtab_offset = headers[link][4]
        out = []
        step = struct.calcsize(entry)
        for pos in range(offset, offset + size, step):
            tag, value = struct.unpack_from(entry, data, pos)
            if tag == 0:
                break
            if tag == DT_NEEDED:
                end = data.index(b"\0", strtab_offset + value)
                out.append(data[strtab_offset + value:end].decode("utf-8", "replace"))
        return out
    raise ValueError(f"{path}: no dynamic section")


def can_load(soname: str) -> bool:
    """Whether the system loader finds and loads ``soname``."""
    try:
        ctypes.CDLL(soname)
    except OSError:
        return False
    return True


def missing_libraries(needed: Iterable[str], loads: Callable[[str], bool] = can_load) -> list[str]:
    """Of ``needed`` (sonames), those the system cannot load (PySide6's own libraries left out)."""
    return [name for name in needed if not name.startswith(BUNDLED_PREFIXES) and not loads(name)]


def advice(missing: list[str]) -> str:
    """What to tell the operator: the libraries missing and the packages that bring them."""
    debian = sorted({PACKAGES[m][0] for m in missing if m in PACKAGES})
    fedora = sorted({PACKAGES[m][1] for m in missing if m in PACKAGES})
    unknown = [m for m in missing if m not in PACKAGES]
    lines = [f"rcon: Qt's X11 platform plugin (xcb) cannot load: missing {', '.join(missing)}.",
             "Install them, then start rcon again:"]
    if debian:
        lines.append(f"  Debian/Ubuntu:  sudo apt install {' '.join(debian)}")
    if fedora:
        lines.append(f"  Fedora:         sudo dnf install {' '.join(fedora)}")
    if unknown:
        lines.append(f"  (and whatever package provides {', '.join(unknown)})")
    lines.append("Without a screen, QT_QPA_PLATFORM=offscreen runs the app headless.")
    return "\n".join(lines)


def xcb_plugin() -> Path | None:
    """PySide6's xcb platform plugin, if PySide6 is installed and has one (found without importing Qt)."""
    spec = importlib.util.find_spec("PySide6")
    if spec is None or not spec.submodule_search_locations:
        return None
    for base in spec.submodule_search_locations:
        plugin = Path(base) / "Qt" / "plugins" / "platforms" / "libqxcb.so"
        if plugin.is_file():
            return plugin
    return None


def uses_xcb(environ: Mapping[str, str], platform: str = sys.platform) -> bool:
    """Whether Qt will try its xcb plugin first: Linux, an X display, and xcb asked for or left to Qt
    (Qt 6 prefers Wayland in a Wayland session)."""
    if not platform.startswith("linux") or not environ.get("DISPLAY"):
        return False
    asked = environ.get("QT_QPA_PLATFORM", "").split(";")[0].split(":")[0].strip()
    if asked:
        return asked == "xcb"
    return not (environ.get("WAYLAND_DISPLAY") and environ.get("XDG_SESSION_TYPE") == "wayland")


def xcb_problem(environ: Mapping[str, str] | None = None, *, platform: str = sys.platform,
                plugin: Path | None = None, loads: Callable[[str], bool] = can_load) -> str | None:
    """The message to print when Qt's xcb plugin would fail to load (None: nothing to say)."""
    environ = os.environ if environ is None else environ
    if not uses_xcb(environ, platform):
        return None
    plugin = plugin if plugin is not None else xcb_plugin()
    if plugin is None:
        return None
    try:
        needed = elf_needed(plugin)
    except (OSError, ValueError, struct.error, IndexError):
        return None  # not a file we can read: let Qt try and say what it says
    missing = missing_libraries(needed, loads)
    return advice(missing) if missing else None
