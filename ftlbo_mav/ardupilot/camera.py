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

from dataclasses import dataclass, field

import numpy as np

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
    from pymavlink.dialects.v20 import ardupilotmega as R  # the emulator's: not a plan's

    return R.MAVLink_camera_feedback_message(
        time_usec, 0, 0, image, lat_e7, lon_e7, alt_msl_m, alt_rel_m, roll_deg, pitch_deg,
        yaw_deg, 0.0, R.CAMERA_FEEDBACK_PHOTO, 0)


def trigger_item_params(distance_m: float, *, at_once: bool) -> tuple[float, float, float, float]:
    """DO_SET_CAM_TRIGG_DIST's params: param1 the distance (0: off), param3 1 to take a
    photo at once; ArduCopter keeps param1 as a float and param3 as a uint8
    (``Cam_Trigg_Distance``, libraries/AP_Mission/AP_Mission.h), param2 and param4 not."""
    return (float(distance_m), 0.0, 1.0 if at_once else 0.0, 0.0)


def track_photos(times: np.ndarray, positions: np.ndarray,
                 switches: list[tuple[float, float, bool]]) -> np.ndarray:
    """Where distance triggering takes its photos on a track sampled at AP_Camera's rate
    (``times (T,)`` seconds, ``positions (T, 3)`` metres, one row per 50 Hz update), with
    the trigger set at ``switches``: ``(time, distance, at_once)`` in time order, each
    applied before the update at or after its time (a DO_SET_CAM_TRIGG_DIST runs in the
    mission's update, before the camera's). :class:`DistanceTrigger`'s rules, searched
    in arrays: the first update after the distance is set remembers the position (or the
    photo taken at once does), then a photo at each update at least the distance (flat,
    straight line) from the last. Returns ``(K, 3)``."""
    times, positions = np.asarray(times, float), np.asarray(positions, float)
    photos: list[np.ndarray] = []
    last = None
    starts = np.searchsorted(times, [t - 1e-9 for t, _, _ in switches])
    ends = [*starts[1:], len(times)]
    for (_, dist, at_once), i, end in zip(switches, starts, ends):
        distance = float(dist)
        if not distance > 0:
            last = None
            continue
        if i >= end:
            continue
        if at_once or last is None:  # this update only remembers where it is
            if at_once:
                photos.append(positions[i])
            last = positions[i, :2]
            i += 1
        while i < end:
            window = positions[i:min(i + _SEARCH, end), :2]
            far = np.hypot(*(window - last).T) >= distance
            if not far.any():
                i += len(window)
                continue
            i += int(np.argmax(far))
            photos.append(positions[i])
            last = positions[i, :2]
            i += 1
    return np.array(photos).reshape(-1, 3)


_SEARCH = 256  # updates searched at once for the next photo (a photo every ~50 at 5 m/s)


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
