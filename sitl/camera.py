"""Record how ArduCopter stores camera trigger items and takes survey photos.

``python -m sitl.record --camera --out DIR`` (``ARDUPILOT_SITL``, ``ARDUPILOT_SITL_DEFAULTS``
set, from the repository root) starts one fresh SITL copter at uav1's home of
``missions/field-survey/`` with one camera configured (CAM1_TYPE 1, a servo-triggered
camera, as ArduPilot's camera documentation describes; nothing else added to the
defaults) and writes ``DIR/camera.json``:

- ``camera_items``: DO_SET_CAM_TRIGG_DIST items with ordinary and odd params uploaded
  and read back (``name``, ``sent``, ``read_back``, as ``mission_items.json``), what
  ``ftlbo_mav.ardupilot.storage`` is held to;
- ``flight``: uav1's survey mission flown once (GUIDED takeoff to its start altitude,
  current item 2, AUTO, until it lands and disarms): every CAMERA_FEEDBACK, every
  MISSION_ITEM_REACHED and the GLOBAL_POSITION_INT rows, times in seconds since AUTO, and
  the camera parameters read back.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

from pymavlink.dialects.v20 import ardupilotmega as R

from ftlbo_mav.ardupilot.storage import WireItem
from ftlbo_mav.errors import FtlboError
from ftlbo_mav.link.codec import from_wire, to_wire
from ftlbo_mav.link.discovery import discover, wait_ready
from ftlbo_mav.link.endpoints import open_links
from ftlbo_mav.link.mission_protocol import Timing, download_mission, upload_mission
from ftlbo_mav.mission.files import digest, read_mission_text

from .launcher import SitlSwarm
from .recording import fly_from_hover, version, wire_to_json

ROOT = Path(__file__).resolve().parents[1]
SURVEY_UAV1 = ROOT / "missions" / "field-survey" / "uav1.waypoints"
CAMERA_PARAMS = "CAM1_TYPE 1\n"
"""A servo camera (AP_Camera_Servo): its trigger needs no hardware to answer."""
READ_PARAMS = ("CAM1_TYPE", "CAM1_DURATION", "CAM1_INTRVAL_MIN", "CAM1_TRIGG_DIST",
               "CAM_AUTO_ONLY", "CAM_MAX_ROLL", "WPNAV_SPEED", "WPNAV_RADIUS")

_CMD = R.MAV_CMD_DO_SET_CAM_TRIGG_DIST
# (name, frame, params, x, y, z): after a home, a takeoff and a waypoint
CASES = [
    ("DO_SET_CAM_TRIGG_DIST (5.7, 0, 1, 0): on, a photo at once", 3, (5.7, 0, 1, 0), 0, 0, 0.0),
    ("DO_SET_CAM_TRIGG_DIST (0, 0, 0, 0): off", 3, (0, 0, 0, 0), 0, 0, 0.0),
    ("DO_SET_CAM_TRIGG_DIST (12.345, 7, 1.7, 9) frame 2", 2, (12.345, 7, 1.7, 9), 0, 0, 0.0),
    ("DO_SET_CAM_TRIGG_DIST (25.5, 0, 2, 0) x,y,z = 1,2,3", 3, (25.5, 0, 2, 0), 1, 2, 3.0),
    ("DO_SET_CAM_TRIGG_DIST (-3, 0, 0, 0): negative distance", 3, (-3, 0, 0, 0), 0, 0, 0.0),
    ("DO_SET_CAM_TRIGG_DIST (0.01, 0, 256, -1): param3 past uint8", 0, (0.01, 0, 256, -1),
     0, 0, 0.0),
    ("DO_SET_CAM_TRIGG_DIST (1e6, 0, -1, 0)", 3, (1e6, 0, -1, 0), 0, 0, 0.0),
]


def _f32(x: float) -> float:
    import numpy as np

    return float(np.float32(x))


def camera_items(home: tuple[float, float]) -> list[tuple[str, WireItem]]:
    """The items to upload: home, takeoff, one waypoint, then :data:`CASES`."""
    lat, lon = round(home[0] * 1e7), round(home[1] * 1e7)
    items = [
        ("item 0 home", WireItem(0, R.MAV_CMD_NAV_WAYPOINT, 0, lat, lon, 0.0, current=1)),
        ("NAV_TAKEOFF alt 10", WireItem(1, R.MAV_CMD_NAV_TAKEOFF, 3, 0, 0, 10.0)),
        ("NAV_WAYPOINT", WireItem(2, R.MAV_CMD_NAV_WAYPOINT, 3, lat + 900, lon, 10.0)),
    ]
    for name, frame, p, x, y, z in CASES:
        items.append((name, WireItem(len(items), _CMD, frame, x, y, _f32(z),
                                     *(_f32(v) for v in p))))
    return items


def record_storage(channel, home, *, timing: Timing) -> dict:
    named = camera_items(home)
    upload_mission(channel, [from_wire(w) for _, w in named], timing=timing)
    back = download_mission(channel, timing=timing)
    if len(back) != len(named):
        raise FtlboError(f"read back {len(back)} items of {len(named)}")
    return {"description": "DO_SET_CAM_TRIGG_DIST items uploaded (MISSION_ITEM_INT) after a "
                           "home, a takeoff and a waypoint, and read back (MISSION_REQUEST_INT)",
            "items": [{"name": name, "sent": wire_to_json(w),
                       "read_back": wire_to_json(to_wire(b))}
                      for (name, w), b in zip(named, back)]}


def record_survey(link, sysid: int, *, timing: Timing, timeout_s: float = 330.0) -> dict:
    from ftlbo_mav.flight.vehicle import FlightVehicle
    from ftlbo_mav.mission.waypoints import read_waypoints

    items = read_waypoints(SURVEY_UAV1)
    with link.channel(sysid) as channel:
        upload_mission(channel, items, timing=timing)
    rows, reached, feedback, texts = [], [], [], []
    t0 = [None]

    def watch(msg) -> None:
        if msg.get_srcSystem() != sysid:
            return
        kind = msg.get_type()
        if kind == "STATUSTEXT":
            texts.append({"t": None if t0[0] is None else round(time.monotonic() - t0[0], 3),
                          "text": msg.text})
        if t0[0] is None:
            return
        t = round(time.monotonic() - t0[0], 3)
        if kind == "GLOBAL_POSITION_INT":
            rows.append([t, msg.time_boot_ms, msg.lat, msg.lon, msg.relative_alt])
        elif kind == "MISSION_ITEM_REACHED":
            reached.append({"t": t, "seq": msg.seq})
        elif kind == "CAMERA_FEEDBACK":
            feedback.append({"t": t, "time_usec": msg.time_usec, "lat": msg.lat, "lng": msg.lng,
                             "alt_msl": msg.alt_msl, "alt_rel": msg.alt_rel, "roll": msg.roll,
                             "pitch": msg.pitch, "yaw": msg.yaw, "img_idx": msg.img_idx,
                             "cam_idx": msg.cam_idx, "flags": msg.flags,
                             "completed_captures": msg.completed_captures})

    link.taps.append(watch)
    v = FlightVehicle("uav1", sysid, link, position_hz=5.0)
    try:
        params = {name: v.read_param(name) for name in READ_PARAMS}
        done = fly_from_hover(v, items[1].alt_m, settle_m=0.2, timeout_s=timeout_s,
                              start=lambda: t0.__setitem__(0, time.monotonic()))
    finally:
        v.close()
        link.taps.remove(watch)
    return {"mission_file": str(SURVEY_UAV1.relative_to(ROOT)),
            "mission_sha256": digest(read_mission_text(SURVEY_UAV1)), "landed": done,
            "params": params, "camera_feedback": feedback, "mission_item_reached": reached,
            "statustext": texts,
            "global_position_int": {"fields": ["t", "time_boot_ms", "lat_e7", "lon_e7",
                                               "relative_alt_mm"], "rows": rows}}


def record_camera(binary: str | None, defaults: list, out: Path) -> dict:
    """Start the SITL copter, record both parts; returns the ``camera.json`` content."""
    from ftlbo_mav.mission.waypoints import read_waypoints

    home_item = read_waypoints(SURVEY_UAV1)[0]
    home = (home_item.lat_deg, home_item.lon_deg, 0.0)
    timing = Timing()
    with tempfile.TemporaryDirectory(prefix="ftlbo-camera-") as tmp:
        camera_parm = Path(tmp) / "camera.parm"
        camera_parm.write_text(CAMERA_PARAMS)
        with SitlSwarm(binary=binary, homes=[home], defaults=[*defaults, camera_parm]) as swarm:
            links = open_links(swarm.urls, connect_timeout_s=30.0)
            try:
                wait_ready(links, [1], timeout_s=180.0)
                found, _missing = discover(links, [1], timeout_s=5.0)
                with found[1].channel(1) as channel:
                    banner = version(channel)
                    storage = record_storage(channel, home[:2], timing=timing)
                flight = record_survey(found[1], 1, timing=timing)
            finally:
                for link in links:
                    link.close()
            used = [str(d) for d in swarm.defaults if d != camera_parm]
    return {"about": f"Recorded {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())} by "
                     f"sitl/record.py --camera against {banner} SITL started by "
                     f"sitl/launcher.py (speedup 1) with defaults {used} and {CAMERA_PARAMS!r}",
            "camera_items": storage, "flight": flight}
