"""Smoke run of ``benchmarks/soak.py --quick``: the reliability figures it prints are at their targets
(fuzz: no client death, every valid message in order; flap: nothing lost; stall: no stale command
delivered; saves: every layout complete after kill -9; gui and reconnect: the app's parts ran).  Its figures are printed, not judged on time."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

SOAK = Path(__file__).resolve().parents[1] / "benchmarks" / "soak.py"


def test_soak_quick_meets_the_reliability_targets(tmp_path):
    out = tmp_path / "soak.json"
    proc = subprocess.run([sys.executable, str(SOAK), "--quick", "--out", str(out)], capture_output=True,
                          text=True, timeout=480)
    assert out.exists(), proc.stderr[-2000:]
    r = json.loads(out.read_text())
    assert r["fuzz"]["client_deaths"] == 0 and r["fuzz"]["delivered_exactly_in_order"], r["fuzz"]
    assert r["fuzz"]["valid_delivered"] == r["fuzz"]["valid_sent"] > 0
    assert r["flap"]["cuts"] >= 2 and not any(r["flap"]["lost"].values()), r["flap"]
    assert r["stall"]["stale_commands_delivered"] == 0 and r["stall"]["commands_delivered"] > 0, r["stall"]
    assert r["saves"]["complete_layouts"] == r["saves"]["kills"], r["saves"]
    # the app's parts: a 5 MB String shown and a flood received on a Text View, reconnects counted
    assert r["gui"]["text_5mb_shown"] and r["gui"]["flood_messages_received"] > 0, r["gui"]
    assert r["reconnect"]["reconnects"] >= 8 and r["reconnect"]["rss_per_reconnect_mb"] is not None, r["reconnect"]
    assert "targets:" in proc.stdout
