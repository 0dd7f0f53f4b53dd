"""Re-record what ArduCopter does, on your own SITL build, in the recordings' own format.

``python -m sitl.record --out DIR`` (from the repository root, with ``ARDUPILOT_SITL``
and ``ARDUPILOT_SITL_DEFAULTS`` set) starts one fresh SITL copter at the recordings' home
and writes, in ``DIR``:

- ``mission_items.json``: every item of ``tests/data/ardupilot-4.5.6/mission_items.json``
  uploaded as it was sent there, and read back (``main_upload.items``: name, sent,
  read_back), the part of that recording the storage model is held to;
- ``flight.json`` (``--flight``): the example's uav1 mission flown once as the shared
  recording did (GUIDED takeoff, hover, current item 2, AUTO): every MISSION_ITEM_REACHED
  and GLOBAL_POSITION_INT row, times in seconds since AUTO.

With ``--camera`` it records ``camera.json`` instead (:mod:`sitl.camera`): camera
trigger items stored and read back, and a photo survey flown with a camera configured,
every CAMERA_FEEDBACK.

Then ``FTLBO_RECORDINGS=DIR python -m pytest tests/ardupilot tests/conformance`` holds the
storage model (and the emulator) to the new recording, so a newer ArduPilot is checked the
way 4.5.6 was. The version string the vehicle reports goes into each file's ``about``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from ftlbo_mav.ardupilot.storage import WireItem
from ftlbo_mav.errors import FtlboError
from ftlbo_mav.link.codec import from_wire, to_wire
from ftlbo_mav.link.discovery import discover, wait_ready
from ftlbo_mav.link.endpoints import open_links
from ftlbo_mav.link.mission_protocol import Timing, download_mission, upload_mission

from .launcher import SitlSwarm
from .recording import HOME, fly_from_hover, version, wire_from_json, wire_to_json

ROOT = Path(__file__).resolve().parents[1]
REFERENCE = ROOT / "tests" / "data" / "ardupilot-4.5.6" / "mission_items.json"
EXAMPLE_UAV1 = ROOT / "missions" / "nha-trang-orchard" / "uav1.waypoints"


def reference_items(path: Path = REFERENCE) -> list[tuple[str, WireItem]]:
    """``(name, item as sent)`` of the reference recording's main upload."""
    doc = json.loads(path.read_text())
    return [(it["name"], wire_from_json(it["sent"])) for it in doc["main_upload"]["items"]]


def record_items(channel, *, timing: Timing) -> dict:
    """Upload the reference items, read them back; the ``main_upload`` section."""
    named = reference_items()
    items = [from_wire(w) for _, w in named]
    upload_mission(channel, items, timing=timing)
    back = download_mission(channel, timing=timing)
    if len(back) != len(items):
        raise FtlboError(f"read back {len(back)} items of {len(items)}")
    return {"description": "the reference items uploaded (MISSION_ITEM_INT) and read back "
                           "(MISSION_REQUEST_INT) by sitl/record.py",
            "items": [{"name": name, "sent": wire_to_json(w), "read_back": wire_to_json(
                to_wire(b))} for (name, w), b in zip(named, back)]}


def record_flight(link, sysid: int, *, timing: Timing, timeout_s: float = 300.0) -> dict:
    """Fly the example's uav1 mission as the shared recording did; reached items and
    positions, times in seconds since the AUTO command."""
    from ftlbo_mav.flight.vehicle import FlightVehicle
    from ftlbo_mav.mission.waypoints import read_waypoints

    items = read_waypoints(EXAMPLE_UAV1)
    with link.channel(sysid) as channel:
        upload_mission(channel, items, timing=timing)
    rows, reached = [], []
    t0 = [None]

    def watch(msg) -> None:
        if msg.get_srcSystem() != sysid or t0[0] is None:
            return
        t = time.monotonic() - t0[0]
        if msg.get_type() == "GLOBAL_POSITION_INT":
            rows.append([round(t, 3), msg.time_boot_ms, msg.lat, msg.lon, msg.relative_alt])
        elif msg.get_type() == "MISSION_ITEM_REACHED":
            reached.append({"t": round(t, 3), "seq": msg.seq})

    link.taps.append(watch)
    v = FlightVehicle("uav1", sysid, link)
    try:
        fly_from_hover(v, items[1].alt_m, settle_m=0.1, timeout_s=timeout_s,
                       start=lambda: t0.__setitem__(0, time.monotonic()))
    finally:
        v.close()
        link.taps.remove(watch)
    return {"mission_file": str(EXAMPLE_UAV1.relative_to(ROOT)),
            "mission_item_reached": reached,
            "global_position_int": {"fields": ["t", "time_boot_ms", "lat_e7", "lon_e7",
                                               "relative_alt_mm"], "rows": rows}}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m sitl.record", description=__doc__)
    parser.add_argument("--out", required=True, type=Path, help="folder for the JSON files")
    parser.add_argument("--binary", help="arducopter binary (default: $ARDUPILOT_SITL)")
    parser.add_argument("--defaults", action="append", default=[],
                        help="defaults .parm file (e.g. ArduPilot's copter.parm)")
    parser.add_argument("--flight", action="store_true",
                        help="also fly the example's uav1 mission (about two minutes)")
    parser.add_argument("--camera", action="store_true",
                        help="instead: camera trigger items and a photo survey flight "
                             "(camera.json, sitl/camera.py; about five minutes)")
    args = parser.parse_args(argv)
    timing = Timing()
    if args.camera:
        from .camera import record_camera

        try:
            doc = record_camera(args.binary, args.defaults, args.out)
        except (FtlboError, ValueError, OSError) as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 1
        args.out.mkdir(parents=True, exist_ok=True)
        (args.out / "camera.json").write_text(json.dumps(doc, indent=1) + "\n")
        print(f"wrote {args.out / 'camera.json'}", file=sys.stderr)
        return 0
    try:
        with SitlSwarm(binary=args.binary, homes=[HOME], defaults=args.defaults) as swarm:
            links = open_links(swarm.urls, connect_timeout_s=30.0)
            try:
                wait_ready(links, [1], timeout_s=180.0)
                found, _missing = discover(links, [1], timeout_s=5.0)
                with found[1].channel(1) as channel:
                    banner = version(channel)
                    print(f"recording {banner}", file=sys.stderr)
                    items = record_items(channel, timing=timing)
                about = (f"Recorded {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())} by "
                         f"sitl/record.py against {banner} SITL started by sitl/launcher.py "
                         f"with defaults {[str(d) for d in swarm.defaults]}")
                args.out.mkdir(parents=True, exist_ok=True)
                (args.out / "mission_items.json").write_text(json.dumps(
                    {"about": about, "main_upload": items}, indent=1) + "\n")
                print(f"wrote {args.out / 'mission_items.json'}", file=sys.stderr)
                if args.flight:
                    flight = record_flight(found[1], 1, timing=timing)
                    (args.out / "flight.json").write_text(json.dumps(
                        {"about": about, **flight}, indent=1) + "\n")
                    print(f"wrote {args.out / 'flight.json'}", file=sys.stderr)
            finally:
                for link in links:
                    link.close()
    except (FtlboError, ValueError, OSError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
