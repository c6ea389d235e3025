"""The layout file on disk: symlinked layouts, file modes, temp files left by a save that was killed,
and two RCON instances on one layout."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest

from rcon_core.canvas import Workspace, WorkspaceFileError, WorkspaceStore, loads_workspace

posix_only = pytest.mark.skipif(os.name != "posix", reason="symlinks, modes and flock are POSIX here")


def names(directory) -> list[str]:
    return sorted(p.name for p in directory.iterdir())


# ------------------------------------------------------------------------------------------- symlinks
@posix_only
def test_saving_a_symlinked_layout_writes_the_target_and_keeps_the_link_and_the_mode(tmp_path):
    shared = tmp_path / "shared"
    config = tmp_path / "config"
    shared.mkdir()
    config.mkdir()
    target = shared / "boat.json"
    WorkspaceStore(target).save(Workspace.new("Before"))
    os.chmod(target, 0o644)
    link = config / "workspace.json"
    link.symlink_to(os.path.relpath(target, config))  # a relative link, as people make them

    store = WorkspaceStore(link)
    assert store.load().canvases[0].name == "Before"
    store.save(Workspace.new("After"))
    assert link.is_symlink() and os.readlink(link) == os.path.relpath(target, config)
    assert json.loads(target.read_text())["canvases"][0]["name"] == "After"
    assert oct(target.stat().st_mode & 0o777) == oct(0o644)
    assert names(config) == ["workspace.json"] and names(shared) == ["boat.json"]  # no temp file left
    assert WorkspaceStore(link).load().canvases[0].name == "After"


@posix_only
def test_a_link_through_a_linked_directory_and_a_dangling_link(tmp_path):
    real = tmp_path / "real"
    real.mkdir()
    (tmp_path / "alias").symlink_to(real, target_is_directory=True)
    chained = tmp_path / "layout.json"
    chained.symlink_to(tmp_path / "alias" / "ws.json")  # dangling until the first save
    store = WorkspaceStore(chained)
    assert store.load().canvases[0].name == "Main"  # no file yet
    store.save(Workspace.new("First"))
    assert chained.is_symlink() and (real / "ws.json").is_file()
    assert oct((real / "ws.json").stat().st_mode & 0o777) == oct(0o600)  # a new file is private
    assert loads_workspace((real / "ws.json").read_bytes()).canvases[0].name == "First"


@posix_only
def test_a_plain_file_keeps_its_mode(tmp_path):
    path = tmp_path / "ws.json"
    store = WorkspaceStore(path)
    store.save(Workspace.new())
    os.chmod(path, 0o640)
    store.save(Workspace.new("Again"))
    assert oct(path.stat().st_mode & 0o777) == oct(0o640)


@posix_only
def test_an_unreadable_symlinked_layout_is_kept_by_its_target_and_moved_aside_behind_the_link(tmp_path):
    target = tmp_path / "shared" / "boat.json"
    target.parent.mkdir()
    target.write_text('{"format": "rcon-workspace", "version": 1, "canvases": [{"id": "c", "name": "A", '
                      '"locked": "no"}]}')
    bad = target.read_bytes()
    link = tmp_path / "workspace.json"
    link.symlink_to(target)
    store = WorkspaceStore(link)
    with pytest.raises(WorkspaceFileError, match="locked must be true or false") as info:
        store.load()
    assert info.value.backup.parent == target.parent and info.value.backup.read_bytes() == bad
    kept = store.move_aside()  # the operator starts a new layout
    assert kept == info.value.backup and link.is_symlink() and not target.exists()
    store.save(Workspace.new("Fresh"))
    assert link.is_symlink() and WorkspaceStore(target).load().canvases[0].name == "Fresh"


# ------------------------------------------------------------------------------------ stale temp files
def age(path, seconds: float) -> None:
    past = time.time() - seconds
    os.utime(path, (past, past))


def test_temp_files_of_a_killed_save_are_removed_when_the_store_opens(tmp_path):
    path = tmp_path / "ws.json"
    WorkspaceStore(path).save(Workspace.new("Kept"))
    before = path.read_bytes()
    stale = [tmp_path / f".ws.json.{s}.tmp" for s in ("abcd1234", "k_9x0q2z")]
    young = tmp_path / ".ws.json.young123.tmp"
    not_ours = [tmp_path / n for n in (".ws.json.TOOLONG12345.tmp", ".other.json.abcd1234.tmp", "ws.json.tmp",
                                       ".ws.json.abcd1234.tmp.keep", "ws.json.unreadable-20260101-000000")]
    for p in [*stale, young, *not_ours]:
        p.write_text('{"half": ')
    for p in [*stale, *not_ours]:
        age(p, 60)
    store = WorkspaceStore(path)
    assert sorted(store.cleaned) == sorted(stale)
    assert not any(p.exists() for p in stale)
    assert young.exists() and all(p.exists() for p in not_ours)
    assert path.read_bytes() == before and store.load().canvases[0].name == "Kept"


SLOW_WRITER = textwrap.dedent("""
    import os, sys
    from rcon_core.canvas import Workspace, WorkspaceStore

    real_replace = os.replace
    def stuck(src, dst):  # a save that hangs between writing its temp file and the rename
        print(src, flush=True)
        sys.stdin.readline()
        real_replace(src, dst)
    os.replace = stuck
    WorkspaceStore(sys.argv[1]).save(Workspace.new("From the other instance"))
    print("saved", flush=True)
