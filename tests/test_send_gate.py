"""issue 25.3: confirm-before-send and hold-to-send as a core API any widget can use
(rcon_core.plugins.send_guard), decided without Qt on an injected clock; the std package's Qt SendGuard
runs on it (tests/test_app_confirm_send.py drives that through the app)."""

from __future__ import annotations

from rcon_core.plugins import Binding
from rcon_core.plugins.send_guard import HOLD_S, Outcome, SendGate, describe_send
from rcon_core.testing import ManualClock


def test_hold_to_send_fires_once_after_a_full_hold():
    clock = ManualClock()
    gate = SendGate(ask=False, hold=True, clock=clock)
    assert gate.active and not gate.holding and gate.progress() == 0.0
    gate.press()
    clock.advance(HOLD_S / 2)
    assert gate.holding and gate.progress() == 0.5 and not gate.due()
    clock.advance(HOLD_S / 2)
    assert gate.progress() == 1.0 and gate.due() and not gate.due()  # once
    gate.sent_one()
    clock.advance(3.0)
    assert gate.release() is Outcome.HELD and (gate.sent, gate.refused) == (1, 0) and not gate.holding


def test_a_short_press_sends_nothing_and_is_counted():
    clock = ManualClock()
    gate = SendGate(ask=False, hold=True, clock=clock)
    gate.press()
    clock.advance(HOLD_S * 0.9)
    assert gate.release() is Outcome.TOO_SHORT and (gate.sent, gate.refused) == (0, 1)
    assert gate.hint() == "hold 1 s to send"
    gate.press()
    clock.advance(HOLD_S)  # complete, but the view never saw due(): it sent nothing, so nothing is claimed
    assert gate.release() is Outcome.TOO_SHORT and gate.refused == 2
    assert gate.release() is Outcome.NONE  # no press going on


def test_ask_only_confirms_on_release_and_counts_a_cancel():
    gate = SendGate(ask=True, hold=False)
    gate.press()
    assert not gate.holding and gate.release() is Outcome.CONFIRM
    gate.answered(False)
    gate.answered(True)
    gate.sent_one()
    assert (gate.sent, gate.refused) == (1, 1)
    off = SendGate(ask=False, hold=False)
    assert not off.active and off.release() is Outcome.NONE


def test_the_confirmation_names_exactly_what_is_sent():
    call = Binding("/lights/set", "std_srvs/SetBool", "call", ["request.data"])
    assert describe_send(call, {"data": True}) == ("Call /lights/set (std_srvs/SetBool)?", "Request:\ndata: true")
    pub = Binding("/dock/cmd", "std_msgs/String", "publish")
    assert describe_send(pub, {"data": "go"}, then="Then, on release: nothing") == (
        "Publish on /dock/cmd (std_msgs/String)?", "Message:\ndata: go\n\nThen, on release: nothing")
    assert describe_send(pub, {})[1] == "Message:\n{}"


def test_the_std_package_reexports_the_core_api():
    from rcon_widgets_std import send_guard

    assert send_guard.HOLD_S is HOLD_S and send_guard.SendGate is SendGate and send_guard.describe_send is describe_send
