"""What ArduCopter 4.5 says when it leaves the mission on its own: failsafes, fence
breaches, crashes. The ground side reads these STATUSTEXTs to tell a vehicle that left
the plan (:mod:`ftlbo_mav.flight.departures`); the emulator says the fence one itself.

Each pattern follows the text ArduCopter sends:

- ``Copter::announce_failsafe`` (ArduCopter/events.cpp): ``"<type> Failsafe"`` or
  ``"<type> Failsafe - <action>"`` for the radio, battery, GCS, terrain and dead-reckoning
  failsafes (WARNING); their ``"... Failsafe Cleared"`` is not a departure;
- ``Copter::failsafe_ekf_event`` (ArduCopter/ekf_check.cpp): ``"EKF Failsafe: changed to
  <mode> Mode"`` (CRITICAL);
- ``Copter::fence_check`` (ArduCopter/fence.cpp): ``"Fence Breached"`` (NOTICE);
- ``Copter::crash_check`` / ``thrust_loss_check`` (ArduCopter/crash_check.cpp):
  ``"Crash: Disarming: ..."``, ``"Potential Thrust Loss (N)"`` (EMERGENCY);
- ``Copter::failsafe_terrain_on_event`` (events.cpp): ``"Failsafe: Terrain data missing"``;
- ``Copter::gpsglitch_check`` (events.cpp): ``"GPS Glitch or Compass error"`` (CRITICAL)
  when the EKF rejects the GPS, ``"Glitch cleared"`` after (not a departure);
- ``Copter::ekf_check`` (ekf_check.cpp): ``"EKF variance"`` (CRITICAL) before its EKF
  failsafe; both mean the vehicle no longer knows well where it is: ``navigation``.
"""

from __future__ import annotations

import re

FENCE, FAILSAFE, CRASH, NAVIGATION = "fence", "failsafe", "crash", "navigation"

_PATTERNS: tuple[tuple[str, re.Pattern], ...] = (
    (FENCE, re.compile(r"^Fence Breached")),
    (FAILSAFE, re.compile(r"^EKF Failsafe(?! Cleared)")),
    (FAILSAFE, re.compile(r"^Failsafe: ")),
    (FAILSAFE, re.compile(r"^[\w +]+ Failsafe(?! Cleared)( - .*)?$")),
    (CRASH, re.compile(r"^(Crash: |Potential Thrust Loss)")),
    (NAVIGATION, re.compile(r"^(GPS Glitch|EKF variance)")),
)


def departure_text(text: str) -> str | None:
    """``"fence"``, ``"failsafe"``, ``"crash"`` or ``"navigation"`` when ArduCopter's
    STATUSTEXT ``text`` says the vehicle left its mission on its own or no longer knows
    where it is (see the module docstring), else None."""
    text = text.strip("\x00 ")
    for kind, pattern in _PATTERNS:
        if pattern.search(text):
            return kind
    return None
