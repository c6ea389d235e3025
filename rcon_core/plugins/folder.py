"""The plugins folder: a lab's widget package added to an installed RCON app without rebuilding it.

The one-folder app (``tox -e bundle``, see ``docs/install-on-a-tablet.md``) has no pip. A lab's widget
package goes into its plugins folder instead: ``rcon plugins install WHEEL`` unpacks the wheel there,
each distribution in a folder of its own (``<folder>/<name>/``: its packages and its ``.dist-info``).
:func:`activate`, run when the ``rcon`` command starts, puts each of those folders on ``sys.path``, so
``importlib.metadata`` finds the package's entry points (group ``rcon.widgets``) exactly as it finds an
installed distribution's, and the plugin manager loads it like any other (a broken one fails alone).

Where the folder is: ``$RCON_PLUGINS_DIR`` when set; else, in the frozen app, ``plugins`` in the user's
data folder (``%LOCALAPPDATA%\\rcon\\plugins`` on Windows, ``~/.local/share/rcon/plugins`` on Linux). A
pip installation has no plugins folder unless ``RCON_PLUGINS_DIR`` is set: there ``pip install`` is the
way, and a second way to the same end would only confuse.

What is refused, with the reason, before anything is written (:class:`PluginInstallError`): a file that
is not a wheel; a wheel with compiled code (the app's Python and libraries are fixed; only pure-Python
wheels, ``py3-none-any``, fit every bundle); a wheel that offers no ``rcon.widgets`` entry point; one
named like a distribution the app already has; one whose requirements the app does not meet (a bundle
cannot install more: the lab vendors the code, or asks for a bundle built with it); a member path that
leaves its folder. Installing replaces an older version of the same distribution in one step (the new
folder is complete before the old one is removed).
"""

from __future__ import annotations

import importlib
import importlib.metadata as md
import os
import re
import shutil
import sys
import tempfile
import zipfile
from collections.abc import Mapping
from email.parser import Parser
from pathlib import Path, PurePosixPath

import attrs

__all__ = ["ENV", "PluginInstallError", "InstalledPlugin", "plugins_dir", "activate", "install", "remove", "canonical",
           "installed"]

ENV = "RCON_PLUGINS_DIR"
GROUP = "rcon.widgets"
#: name-version(-build)-python-abi-platform.whl (PEP 427)
WHEEL_RE = re.compile(r"^(?P<name>[^-]+)-(?P<version>[^-]+)(-\d[^-]*)?-(?P<py>[^-]+)-(?P<abi>[^-]+)-(?P<plat>[^-]+)\.whl$")


class PluginInstallError(ValueError):
    """A wheel that cannot go into the plugins folder; the message says why and what to do instead."""


@attrs.frozen
class InstalledPlugin:
    name: str  #: the distribution name, as its metadata spells it
    version: str
    path: Path  #: its folder inside the plugins folder


def plugins_dir(environ: Mapping[str, str] | None = None, frozen: bool | None = None) -> Path | None:
    """The plugins folder, or None for a pip installation without ``RCON_PLUGINS_DIR``."""
    env = os.environ if environ is None else environ
    if env.get(ENV):
        return Path(env[ENV])
    if frozen if frozen is not None else getattr(sys, "frozen", False):
        import platformdirs

        return Path(platformdirs.user_data_dir("rcon", appauthor=False)) / "plugins"
    return None


def _folders(root: Path) -> list[Path]:
    if not root.is_dir():
        return []
    return sorted(p for p in root.iterdir() if p.is_dir() and not p.name.startswith("."))


def activate(root: Path | None = None) -> list[Path]:
    """Put each installed distribution's folder on ``sys.path`` (once); returns the folders added."""
    root = root if root is not None else plugins_dir()
    if root is None:
        return []
    added = []
    for folder in _folders(root):
        if str(folder) not in sys.path:
            sys.path.append(str(folder))
            added.append(folder)
    if added:
        importlib.invalidate_caches()
    return added


def installed(root: Path) -> list[InstalledPlugin]:
    """What the plugins folder holds."""
    out = []
    for folder in _folders(root):
        for info in folder.glob("*.dist-info"):
            meta = Parser().parsestr((info / "METADATA").read_text(encoding="utf-8"), headersonly=True)
            out.append(InstalledPlugin(meta["Name"], meta["Version"], folder))
    return out


