"""Issue 24.6: strings that were really kinds are types now (``StrEnum``s and small tagged records), and the
old words still read the same, so nothing stored or compared by value breaks."""

from __future__ import annotations

import pytest

from rcon_core.bridge import BridgeStats
from rcon_core.bridge.freshness import LinkEvent
from rcon_core.canvas import Change, ChangeKind, Document, Workspace
from rcon_core.plugins import CallPhase, GoalPhase
from rcon_core.plugins.registry import TypeContributions, TypeDefinition, TypeKind


def test_a_document_change_names_its_kind():
    doc = Document(Workspace.new("Ops"))
    seen: list[Change] = []
    doc.add_listener(seen.append)
    doc.create_canvas("Nav")
    assert [c.what for c in seen] == [ChangeKind.CANVAS_ADDED]
    assert seen[0].what == "canvas-added"  # the old word still compares equal
    assert Change("robots-changed").what is ChangeKind.ROBOTS_CHANGED  # and is taken
    with pytest.raises(ValueError):
        Change("robot-changed")  # a misspelt kind is refused, not a new kind


def test_a_contributed_definition_names_how_it_is_given():
    reg = TypeContributions("lab")
    reg.add_msg("lab_msgs/Gripper", "float64 opening\n")
    reg.add_srv("lab_srvs/Pump", "bool on\n---\nbool ok\n")
    reg.add_typedefs([{"type": "lab_msgs/X", "fieldnames": [], "fieldtypes": []}])
    assert [d.kind for d in reg.definitions] == [TypeKind.MSG, TypeKind.SRV, TypeKind.TYPEDEFS]
    assert TypeDefinition("msg", "a/B").kind is TypeKind.MSG and TypeKind.MSG == "msg"


def test_phases_and_link_events_are_enums_that_read_as_their_words():
    assert CallPhase("ok") is CallPhase.OK and CallPhase.FAILED == "failed"
    assert {p for p in GoalPhase if p.final} == {GoalPhase.SUCCEEDED, GoalPhase.CANCELED, GoalPhase.ABORTED,
                                                 GoalPhase.FAILED, GoalPhase.UNKNOWN}
    assert {p for p in GoalPhase if p.running} == {GoalPhase.ACTIVE, GoalPhase.CANCELING}
    assert [e.value for e in LinkEvent] == ["latency", "stalled", "recovered", "cut", "timeout"]


def test_the_bridge_counters_are_a_record_that_still_reads_by_name():
    stats = BridgeStats()
    stats.connects += 2
    assert stats["connects"] == 2 and stats.get("connects") == 2 and dict(stats)["connects"] == 2
    assert stats.as_dict() == dict(stats) and stats.get("no_such_counter", 7) == 7
    with pytest.raises(KeyError):
        stats["conects"]
    with pytest.raises(AttributeError):
        stats.conects = 1  # type: ignore[attr-defined]  # a misspelt counter is an error, not a new key
