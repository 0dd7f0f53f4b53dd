"""How ArduCopter 4.5 takes survey photos by distance (AP_Camera), and the mission item
that turns it on and off.

``MAV_CMD_DO_SET_CAM_TRIGG_DIST`` in a mission (AP_Mission::start_command_camera,
libraries/AP_Mission/AP_Mission_Commands.cpp) sets the primary camera's trigger distance
to param1 (``AP_Camera_Backend::set_trigger_distance``) and, when param3 is 1, takes a
photo at once (``take_picture``). Like every DO command it runs when the navigation
command before it is done (``AP_Mission::advance_current_nav_cmd``): after a lane's
entry waypoint, the photos start there.

``AP_Camera_Backend::update`` (libraries/AP_Camera/AP_Camera_Backend.cpp), at 50 Hz:
with a positive trigger distance (and no time-interval capture running, a 3D GPS fix,
a mode allowed by CAMx_AUTO_ONLY, roll within CAMx_MAX_ROLL), the first update only
remembers the position; afterwards a photo is taken once the vehicle is at least the
trigger distance (``Location::get_distance``, a straight line) from the last photo's
position (or the remembered one), and each photo (``take_picture``) remembers where it
was taken. Setting the distance to 0 forgets the remembered position. Photos closer in
time than CAMx_INTRVAL_MIN wait (``trigger_pending``). Each photo goes to the ground
station as CAMERA_FEEDBACK (``prep_mavlink_msg_camera_feedback``, without a feedback
pin) with the count of images so far in ``completed_captures``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as R

from .navigation import INT8, REAL32, ParamDefault

UPDATE_HZ = 50.0
"""AP_Camera::update's rate (Copter's scheduler table)."""

_PARAMS = "libraries/AP_Camera/AP_Camera_Params.cpp"
CAMERA_PARAM_DEFAULTS = {
    "CAM1_TYPE": ParamDefault(0.0, INT8, _PARAMS + " (0: none, 1: servo, 2: relay, ...)"),
    "CAM1_TRIGG_DIST": ParamDefault(0.0, REAL32, _PARAMS + " (m; DO_SET_CAM_TRIGG_DIST sets "
                                                 "it)"),
}
"""The camera parameters the emulator knows. ArduPilot makes its camera backends at boot
from CAMx_TYPE; the emulator, which has no reboot, counts it from when it is set."""


def feedback_message(*, time_usec: int, image: int, lat_e7: int, lon_e7: int, alt_msl_m: float,
                     alt_rel_m: float, roll_deg: float = 0.0, pitch_deg: float = 0.0,
                     yaw_deg: float = 0.0):
    """CAMERA_FEEDBACK as AP_Camera_Backend::send_camera_feedback fills it: target system
    0, camera id 0 (the first instance), the image index, the position and attitude at
    the photo, focal length 0, flags CAMERA_FEEDBACK_PHOTO, completed captures 0 (the
    feedback-pin count: no pin)."""
    return R.MAVLink_camera_feedback_message(
        time_usec, 0, 0, image, lat_e7, lon_e7, alt_msl_m, alt_rel_m, roll_deg, pitch_deg,
        yaw_deg, 0.0, R.CAMERA_FEEDBACK_PHOTO, 0)


def trigger_item_params(distance_m: float, *, at_once: bool) -> tuple[float, float, float, float]:
    """DO_SET_CAM_TRIGG_DIST's params: param1 the distance (0: off), param3 1 to take a
    photo at once; ArduCopter keeps param1 as a float and param3 as a uint8
    (``Cam_Trigg_Distance``, libraries/AP_Mission/AP_Mission.h), param2 and param4 not."""
    return (float(distance_m), 0.0, 1.0 if at_once else 0.0, 0.0)


def photo_positions(path: np.ndarray, distance_m: float) -> np.ndarray:
    """Where distance triggering takes its photos as the vehicle flies the polyline
    ``path (P, 2)`` (metres, flat): one at its start (param3 1), then one each time the
    vehicle is ``distance_m`` from the last photo in a straight line. The 50 Hz updates
    are taken as continuous (a photo at most one update's travel late: 6 cm at 3 m/s).
    Returns ``(K, 2)``."""
    path = np.asarray(path, float)
    photos = [path[0]]
    last = path[0]
    for a, b in zip(path[:-1], path[1:]):
        while True:  # the point of a->b beyond `a` at distance_m from `last`, if any
            d, f = b - a, a - last
            qa, qb, qc = d @ d, 2 * (f @ d), f @ f - distance_m**2
            if qa < 1e-18:
                break
            disc = qb * qb - 4 * qa * qc
            if disc < 0:
                break
            t = (-qb + math.sqrt(disc)) / (2 * qa)
            if not 0.0 <= t <= 1.0:
                break
            last = a + t * d
            photos.append(last)
            a = last
    return np.array(photos)


@dataclass
class DistanceTrigger:
    """One camera's distance triggering, as AP_Camera_Backend keeps it: the trigger
    distance, the remembered position, the image count. Positions are metres on a flat
    frame (the emulator's), the vehicle's at each call of :meth:`update`."""

    distance_m: float = 0.0
    images: int = 0
    last: np.ndarray | None = field(default=None)

    def set_distance(self, distance_m: float) -> None:
        self.distance_m = float(distance_m)
        if not self.distance_m > 0:
            self.last = None  # update: "if (!is_positive(trigg_dist)) last_location = 0"

    def take_picture(self, position: np.ndarray) -> int:
        """A photo here; returns its image number (1, 2, ...)."""
        self.images += 1
        self.last = np.array(position[:2], float)
        return self.images

    def update(self, position: np.ndarray) -> bool:
        """One AP_Camera_Backend::update: whether a photo is due here (the caller takes
        it with :meth:`take_picture`)."""
        if not self.distance_m > 0:
            return False
        here = np.array(position[:2], float)
        if self.last is None:
            self.last = here
            return False
        return bool(np.hypot(*(here - self.last)) >= self.distance_m)
