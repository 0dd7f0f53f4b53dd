"""ArduCopter 4.5's battery monitor and battery failsafe: what the emulator does and what
the ground side reads (BATTERY_STATUS, the failsafe's STATUSTEXTs).

Each part follows ArduPilot 4.5.6 and is held to a SITL recording
(``tests/data/ardupilot-4.5.6/battery.json``, made with ``python -m sitl.battery``):

- the parameters (libraries/AP_BattMonitor/AP_BattMonitor_Params.cpp; BATT_MONITOR 4,
  analog voltage and current, as copter.parm sets it): BATT_CAPACITY 3300 mAh, the
  thresholds BATT_LOW_MAH / BATT_CRT_MAH / BATT_CRT_VOLT 0 (off), BATT_LOW_VOLT 10.5 V,
  BATT_LOW_TIMER 10 s, the actions BATT_FS_LOW_ACT / BATT_FS_CRT_ACT 0 (none);
- the remaining charge: ``100 (capacity - consumed) / capacity`` per cent
  (AP_BattMonitor_Backend::capacity_remaining_pct), BATTERY_STATUS's charge state OK,
  LOW, CRITICAL from the failsafe reached (AP_BattMonitor::get_mavlink_charge_state);
- the failsafe types (AP_BattMonitor_Backend::check_failsafe_types and
  update_failsafes): critical before low; a capacity threshold at once when
  ``capacity - consumed`` falls below it, a voltage one once the voltage has stayed below
  it for more than BATT_LOW_TIMER s (0 turns the voltage failsafes off);
- checked only while armed, and acted on only when the type is worse than the one
  reached (AP_BattMonitor::check_failsafes): ``"Battery 1 is low 12.60V used 1321 mAh"``
  (WARNING), then the copter's handler (ArduCopter/events.cpp
  Copter::handle_battery_failsafe): ``"Battery Failsafe"`` and BATT_FS_*_ACT's mode
  (do_failsafe_action: 1 LAND, 2 RTL, 3/4 SmartRTL, 5 terminate, 6 DO_LAND_START or
  RTL), or ``"Battery Failsafe - Disarming"`` on the ground; an action of lower priority
  than one already taken is not taken again (Copter::_failsafe_priorities);
- MAV_CMD_BATTERY_RESET (GCS_Common.cpp handle_command_battery_reset; param1 the
  battery mask, param2 the per cent, held to 0..100): consumed becomes ``(100 - p) %``
  of the capacity and the failsafe state is set to what that gives *silently*
  (AP_BattMonitor_Backend::reset_remaining): a reset below a threshold announces nothing
  and changes no mode (recorded: charge state LOW, no text, the copter stays in
  GUIDED). Accepted armed or not.

Pure data and arithmetic.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as R

from .navigation import INT8, INT32, REAL32, ParamDefault

NONE, LOW, CRITICAL = 0, 1, 2
"""AP_BattMonitor::Failsafe, in its order."""

CHARGE_STATE = {NONE: R.MAV_BATTERY_CHARGE_STATE_OK, LOW: R.MAV_BATTERY_CHARGE_STATE_LOW,
                CRITICAL: R.MAV_BATTERY_CHARGE_STATE_CRITICAL}

# FailsafeAction (ArduCopter/Copter.h) and Copter::_failsafe_priorities, most urgent first
ACTION_NONE, ACTION_LAND, ACTION_RTL, ACTION_SMARTRTL, ACTION_SMARTRTL_LAND = 0, 1, 2, 3, 4
ACTION_TERMINATE, ACTION_AUTO_DO_LAND_START = 5, 6
PRIORITIES = (ACTION_TERMINATE, ACTION_LAND, ACTION_RTL, ACTION_SMARTRTL_LAND,
              ACTION_SMARTRTL, ACTION_NONE)

_PARAMS = "libraries/AP_BattMonitor/AP_BattMonitor_Params.cpp"
BATTERY_PARAM_DEFAULTS = {
    "BATT_MONITOR": ParamDefault(4.0, INT8, _PARAMS + " (copter.parm: 4, analog V and I)"),
    "BATT_CAPACITY": ParamDefault(3300.0, INT32, _PARAMS + " (mAh)"),
    "BATT_LOW_MAH": ParamDefault(0.0, REAL32, _PARAMS + " (mAh left; 0: off)"),
    "BATT_CRT_MAH": ParamDefault(0.0, REAL32, _PARAMS + " (mAh left; 0: off)"),
    "BATT_LOW_VOLT": ParamDefault(10.5, REAL32, _PARAMS + " (V; copter's default)"),
    "BATT_CRT_VOLT": ParamDefault(0.0, REAL32, _PARAMS + " (V; 0: off)"),
    "BATT_LOW_TIMER": ParamDefault(10.0, INT8, _PARAMS + " (s a voltage must stay low)"),
    "BATT_FS_LOW_ACT": ParamDefault(0.0, INT8, _PARAMS + " (0 none, 1 land, 2 RTL, ...)"),
    "BATT_FS_CRT_ACT": ParamDefault(0.0, INT8, _PARAMS + " (0 none, 1 land, 2 RTL, ...)"),
}
"""The battery parameters the emulator knows, as ArduCopter 4.5.6 SITL reports them
after booting with copter.parm (battery.json ``params_after_boot``)."""

LOW_TEXT = "Battery {n} is {kind} {volts:.2f}V used {mah:.0f} mAh"
LOW_PATTERN = re.compile(r"^Battery \d+ is (low|critical) ")
""":data:`LOW_TEXT` as the ground side reads it (AP_BattMonitor::check_failsafes sends it
whatever BATT_FS_*_ACT says; recorded: ``Battery 1 is low 12.60V used 1321 mAh``)."""
FAILSAFE_TEXT = "Battery Failsafe"
DISARMING_TEXT = "Battery Failsafe - Disarming"


def remaining_pct(capacity_mah: float, consumed_mah: float) -> int:
    """AP_BattMonitor_Backend::capacity_remaining_pct: whole per cent, 0..100."""
    if capacity_mah <= 0:
        return 0
    pct = 100.0 * (capacity_mah - consumed_mah) / capacity_mah
    return int(min(max(pct, 0.0), 100.0))


def failsafe_mode(action: int, *, rtl: int, land: int) -> int | None:
    """The mode Copter::do_failsafe_action asks for (the emulator has no SmartRTL, which
    falls back to RTL or LAND as ArduCopter's does when it has no path; no DO_LAND_START
    mission: RTL); None for none or terminate (a disarm)."""
    return {ACTION_LAND: land, ACTION_RTL: rtl, ACTION_SMARTRTL: rtl,
            ACTION_SMARTRTL_LAND: land, ACTION_AUTO_DO_LAND_START: rtl}.get(action)


@dataclass
class BatteryMonitor:
    """One battery as AP_BattMonitor keeps it: ``consumed_mah`` (and Wh), the
    ``voltage``, the failsafe reached and the most urgent action taken so far."""

    voltage: float = 12.6
    consumed_mah: float = 0.0
    consumed_wh: float = 0.0
    current_a: float = 0.0
    failsafe: int = NONE
    highest_priority: int = len(PRIORITIES)
    _low_volt_since: float | None = None
    _crit_volt_since: float | None = None

    def draw(self, current_a: float, dt: float) -> None:
        """``current_a`` for ``dt`` seconds (AP_BattMonitor_Analog::read)."""
        self.current_a = current_a
        self.consumed_mah += current_a * dt / 3.6
        self.consumed_wh += current_a * self.voltage * dt / 3600.0

    def remaining_pct(self, params) -> int:
        return remaining_pct(params["BATT_CAPACITY"], self.consumed_mah)

    def charge_state(self) -> int:
        return CHARGE_STATE[self.failsafe]

    def failsafe_type(self, params, now: float) -> int:
        """AP_BattMonitor_Backend::update_failsafes at ``now`` (seconds)."""
        left = params["BATT_CAPACITY"] - self.consumed_mah
        timer = params["BATT_LOW_TIMER"]

        def held(volts: float, since: float | None) -> tuple[bool, float | None]:
            if not (volts > 0 and self.voltage < volts):
                return False, None
            since = now if since is None else since
            return timer > 0 and now - since > timer, since

        crit_v, self._crit_volt_since = held(params["BATT_CRT_VOLT"], self._crit_volt_since)
        if crit_v or (params["BATT_CRT_MAH"] > 0 and left < params["BATT_CRT_MAH"]):
            return CRITICAL
        low_v, self._low_volt_since = held(params["BATT_LOW_VOLT"], self._low_volt_since)
        if low_v or (params["BATT_LOW_MAH"] > 0 and left < params["BATT_LOW_MAH"]):
            return LOW
        return NONE

    def check(self, params, now: float, *, armed: bool) -> tuple[str, int] | None:
        """AP_BattMonitor::check_failsafes: ``(text, action)`` when a worse failsafe is
        reached while armed and its action is as urgent as any taken before (the
        handler is then called: :func:`handler_text`); ``(text, -1)`` when only the
        text is sent; None."""
        if not armed:
            return None
        kind = self.failsafe_type(params, now)
        if kind <= self.failsafe:
            return None
        self.failsafe = kind
        action = int(params["BATT_FS_CRT_ACT" if kind == CRITICAL else "BATT_FS_LOW_ACT"])
        text = LOW_TEXT.format(n=1, kind="critical" if kind == CRITICAL else "low",
                               volts=self.voltage, mah=self.consumed_mah)
        priority = PRIORITIES.index(action) if action in PRIORITIES else len(PRIORITIES) - 1
        if priority > self.highest_priority:
            return text, -1
        self.highest_priority = priority
        return text, action

    def reset(self, percent: float, params, now: float) -> None:
        """AP_BattMonitor_Backend::reset_remaining: consumed from ``percent``, the
        failsafe state set to what that gives, with nothing announced; the priority
        cleared when no failsafe is left (AP_BattMonitor::reset_remaining_mask)."""
        f32 = np.float32  # ArduPilot's floats: a 60 % reset of 3300 mAh is 1319.99997
        used = f32(100.0 - min(max(percent, 0.0), 100.0)) * f32(0.01)
        self.consumed_mah = float(used * f32(params["BATT_CAPACITY"]))
        self.consumed_wh = self.consumed_mah * self.voltage / 1000.0
        self.failsafe = self.failsafe_type(params, now)
        if self.failsafe == NONE:
            self.highest_priority = len(PRIORITIES)


def handler_text(*, landed: bool) -> str:
    """Copter::handle_battery_failsafe's announcement: on the ground it disarms."""
    return DISARMING_TEXT if landed else FAILSAFE_TEXT
