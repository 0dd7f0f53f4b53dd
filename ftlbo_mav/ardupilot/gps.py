"""How ArduCopter 4.5 reports its GPS and its position estimate, and when it calls them bad.

- GPS_RAW_INT (libraries/GCS_MAVLink/GCS_Common.cpp ``send_gps_raw`` from AP_GPS):
  ``fix_type`` a GPS_FIX_TYPE (3: 3D, 4: DGPS/SBAS, 5: RTK float, 6: RTK fixed),
  ``h_acc`` the receiver's horizontal accuracy estimate in mm (0 when it gives none),
  ``satellites_visible`` (255 unknown), ``vel`` cm/s and ``cog`` cdeg (UINT16_MAX unknown).
  ArduPilot SITL reports its simulated receiver's ``SIM_GPS_ACC`` as the accuracy
  (libraries/SITL/SIM_GPS.cpp: ``d.horizontal_acc = _sitl->gps_accuracy``; default 0.3 m).
- EKF_STATUS_REPORT (libraries/AP_NavEKF3/AP_NavEKF3_Outputs.cpp ``send_status_report``):
  ``flags`` EKF_STATUS_FLAGS, ``pos_horiz_variance`` the position innovation test ratio
  (1.0: at the gate). ArduCopter's EKF failsafe (ArduCopter/ekf_check.cpp
  ``ekf_over_threshold``) compares the variances with ``FS_EKF_THRESH`` (0.8 by
  default, ArduCopter/Parameters.cpp).
- Its announcements: ``"GPS Glitch or Compass error"`` when the EKF rejects the GPS
  (ArduCopter/events.cpp ``gpsglitch_check``, ``"Glitch cleared"`` after),
  ``"EKF variance"`` (ekf_check.cpp) before the EKF failsafe; those are in
  :mod:`.failsafes`.
"""

from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as R

FS_EKF_THRESH = 0.8
"""ArduCopter's EKF variance threshold (FS_EKF_THRESH default, ArduCopter/Parameters.cpp)."""

EKF_POS_HORIZ_ABS = R.EKF_POS_HORIZ_ABS
"""EKF_STATUS_REPORT flag: an absolute horizontal position estimate (what AUTO needs)."""

SITL_GPS_ACCURACY_M = 0.3
"""What ArduPilot SITL's receiver reports as its accuracy (SIM_GPS_ACC's default,
libraries/SITL/SIM.cpp)."""


def h_acc_m(raw_mm: int) -> float | None:
    """GPS_RAW_INT ``h_acc`` in metres; None when the receiver gives none (0)."""
    return None if raw_mm <= 0 else raw_mm / 1000.0
