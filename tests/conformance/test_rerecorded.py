"""A recording made with ``python -m sitl.record --flight`` (``FTLBO_RECORDINGS``) against
the one the emulator is held to: if a newer ArduPilot flies the same mission differently,
the emulator's conformance no longer speaks for it. Skipped without such a recording."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

SHIPPED = Path(__file__).parents[1] / "data" / "ardupilot-4.5.6" / "flight.json"
NEW = Path(os.environ.get("FTLBO_RECORDINGS", "/nonexistent")) / "flight.json"


@pytest.mark.skipif(not NEW.exists(), reason="no FTLBO_RECORDINGS flight.json")
def test_a_new_recording_reaches_every_item_when_the_reference_did():
    ref = json.loads(SHIPPED.read_text())
    auto = ref["milestones"]["t_auto_cmd"]
    want = {r["seq"]: r["t"] - auto for r in ref["mission_item_reached"]}
    got = {r["seq"]: r["t"] for r in json.loads(NEW.read_text())["mission_item_reached"]}
    assert set(got) == set(want)
    first = min(want)  # both clocks start at the AUTO command, sent a little differently
    shift = got[first] - want[first]
    for seq, t in want.items():
        assert abs((got[seq] - shift) - t) <= max(0.5, 0.1 * t), (seq, got[seq] - shift, t)
