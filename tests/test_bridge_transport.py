"""Which WebSocket library carries the link (``rcon_core/bridge/transport.py``): picows where it is installed,
websockets when told (argument or ``RCON_TRANSPORT``), a clear error for anything else."""

from __future__ import annotations

import pytest

from rcon_core.bridge import BridgeClient, LinkSettingsError
from rcon_core.bridge.transport import available, choose


def test_auto_prefers_picows_where_it_is_installed(monkeypatch):
    monkeypatch.delenv("RCON_TRANSPORT", raising=False)
    assert available()[-1] == "websockets"
    assert choose() == available()[0] == choose("auto")
    assert BridgeClient("ws://127.0.0.1:1").transport == available()[0]


def test_the_setting_and_the_environment_choose(monkeypatch):
    monkeypatch.setenv("RCON_TRANSPORT", "websockets")
    assert BridgeClient("ws://127.0.0.1:1").transport == "websockets"
    assert BridgeClient("ws://127.0.0.1:1", transport="auto").transport == available()[0]
    with pytest.raises(LinkSettingsError, match="unknown transport 'tornado'; choose one of auto, picows, websockets"):
        BridgeClient("ws://127.0.0.1:1", transport="tornado")
    monkeypatch.setenv("RCON_TRANSPORT", "Websockets ")
    assert choose() == "websockets"
