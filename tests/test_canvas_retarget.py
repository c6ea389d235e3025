"""rcon_core/canvas/retarget.py: the names a re-targeted canvas uses on another robot (issue 21.6)."""

from __future__ import annotations

from rcon_core.canvas import Binding, Document, Geometry, Workspace
from rcon_core.canvas.retarget import plan_retarget, rename_settings, setting_names
from rcon_core.canvas.robots import Robot

BOAT2 = {"/boat2/cmd_vel", "/boat2/gps/fix", "/boat2/lights/set", "/rosout", "/map", "/rosapi/topics"}


def test_names_are_mapped_through_the_targets_namespace_and_what_it_lacks_is_listed():
    plan = plan_retarget(["/cmd_vel", "/gps/fix", "/rosout", "/map", "/lab/thing", "/cmd_vel"], BOAT2)
    assert plan.renames == {"/cmd_vel": "/boat2/cmd_vel", "/gps/fix": "/boat2/gps/fix"}
    assert plan.missing == ("/lab/thing",) and plan.namespace == "/boat2" and plan.checked and not plan.quiet
    text = plan.describe("boat2")
    assert "Names mapped in boat2's namespace /boat2:" in text and "/cmd_vel → /boat2/cmd_vel" in text
    assert "Not on boat2" in text and "/lab/thing" in text


def test_a_source_namespace_is_swapped_for_the_targets_or_dropped():
    assert plan_retarget(["/boat1/cmd_vel"], BOAT2).renames == {"/boat1/cmd_vel": "/boat2/cmd_vel"}
    plain = plan_retarget(["/boat1/cmd_vel", "/boat1/gps/fix"], {"/cmd_vel", "/gps/fix"})
    assert plain.renames == {"/boat1/cmd_vel": "/cmd_vel", "/boat1/gps/fix": "/gps/fix"} and not plain.missing


def test_names_the_target_has_are_kept_and_an_unknown_target_is_not_checked():
    assert plan_retarget(["/cmd_vel", "/rosout"], {"/cmd_vel", "/rosout"}).quiet
    unknown = plan_retarget(["/cmd_vel"], None)
    assert not unknown.checked and not unknown.renames and "not checked" in unknown.describe("boat2")


def test_one_namespace_wins_a_name_found_only_elsewhere_is_not_guessed_at():
    target = {"/boat2/cmd_vel", "/boat2/gps/fix", "/other/camera"}
    plan = plan_retarget(["/cmd_vel", "/gps/fix", "/camera"], target)
    assert plan.renames == {"/cmd_vel": "/boat2/cmd_vel", "/gps/fix": "/boat2/gps/fix"}
    assert plan.missing == ("/camera",)


def test_topic_names_in_settings_are_found_and_renamed_but_not_other_paths():
    settings = {"state_topic": "/lights/state", "cache_dir": "/home/tiles", "children": [
        {"kind": "std.switch", "settings": {"state_topic": "/lights/state"}}], "units": "m/s"}
    assert sorted(setting_names(settings)) == ["/lights/state", "/lights/state"]
    renamed = rename_settings(settings, {"/lights/state": "/boat2/lights/state", "/home/tiles": "/x"})
    assert renamed["state_topic"] == "/boat2/lights/state" and renamed["cache_dir"] == "/home/tiles"
    assert renamed["children"][0]["settings"]["state_topic"] == "/boat2/lights/state"
    assert settings["state_topic"] == "/lights/state"  # a copy


def test_duplicate_for_robot_applies_the_renames_in_one_undo_step():
    ws = Workspace.new("Drive")
    ws.robots = [Robot("r-1", "Alpha"), Robot("r-2", "boat2")]
    doc = Document(ws)
    w = doc.add_widget(doc.current.id, "std.switch", Binding("/lights/set", "std_srvs/SetBool", "call"),
                       Geometry(0, 0, 100, 100), {"state_topic": "/lights/state"})
    dup = doc.duplicate_for_robot(doc.current.id, "r-2", renames={"/lights/set": "/boat2/lights/set",
                                                                  "/lights/state": "/boat2/lights/state"})
    [copy] = dup.widgets
    assert (copy.binding.name, copy.binding.robot, copy.settings["state_topic"]) == (
        "/boat2/lights/set", "r-2", "/boat2/lights/state")
    assert (w.binding.name, w.settings["state_topic"]) == ("/lights/set", "/lights/state")
    doc.undo()
    assert len(doc.workspace.canvases) == 1
