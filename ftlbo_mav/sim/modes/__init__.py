"""The emulated copter's flight modes, split as ArduCopter splits them (mode_auto.cpp,
mode_guided.cpp, mode_rtl.cpp, mode_land.cpp, mode_brake.cpp): each a part of
:class:`~ftlbo_mav.sim.autopilot.Autopilot`, which holds the shared state (position,
arming, the navigation in use) and runs the one whose phase is current."""

from .auto import ModeAuto
from .brake import ModeBrake
from .guided import ModeGuided
from .land import ModeLand
from .rtl import ModeRTL

__all__ = ["ModeAuto", "ModeBrake", "ModeGuided", "ModeLand", "ModeRTL"]
