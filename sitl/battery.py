"""Record how ArduCopter's battery monitor and battery failsafe behave on SITL.

``python -m sitl.battery --out DIR`` (from the repository root, with ``ARDUPILOT_SITL``
set to a built ``arducopter`` and ``ARDUPILOT_SITL_DEFAULTS`` to ArduPilot's
``Tools/autotest/default_params/copter.parm``) starts one fresh SITL copter (instance 0,
speedup 1, at the shared recordings' home) and writes ``DIR/battery.json``:

- ``params_after_boot``: the battery, failsafe and WPNAV parameters as the vehicle reports
  them; ``param_changes``: every PARAM_SET this script made, with the value read back;
- ``messages``: from the stream requests on, every SYS_STATUS and BATTERY_STATUS (asked
  at 5 Hz each with MAV_CMD_SET_MESSAGE_INTERVAL), GLOBAL_POSITION_INT (5 Hz), HEARTBEAT,
  STATUSTEXT and COMMAND_ACK, as rows with their arrival time ``t`` (seconds since the
  script's t0);
- ``phases``: what was done when (``start`` / ``end`` on the same clock): (a) 10 s
  disarmed; (b) MAV_CMD_BATTERY_RESET (param1 battery mask 1, param2 60 %) and 5 s;
  (c) GUIDED, arm, take off to 10 m, hover 20 s; (d) 100 m north with a GUIDED position
  target (SET_POSITION_TARGET_GLOBAL_INT) and a 5 s hold; (e) climb to 20 m, hold, down
  to 10 m, hold; (f) the low battery failsafe (BATT_FS_LOW_ACT 2, RTL): a reset below
  BATT_LOW_MAH while armed, then a reset just above it so that the consumption crosses
  it, until the copter lands and disarms; (g) the critical failsafe (BATT_CRT_MAH,
  BATT_FS_CRT_ACT 1, LAND) on a second short flight;
- ``battery_resets``: each MAV_CMD_BATTERY_RESET with its COMMAND_ACK and the
  BATTERY_STATUS before and after; ``failsafes``: the failsafe texts and mode changes
  with their times from the reset that caused them; ``mode_sequence``; ``summary``:
  median currents (hover, cruise at speed, climb, descent) and mAh per phase.

Run SITL and this script only inside a loopback-only network namespace (SITL listens on
0.0.0.0). The version string the vehicle reports goes into ``about``.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

from pymavlink.dialects.v20 import ardupilotmega as R

from ftlbo_mav.errors import FtlboError
from ftlbo_mav.link.discovery import discover, wait_ready
from ftlbo_mav.link.endpoints import open_links

from .battery_log import (
    FIELDS,
    M_PER_DEG_LAT,
    Recorder,
    battery_status,
    current_a,
    median,
    mode_changes,
    summarise,
)
from .launcher import SitlSwarm
from .recording import HOME, version

SYSID = 1
READ_PARAMS = ("BATT_MONITOR", "BATT_CAPACITY", "BATT_LOW_MAH", "BATT_CRT_MAH",
               "BATT_LOW_VOLT", "BATT_CRT_VOLT", "BATT_FS_LOW_ACT", "BATT_FS_CRT_ACT",
               "BATT_LOW_TIMER", "BATT_FS_VOLTSRC", "BATT_ARM_MAH", "BATT_ARM_VOLT",
               "SIM_BATT_CAP_AH", "SIM_BATT_VOLTAGE", "FS_OPTIONS", "WPNAV_SPEED",
               "WPNAV_SPEED_UP", "WPNAV_SPEED_DN")
EXTRA_PARAMS = ("RTL_ALT", "RTL_LOIT_TIME", "RTL_SPEED", "LAND_SPEED", "LAND_SPEED_HIGH",
                "DISARM_DELAY")
STREAM_HZ = 5.0
BATTERY_MASK = 1  # bit 0: the first battery (AP_BattMonitor::reset_remaining_mask)
TAKEOFF_M, CLIMB_TO_M, NORTH_M = 10.0, 20.0, 100.0
CROSS_AFTER_S = 10.0  # a reset just above a threshold is crossed after about this long

class Session:
    """The vehicle, the recorder, the phases and the document being built."""

    def __init__(self, v, rec: Recorder, doc: dict):
        self.v, self.rec, self.doc = v, rec, doc

    def log(self, text: str) -> None:
        print(f"[{self.rec.now():8.2f}] {text}", file=sys.stderr, flush=True)

    def phase(self, name: str, description: str) -> dict:
        p = {"name": name, "description": description, "start": self.rec.now(), "end": None}
        self.doc["phases"].append(p)
        self.log(f"phase {name}: {description}")
        return p

    @staticmethod
    def end(p: dict, rec: Recorder) -> None:
        p["end"] = rec.now()

    def set_param(self, name: str, value: float, why: str) -> float | None:
        """PARAM_SET, then the PARAM_VALUE it is answered with (read back once more)."""
        t = self.rec.now()
        s = self.v.status
        with self.v._changed:
            s.params.pop(name, None)
        got = None
        for _ in range(3):
            self.v.send(R.MAVLink_param_set_message(SYSID, 1, name.encode(), float(value),
                                                    R.MAV_PARAM_TYPE_REAL32))
            if self.v.wait_for(lambda st: name in st.params, 1.0):
                got = s.params[name]
                break
        back = self.v.read_param(name)
        self.doc["param_changes"].append({"t": t, "name": name, "value": value,
                                          "answered": got, "read_back": back, "why": why})
        self.log(f"set {name} = {value:g} (read back {back})")
        return back

    def battery_reset(self, percent: float, label: str) -> dict:
        """MAV_CMD_BATTERY_RESET(mask, percent); its ack and BATTERY_STATUS around it."""
        before = battery_status(self.rec.last("BATTERY_STATUS"))
        t_sent = self.rec.now()
        result = self.v.command(R.MAV_CMD_BATTERY_RESET, BATTERY_MASK, percent,
                                step="battery reset")
        ack = self.rec.first_after("COMMAND_ACK", t_sent,
                                   lambda r: r[1] == R.MAV_CMD_BATTERY_RESET)
        t_ack = ack[0] if ack else self.rec.now()
        time.sleep(1.2)
        after = self.rec.first_after("BATTERY_STATUS", t_ack)
        after_1s = self.rec.first_after("BATTERY_STATUS", t_ack + 1.0)
        entry = {"label": label, "t_sent": t_sent, "param1_battery_mask": BATTERY_MASK,
                 "param2_percent": percent, "result": result,
                 "result_name": R.enums["MAV_RESULT"][result].name, "t_ack": t_ack,
                 "armed": self.v.status.armed, "mode": self.v.status.mode,
                 "battery_status_before": before, "battery_status_after": battery_status(after),
                 "battery_status_1s_after": battery_status(after_1s)}
        self.doc["battery_resets"].append(entry)
        self.log(f"BATTERY_RESET {percent:.3f} %: {entry['result_name']}; after: "
                 f"{entry['battery_status_after']}")
        return entry

    def hold(self, seconds: float) -> None:
        time.sleep(seconds)

    def goto(self, lat: float, lon: float, alt: float, *, timeout_s: float = 90.0) -> bool:
        """Send the GUIDED position target until the copter is there and still."""
        self.v.goto(lat, lon, alt)

        def there(s) -> bool:
            if s.lat_deg is None:
                return False
            dn = (s.lat_deg - lat) * M_PER_DEG_LAT
            de = (s.lon_deg - lon) * M_PER_DEG_LAT * math.cos(math.radians(lat))
            return (math.hypot(dn, de) < 1.0 and abs(s.alt_m - alt) < 0.3
                    and s.ground_speed_m_s < 0.3 and abs(s.climb_m_s) < 0.2)

        return self.v.wait_for(there, timeout_s)

    def wait_failsafe(self, t_from: float, word: str, timeout_s: float) -> dict:
        """Wait for "Battery 1 is <word>" and the mode change after ``t_from``."""
        deadline = time.monotonic() + timeout_s
        start_mode = self.v.status.mode
        text = mode_t = None
        while time.monotonic() < deadline:
            if text is None:
                text = next((x for x in self.rec.texts_since(t_from)
                             if x["text"].startswith(f"Battery 1 is {word}")), None)
            if mode_t is None and self.v.status.mode != start_mode:
                mode_t = self.rec.now()
            if text is not None and mode_t is not None:
                break
            time.sleep(0.1)
        return {"text": text, "mode_changed_seen_t": mode_t}


def fly(s: Session, home_lat: float, home_lon: float) -> None:
    v, rec, doc = s.v, s.rec, s.doc
    params = doc["params_after_boot"]
    capacity = params.get("BATT_CAPACITY") or 3300.0

    p = s.phase("a_ground_disarmed", "10 s disarmed on the ground")
    s.hold(10.0)
    s.end(p, rec)

    p = s.phase("b_battery_reset_60", "MAV_CMD_BATTERY_RESET param1 1 (battery mask: first "
                "battery), param2 60 (percent), disarmed, then 5 s")
    p["reset"] = s.battery_reset(60.0, "b: disarmed, 60 %")
    s.hold(5.0)
    s.end(p, rec)

    p = s.phase("c_takeoff", f"GUIDED, arm, MAV_CMD_NAV_TAKEOFF {TAKEOFF_M:g} m")
    v.set_mode("GUIDED", timeout_s=30)
    v.arm(budget_s=90)
    p["armed_t"] = rec.now()
    v.takeoff(TAKEOFF_M)
    p["reached"] = v.wait_for(lambda st: abs(st.alt_m - TAKEOFF_M) < 0.2
                              and abs(st.climb_m_s) < 0.1, 60)
    s.end(p, rec)
    p = s.phase("c_hover_20s", f"hover at {TAKEOFF_M:g} m for 20 s")
    s.hold(20.0)
    s.end(p, rec)

    north_lat = home_lat + NORTH_M / M_PER_DEG_LAT
    p = s.phase("d_north_100m", f"{NORTH_M:g} m north at {TAKEOFF_M:g} m, GUIDED position "
                "target (SET_POSITION_TARGET_GLOBAL_INT, position only), default speed")
    p["target"] = [north_lat, home_lon, TAKEOFF_M]
    p["arrived"] = s.goto(north_lat, home_lon, TAKEOFF_M)
    s.end(p, rec)
    p = s.phase("d_hold", "hold 5 s")
    s.hold(5.0)
    s.end(p, rec)

    p = s.phase("e_climb_to_20m", f"climb to {CLIMB_TO_M:g} m (same position target)")
    p["arrived"] = s.goto(north_lat, home_lon, CLIMB_TO_M)
    s.end(p, rec)
    p = s.phase("e_hold_20m", "hold 5 s")
    s.hold(5.0)
    s.end(p, rec)
    p = s.phase("e_descend_to_10m", f"descend to {TAKEOFF_M:g} m")
    p["arrived"] = s.goto(north_lat, home_lon, TAKEOFF_M)
    s.end(p, rec)
    p = s.phase("e_hold_10m", "hold 5 s")
    s.hold(5.0)
    s.end(p, rec)

    hover_a = median(current_a(rec.between(
        "SYS_STATUS", *next((q["start"], q["end"]) for q in doc["phases"]
                            if q["name"] == "c_hover_20s")))) or 15.0
    margin_mah = hover_a * CROSS_AFTER_S / 3.6

    # (f) the low failsafe
    p = s.phase("f_prepare", "BATTERY_RESET to 100 % (armed), then BATT_LOW_MAH (if 0 in "
                "the defaults) and BATT_FS_LOW_ACT 2 (RTL); BATT_LOW_TIMER left as it is")
    p["reset"] = s.battery_reset(100.0, "f: armed, 100 % before setting the thresholds")
    low_mah = params.get("BATT_LOW_MAH") or 0.0
    if low_mah <= 0:
        low_mah = round(0.6 * capacity)
        p["set_low_mah"] = s.set_param("BATT_LOW_MAH", low_mah,
                                       "BATT_LOW_MAH is 0 after boot: 60 % of BATT_CAPACITY")
    p["set_fs_low_act"] = s.set_param("BATT_FS_LOW_ACT", 2, "low failsafe action RTL")
    p["low_timer"] = v.read_param("BATT_LOW_TIMER")
    s.hold(3.0)
    s.end(p, rec)

    below_pct = round(100.0 * (low_mah - 0.1 * capacity) / capacity, 3)
    p = s.phase("f_reset_below_low", f"armed in GUIDED: BATTERY_RESET to {below_pct:g} % "
                f"(remaining {capacity * below_pct / 100:.0f} mAh < BATT_LOW_MAH "
                f"{low_mah:g}), then watch 15 s for a failsafe")
    t_reset = rec.now()
    p["reset"] = s.battery_reset(below_pct, "f: armed, below BATT_LOW_MAH")
    res = s.wait_failsafe(t_reset, "low", 15.0)
    p["failsafe_text"], p["mode_change_seen_t"] = res["text"], res["mode_changed_seen_t"]
    p["texts_after_reset"] = rec.texts_since(t_reset)
    p["mode_after"] = v.status.mode
    s.end(p, rec)
    fired = v.status.mode != "GUIDED" or res["text"] is not None
    doc["failsafes"].append({"label": "low: reset below BATT_LOW_MAH while armed",
                             "t_reset": t_reset, "fired": fired, **res,
                             "mode_after": v.status.mode})

    if not fired:
        above_pct = round(100.0 * (low_mah + margin_mah) / capacity, 3)
        p = s.phase("f_reset_above_low", f"BATTERY_RESET to {above_pct:g} % (remaining "
                    f"{low_mah + margin_mah:.1f} mAh, {margin_mah:.1f} mAh above BATT_LOW_MAH: "
                    f"about {CROSS_AFTER_S:g} s of hover at {hover_a:g} A), hover until the "
                    "consumption crosses it, then until landed and disarmed (120 s)")
        t_reset = rec.now()
        p["reset"] = s.battery_reset(above_pct, "f: armed, just above BATT_LOW_MAH")
        if p["reset"]["result"] != R.MAV_RESULT_ACCEPTED:
            # the other way: a BATT_LOW_MAH just under what remains (the monitor re-reads it)
            bs = s.rec.last("BATTERY_STATUS")
            remaining = capacity - (bs[1] if bs else 0)
            p["fallback"] = s.set_param("BATT_LOW_MAH", round(remaining - margin_mah),
                                        "BATTERY_RESET refused: threshold just below remaining")
        res = s.wait_failsafe(t_reset, "low", 60.0)
        p["failsafe_text"], p["mode_change_seen_t"] = res["text"], res["mode_changed_seen_t"]
        doc["failsafes"].append({"label": "low: consumption crosses BATT_LOW_MAH",
                                 "t_reset": t_reset, **res})
    else:
        p = s.phase("f_failsafe_landing", "the failsafe fired on the reset below: follow it")
    p["landed_disarmed"] = v.wait_for(lambda st: not st.armed, 120.0)
    p["texts_after_reset"] = rec.texts_since(t_reset)
    s.end(p, rec)
    f = doc["failsafes"][-1]
    f["disarmed_t"] = rec.now() if p["landed_disarmed"] else None
    if f.get("text"):
        f["text_after_reset_s"] = round(f["text"]["t"] - t_reset, 3)
    f["mode_changes_after_reset"] = [m for m in mode_changes(rec) if m["t"] >= t_reset]
    for m in f["mode_changes_after_reset"]:
        m["after_reset_s"] = round(m["t"] - t_reset, 3)
    if not p["landed_disarmed"]:
        s.log("not disarmed within 120 s after the low failsafe: LAND, then skip (g)")
        v.set_mode("LAND")
        v.wait_for(lambda st: not st.armed, 90.0)
        return

    # (g) the critical failsafe, on its own
    p = s.phase("g_prepare", "disarmed: BATTERY_RESET 100 %, BATT_LOW_MAH 0 (low off, so "
                "the critical one is seen alone), BATT_CRT_MAH 30 % of capacity, "
                "BATT_FS_CRT_ACT 1 (LAND)")
    p["reset"] = s.battery_reset(100.0, "g: disarmed, 100 %")
    crt_mah = round(0.3 * capacity)
    p["set"] = [s.set_param("BATT_LOW_MAH", 0, "g: low failsafe off"),
                s.set_param("BATT_CRT_MAH", crt_mah, "g: 30 % of BATT_CAPACITY"),
                s.set_param("BATT_FS_CRT_ACT", 1, "g: critical action LAND")]
    s.end(p, rec)
    p = s.phase("g_takeoff", f"GUIDED, arm, take off to {TAKEOFF_M:g} m, hover 3 s")
    v.set_mode("GUIDED", timeout_s=30)
    v.arm(budget_s=60)
    v.takeoff(TAKEOFF_M)
    p["reached"] = v.wait_for(lambda st: abs(st.alt_m - TAKEOFF_M) < 0.2
                              and abs(st.climb_m_s) < 0.1, 60)
    s.hold(3.0)
    s.end(p, rec)
    crt_pct = round(100.0 * (crt_mah + margin_mah) / capacity, 3)
    p = s.phase("g_reset_above_critical", f"BATTERY_RESET to {crt_pct:g} % ({margin_mah:.1f} "
                "mAh above BATT_CRT_MAH), until the critical failsafe lands and disarms (90 s)")
    t_reset = rec.now()
    p["reset"] = s.battery_reset(crt_pct, "g: armed, just above BATT_CRT_MAH")
    res = s.wait_failsafe(t_reset, "critical", 60.0)
    p["landed_disarmed"] = v.wait_for(lambda st: not st.armed, 90.0)
    p["texts_after_reset"] = rec.texts_since(t_reset)
    s.end(p, rec)
    f = {"label": "critical: consumption crosses BATT_CRT_MAH", "t_reset": t_reset, **res,
         "disarmed_t": rec.now() if p["landed_disarmed"] else None}
    if res["text"]:
        f["text_after_reset_s"] = round(res["text"]["t"] - t_reset, 3)
    f["mode_changes_after_reset"] = [m for m in mode_changes(rec) if m["t"] >= t_reset]
    for m in f["mode_changes_after_reset"]:
        m["after_reset_s"] = round(m["t"] - t_reset, 3)
    doc["failsafes"].append(f)
    if not p["landed_disarmed"]:
        v.set_mode("LAND")
        v.wait_for(lambda st: not st.armed, 90.0)


def record_battery(binary: str | None, defaults: list, t0: float) -> dict:
    """Start the SITL copter, fly the phases; the ``battery.json`` content (written even
    when a step failed: ``error`` says which)."""
    from ftlbo_mav.flight.vehicle import FlightVehicle

    rec = Recorder(t0, sysid=SYSID)
    doc: dict = {"about": {}, "params_after_boot": {}, "params_other": {},
                 "param_changes": [], "stream_requests": [], "phases": [],
                 "battery_resets": [], "failsafes": []}
    with SitlSwarm(binary=binary, homes=[HOME], defaults=defaults, speedup=1.0) as swarm:
        links = open_links(swarm.urls, connect_timeout_s=30.0)
        try:
            wait_ready(links, [SYSID], timeout_s=180.0)
            found, _missing = discover(links, [SYSID], timeout_s=5.0)
            link = found[SYSID]
            link.taps.append(rec)
            with link.channel(SYSID) as channel:
                banner = version(channel)
            print(f"recording {banner}", file=sys.stderr)
            doc["about"] = {
                "firmware": banner,
                "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
                "recorded_by": "sitl/battery.py (python -m sitl.battery)",
                "sitl": f"{swarm.binary}, instance 0 (tcp:127.0.0.1:5760), model quad, "
                        "speedup 1, started by sitl/launcher.py (--wipe)",
                "defaults": [str(d) for d in swarm.defaults],
                "home": list(HOME),
                "clock": "t: seconds since the script's t0 (time.monotonic at start), "
                         "the arrival time of each message",
            }
            v = FlightVehicle("uav1", SYSID, link, position_hz=STREAM_HZ)
            session = Session(v, rec, doc)
            try:
                doc["params_after_boot"] = {n: v.read_param(n) for n in READ_PARAMS}
                doc["params_other"] = {n: v.read_param(n) for n in EXTRA_PARAMS}
                session.log(f"params {doc['params_after_boot']}")
                rec.on = True
                for msgid in (R.MAVLINK_MSG_ID_SYS_STATUS, R.MAVLINK_MSG_ID_BATTERY_STATUS,
                              R.MAVLINK_MSG_ID_GLOBAL_POSITION_INT):
                    t = rec.now()
                    result = v.command(R.MAV_CMD_SET_MESSAGE_INTERVAL, msgid,
                                       1e6 / STREAM_HZ, step="message interval")
                    doc["stream_requests"].append({"t": t, "message_id": msgid,
                                                   "interval_us": 1e6 / STREAM_HZ,
                                                   "result": result})
                # the link re-asks until each arrives (SITL may drop an early interval)
                link.want(SYSID, {R.MAVLINK_MSG_ID_SYS_STATUS: STREAM_HZ,
                                  R.MAVLINK_MSG_ID_BATTERY_STATUS: STREAM_HZ,
                                  R.MAVLINK_MSG_ID_GLOBAL_POSITION_INT: STREAM_HZ})
                time.sleep(2.0)
                v.wait_for(lambda st: st.lat_deg is not None, 10.0)
                fly(session, v.status.lat_deg or HOME[0], v.status.lon_deg or HOME[1])
            except (FtlboError, ValueError, OSError) as exc:
                doc["error"] = f"{type(exc).__name__}: {exc} (at t={rec.now()})"
                session.log(f"error: {exc}")
                try:
                    if v.status.armed:
                        v.set_mode("LAND")
                        v.wait_for(lambda st: not st.armed, 90.0)
                except FtlboError:
                    pass
            finally:
                time.sleep(1.0)
                v.close()
                link.taps.remove(rec)
        finally:
            for link in links:
                link.close()
    doc["mode_sequence"] = mode_changes(rec)
    doc["summary"] = summarise(rec, doc)
    doc["statustext"] = rec.texts
    doc["messages"] = {k: {"fields": list(f), "rows": rec.rows[k]} for k, f in FIELDS.items()}
    doc["messages"]["notes"] = (
        "SYS_STATUS voltage_battery mV, current_battery 10 mA (-1 unknown), "
        "battery_remaining %; BATTERY_STATUS current_consumed mAh, energy_consumed hJ, "
        "current_battery cA, voltages0 mV (the pack voltage, no cell voltages), "
        "time_remaining s (0: not provided), charge_state MAV_BATTERY_CHARGE_STATE; "
        "GLOBAL_POSITION_INT lat/lon 1e-7 deg, relative_alt mm, vx/vy/vz cm/s (NED); "
        "HEARTBEAT custom_mode (ArduCopter mode number), base_mode (128: armed)")
    return doc


def main(argv: list[str] | None = None) -> int:
    t0 = time.monotonic()
    parser = argparse.ArgumentParser(prog="python -m sitl.battery", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", required=True, type=Path, help="folder for battery.json")
    parser.add_argument("--binary", help="arducopter binary (default: $ARDUPILOT_SITL)")
    parser.add_argument("--defaults", action="append", default=[],
                        help="defaults .parm file (e.g. ArduPilot's copter.parm)")
    args = parser.parse_args(argv)
    try:
        doc = record_battery(args.binary, args.defaults, t0)
    except (FtlboError, ValueError, OSError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "battery.json").write_text(json.dumps(doc, indent=1) + "\n")
    print(f"wrote {args.out / 'battery.json'}", file=sys.stderr)
    return 1 if "error" in doc else 0


if __name__ == "__main__":
    sys.exit(main())
