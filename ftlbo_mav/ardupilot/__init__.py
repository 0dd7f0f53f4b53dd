"""The model of ArduCopter 4.5, as far as ftlbo-mav depends on it.

One place for what ArduPilot does that both the ground side and the emulator must agree
on, each rule citing the ArduPilot source it follows and tested against recordings of
ArduCopter 4.5.6 SITL (``tests/data/ardupilot-4.5.6/``):

- :mod:`.storage`: which mission items it accepts and what it keeps of each
  (AP_Mission.cpp), behind ``upload``'s verification and the emulator's mission store;
- :mod:`.modes`: its flight-mode numbers (ArduCopter/mode.h);
- :mod:`.streams`: the telemetry a ground station must ask for, and how (GCS_Common.cpp,
  ArduCopter/GCS_Mavlink.cpp).
"""