def canonical(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def _read_wheel(wheel: Path) -> tuple[zipfile.ZipFile, str, dict[str, str], str]:
    """(open zip, dist-info folder name, METADATA headers, entry_points.txt) of a wheel; refuses others."""
    if not wheel.is_file():
        raise PluginInstallError(f"{wheel}: no such file")
    found = WHEEL_RE.match(wheel.name)
    if found is None:
        raise PluginInstallError(f"{wheel.name} is not a wheel (name-version-python-abi-platform.whl); build one "
                                 "with `pip wheel --no-deps .` in the package's folder")
    if found["abi"] != "none" or found["plat"] != "any":
        raise PluginInstallError(
            f"{wheel.name} holds compiled code ({found['abi']}, {found['plat']}): the app takes pure-Python "
            "wheels only (py3-none-any), since its Python and libraries are fixed. Ask for a bundle built "
            "with the package instead (docs/install-on-a-tablet.md)")
    try:
        zf = zipfile.ZipFile(wheel)
    except zipfile.BadZipFile:
        raise PluginInstallError(f"{wheel.name} is not a readable wheel (not a zip file)") from None
    infos = {n.split("/")[0] for n in zf.namelist() if n.split("/")[0].endswith(".dist-info")}
    if len(infos) != 1:
        zf.close()
        raise PluginInstallError(f"{wheel.name} has {len(infos)} .dist-info folders, a wheel has one")
    info = infos.pop()
    try:
        meta = Parser().parsestr(zf.read(f"{info}/METADATA").decode("utf-8"), headersonly=True)
        entry_points = zf.read(f"{info}/entry_points.txt").decode("utf-8") if f"{info}/entry_points.txt" in \
            zf.namelist() else ""
    except (KeyError, UnicodeDecodeError) as exc:
        zf.close()
        raise PluginInstallError(f"{wheel.name}: unreadable metadata ({exc})") from None
    headers = {"Name": meta["Name"] or "", "Version": meta["Version"] or ""}
    headers["Requires-Dist"] = "\n".join(meta.get_all("Requires-Dist") or [])
    return zf, info, headers, entry_points


def _unmet(requirements: list[str]) -> list[str]:
    """The requirements (without extras) this app does not meet, each with what it has instead."""
    from packaging.requirements import InvalidRequirement, Requirement

    out = []
    for text in requirements:
        try:
            req = Requirement(text)
        except InvalidRequirement:
            out.append(f"{text} (not a valid requirement)")
            continue
        if req.marker is not None and not req.marker.evaluate({"extra": ""}):
            continue
        try:
            have = md.version(req.name)
        except md.PackageNotFoundError:
            out.append(f"{req} (not in this RCON)")
            continue
        if not req.specifier.contains(have, prereleases=True):
            out.append(f"{req} (this RCON has {have})")
    return out


def install(wheel: Path, root: Path) -> InstalledPlugin:
    """Unpack a widget package's wheel into the plugins folder ``root``; see the module docstring for what
    is refused. Returns what was installed; the app finds it on its next start."""
    zf, info, meta, entry_points = _read_wheel(wheel)
    with zf:
        name, version = meta["Name"], meta["Version"]
        if f"[{GROUP}]" not in entry_points:
            raise PluginInstallError(f"{name} {version} offers no widgets: its wheel has no '{GROUP}' entry point "
                                     "(see docs/writing-a-widget-plugin.md)")
        key = canonical(name)
        mine = {p.path.name for p in installed(root)} if root.is_dir() else set()
        try:
            other = md.distribution(name)
        except md.PackageNotFoundError:
            other = None
        if other is not None and key not in mine:
            raise PluginInstallError(f"this RCON already has {name} {other.version}: a plugin may not replace "
                                     "a part of the app")
        unmet = _unmet([r for r in meta["Requires-Dist"].splitlines() if r.strip()])
        if unmet:
            raise PluginInstallError(
                f"{name} {version} needs what this RCON does not have: {'; '.join(unmet)}. The app cannot install "
                "more packages: vendor that code into the widget package, or ask for a bundle built with it")
        members = zf.namelist()
        for member in members:
            path = PurePosixPath(member)
            if path.is_absolute() or ".." in path.parts or "\\" in member or ":" in member:
                raise PluginInstallError(f"{wheel.name}: member {member!r} would be written outside its folder")
        root.mkdir(parents=True, exist_ok=True)
        staging = Path(tempfile.mkdtemp(prefix=f".{key}-", dir=root))
        try:
            zf.extractall(staging)
        except BaseException:
            shutil.rmtree(staging, ignore_errors=True)
            raise
    target = root / key
    old = root / f".{key}-old"
    shutil.rmtree(old, ignore_errors=True)
    if target.exists():
        target.rename(old)
    staging.rename(target)
    shutil.rmtree(old, ignore_errors=True)
    return InstalledPlugin(name, version, target)


def remove(name: str, root: Path) -> InstalledPlugin:
    """Remove a distribution from the plugins folder (by its name, any spelling); KeyError if absent."""
    key = canonical(name)
    for plugin in installed(root):
        if plugin.path.name == key or canonical(plugin.name) == key:
            shutil.rmtree(plugin.path)
            return plugin
    raise KeyError(name)