""")


@posix_only
def test_two_instances_on_one_layout_never_remove_a_save_in_progress(tmp_path):
    path = tmp_path / "ws.json"
    WorkspaceStore(path).save(Workspace.new("First"))
    other = subprocess.Popen([sys.executable, "-c", SLOW_WRITER, str(path)], stdin=subprocess.PIPE,
                             stdout=subprocess.PIPE, text=True)
    try:
        temp = tmp_path / os.path.basename(other.stdout.readline().strip())
        assert temp.exists() and temp.name.startswith(".ws.json.")
        age(temp, 3600)  # old, but its writer is alive and holds it
        assert WorkspaceStore(path).cleaned == [] and temp.exists()
        other.stdin.write("\n")
        other.stdin.flush()
        assert other.stdout.readline().strip() == "saved"
        assert other.wait(timeout=30) == 0
    finally:
        if other.poll() is None:
            other.kill()
            other.wait()
    assert WorkspaceStore(path).load().canvases[0].name == "From the other instance"
    assert names(tmp_path) == ["ws.json"]


@posix_only
def test_a_writer_killed_mid_save_leaves_a_temp_file_the_next_start_removes(tmp_path):
    path = tmp_path / "ws.json"
    WorkspaceStore(path).save(Workspace.new("First"))
    before = path.read_bytes()
    other = subprocess.Popen([sys.executable, "-c", SLOW_WRITER, str(path)], stdin=subprocess.PIPE,
                             stdout=subprocess.PIPE, text=True)
    try:
        temp = tmp_path / os.path.basename(other.stdout.readline().strip())
        other.send_signal(signal.SIGKILL)
        other.wait(timeout=30)
    finally:
        if other.poll() is None:
            other.kill()
            other.wait()
    assert temp.exists() and path.read_bytes() == before
    assert WorkspaceStore(path).cleaned == []  # just now: it might be a writer that has not locked it yet
    age(temp, 60)
    store = WorkspaceStore(path)
    assert store.cleaned == [temp] and names(tmp_path) == ["ws.json"]
    assert store.load().canvases[0].name == "First"


# -------------------------------------------------------------------------------------- a full disk
def test_when_no_copy_can_be_kept_the_file_is_neither_moved_nor_overwritten(tmp_path, monkeypatch):
    from rcon_core.canvas import files

    path = tmp_path / "ws.json"
    bad = b'{"format": "rcon-workspace", "version": 1, "canvases": [{"id": "c", "name": "A", "locked": 1}]}'
    path.write_bytes(bad)

    def disk_full(src, dst, **_kw):
        open(dst, "wb").close()  # a partial copy, then the error
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(files.shutil, "copy2", disk_full)
    store = WorkspaceStore(path)
    with pytest.raises(WorkspaceFileError, match="locked must be true or false") as info:
        store.load()
    assert info.value.backup is None and store.read_only
    with pytest.raises(WorkspaceFileError, match="no copy of it could be kept"):
        store.move_aside()
    assert store.read_only and path.read_bytes() == bad
    with pytest.raises(WorkspaceFileError, match="not saving over"):
        store.save(Workspace.new())
    assert names(tmp_path) == ["ws.json"]  # the partial copy is gone, the file is as it was
