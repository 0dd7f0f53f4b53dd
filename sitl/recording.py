"""What every recorder in ``sitl/`` shares: the shared recordings' home, mission items as
the recordings write them (JSON), the vehicle's banner, and a stored mission flown from a
hover as the shared recordings flew it.

:mod:`sitl.record` (mission items, the example's flight), :mod:`sitl.camera` (camera items,
a photo survey) and :mod:`sitl.battery` (the battery failsafes) import these; none of them
imports another recorder.
"""

from __future__ import annotations

import math
import time

from pymavlink.dialects.v20 import ardupilotmega as R

from ftlbo_mav.ardupilot.storage import WireItem

HOME = (12.2332099, 109.1145051, 0.0)  # where the shared recordings were made
FIELDS = ("seq", "frame", "command", "current", "autocontinue", "param1", "param2",
          "param3", "param4", "x", "y", "z")


def _num(v):
    return float(v) if isinstance(v, str) else v


def _json_num(v):
    return str(v) if isinstance(v, float) and not math.isfinite(v) else v


def wire_from_json(d: dict) -> WireItem:
    return WireItem(**{k: _num(d[k]) for k in FIELDS})


def wire_to_json(w: WireItem) -> dict:
    return {k: _json_num(getattr(w, k)) for k in FIELDS} | {"mission_type": 0}


def version(channel, timeout_s: float = 5.0) -> str:
    """The vehicle's banner ("ArduCopter V4.5.6 (bbf0b066)"), from its STATUSTEXT."""
    channel.send(R.MAVLink_command_long_message(
        channel.sysid, 1, R.MAV_CMD_DO_SEND_BANNER, 0, 0, 0, 0, 0, 0, 0, 0))
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        msg = channel.recv(0.2)
        if msg is not None and msg.get_type() == "STATUSTEXT" and "V" in msg.text:
            return msg.text.strip()
    return "unknown version"


def fly_from_hover(v, takeoff_alt_m: float, *, settle_m: float, timeout_s: float,
                   start) -> bool:
    """Fly vehicle ``v``'s stored mission as the shared recordings did: GUIDED, arm, take
    off to ``takeoff_alt_m``, hover until within ``settle_m`` of it and still, then item 2
    current and AUTO (``start()`` runs just before the switch); True once it has landed
    (disarmed) within ``timeout_s``."""
    v.set_mode("GUIDED", timeout_s=60)
    v.arm(budget_s=90)
    v.takeoff(takeoff_alt_m)
    v.wait_for(lambda s: abs(s.alt_m - takeoff_alt_m) < settle_m and abs(s.climb_m_s) < 0.1,
               60)
    time.sleep(1.0)
    v.set_current(2)
    start()
    v.set_mode("AUTO")
    return v.wait_for(lambda s: not s.armed, timeout_s)
