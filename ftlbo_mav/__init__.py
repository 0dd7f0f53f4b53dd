"""ftlbo-mav: formation path planning for small UAV swarms and MAVLink mission tooling."""

import os

# pymavlink chooses MAVLink 1 or 2 from this variable when it first loads a dialect, and
# some of its helpers (mavwp) read it again at every call: it must be set before anything
# imports pymavlink, or the two disagree. The mission protocol with MISSION_ITEM_INT and
# signing need MAVLink 2.
os.environ.setdefault("MAVLINK20", "1")

__version__ = "0.1.0"
