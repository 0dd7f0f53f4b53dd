"""The battery recording's log and what it says (``python -m sitl.battery``).

:class:`Recorder` keeps every message of interest from the copter with its arrival time;
:func:`summarise` reads the ``summary`` of ``battery.json`` from it: median currents
(hover, cruise at speed, climb, descent), mAh per phase, the tracks after each failsafe.
The flight that fills the log is :mod:`sitl.battery`.
"""

from __future__ import annotations

import math
import statistics
import threading
import time

from pymavlink.dialects.v20 import ardupilotmega as R

from ftlbo_mav.ardupilot.modes import mode_name

M_PER_DEG_LAT = 111318.84502145034  # ArduPilot's LATLON_TO_M * 1e7
FIELDS = {
    "SYS_STATUS": ("t", "voltage_battery", "current_battery", "battery_remaining"),
    "BATTERY_STATUS": ("t", "current_consumed", "energy_consumed", "current_battery",
                       "battery_remaining", "voltages0", "time_remaining", "charge_state"),
    "GLOBAL_POSITION_INT": ("t", "time_boot_ms", "lat", "lon", "relative_alt", "vx", "vy",
                            "vz"),
    "HEARTBEAT": ("t", "custom_mode", "base_mode"),
    "COMMAND_ACK": ("t", "command", "result"),
}


class Recorder:
    """Every message of interest from the vehicle, with its arrival time since ``t0``."""

    def __init__(self, t0: float, *, sysid: int):
        self.t0 = t0
        self.sysid = sysid
        self.lock = threading.Lock()
        self.rows: dict[str, list] = {k: [] for k in FIELDS}
        self.texts: list[dict] = []
        self.on = False

    def now(self) -> float:
        return round(time.monotonic() - self.t0, 3)

    def __call__(self, msg) -> None:
        if msg.get_srcSystem() != self.sysid:
            return
        kind = msg.get_type()
        t = self.now()
        with self.lock:
            if kind == "STATUSTEXT":  # every one, from connection on
                self.texts.append({"t": t, "severity": msg.severity, "text": msg.text})
                return
            if not self.on:
                return
            if kind == "SYS_STATUS":
                row = [t, msg.voltage_battery, msg.current_battery, msg.battery_remaining]
            elif kind == "BATTERY_STATUS":
                row = [t, msg.current_consumed, msg.energy_consumed, msg.current_battery,
                       msg.battery_remaining, msg.voltages[0], msg.time_remaining,
                       msg.charge_state]
            elif kind == "GLOBAL_POSITION_INT":
                row = [t, msg.time_boot_ms, msg.lat, msg.lon, msg.relative_alt, msg.vx,
                       msg.vy, msg.vz]
            elif kind == "HEARTBEAT":
                if msg.get_srcComponent() != 1 or msg.type == R.MAV_TYPE_GCS:
                    return
                row = [t, msg.custom_mode, msg.base_mode]
            elif kind == "COMMAND_ACK":
                row = [t, msg.command, msg.result]
            else:
                return
            self.rows[kind].append(row)

    def last(self, kind: str):
        with self.lock:
            return self.rows[kind][-1] if self.rows[kind] else None

    def between(self, kind: str, start: float, end: float) -> list:
        with self.lock:
            return [r for r in self.rows[kind] if start <= r[0] <= end]

    def texts_since(self, t: float) -> list[dict]:
        with self.lock:
            return [x for x in self.texts if x["t"] >= t]

    def first_after(self, kind: str, t: float, pred=lambda r: True):
        with self.lock:
            return next((r for r in self.rows[kind] if r[0] >= t and pred(r)), None)

def battery_status(row) -> dict | None:
    return None if row is None else dict(zip(FIELDS["BATTERY_STATUS"], row))


def mode_changes(rec: Recorder) -> list[dict]:
    out, last = [], None
    for t, custom, base in rec.rows["HEARTBEAT"]:
        state = (mode_name(custom), bool(base & R.MAV_MODE_FLAG_SAFETY_ARMED))
        if state != last:
            out.append({"t": t, "mode": state[0], "custom_mode": custom, "armed": state[1]})
            last = state
    return out


def median(values):
    return round(statistics.median(values), 3) if values else None


def current_a(rows) -> list[float]:
    return [r[2] / 100.0 for r in rows if r[2] >= 0]


def _integrated_mah(rec: Recorder, start: float, end: float) -> float | None:
    rows = rec.between("SYS_STATUS", start, end)
    if len(rows) < 2:
        return None
    mah = 0.0
    for a, b in zip(rows, rows[1:]):
        mah += 0.5 * (a[2] + b[2]) / 100.0 * (b[0] - a[0]) / 3.6
    return round(mah, 2)


def summarise(rec: Recorder, doc: dict) -> dict:
    phases = {p["name"]: p for p in doc["phases"] if p.get("end") is not None}
    resets = [r["t_sent"] for r in doc["battery_resets"]]
    per_phase = {}
    for p in doc["phases"]:
        if p.get("end") is None:
            continue
        bs = rec.between("BATTERY_STATUS", p["start"], p["end"])
        entry = {"start": p["start"], "end": p["end"],
                 "duration_s": round(p["end"] - p["start"], 3),
                 "integrated_from_sys_status_current_mAh": _integrated_mah(
                     rec, p["start"], p["end"]),
                 "median_current_A": median(current_a(rec.between(
                     "SYS_STATUS", p["start"], p["end"])))}
        if bs:
            entry["current_consumed_first_mAh"] = bs[0][1]
            entry["current_consumed_last_mAh"] = bs[-1][1]
            entry["current_consumed_delta_mAh"] = bs[-1][1] - bs[0][1]
        entry["battery_reset_inside"] = any(p["start"] <= t < p["end"] for t in resets)
        per_phase[p["name"]] = entry

    gpi = rec.rows["GLOBAL_POSITION_INT"]
    home = gpi[0] if gpi else None
    tracks = []
    for f in doc["failsafes"]:
        if not f.get("text") or home is None:
            continue
        t_fs, t_end = f["text"]["t"], f.get("disarmed_t") or 1e9
        rows = [r for r in gpi if t_fs <= r[0] <= t_end]
        if not rows:
            continue

        def dist(r):
            dn = (r[2] - home[2]) * 1e-7 * M_PER_DEG_LAT
            de = ((r[3] - home[3]) * 1e-7 * M_PER_DEG_LAT
                  * math.cos(math.radians(home[2] * 1e-7)))
            return round(math.hypot(dn, de), 2)

        top = max(rows, key=lambda r: r[4])
        tracks.append({"label": f["label"], "from_failsafe_text_t": t_fs,
                       "to_disarm_t": f.get("disarmed_t"),
                       "start_alt_m": rows[0][4] / 1000, "start_dist_from_home_m": dist(rows[0]),
                       "max_alt_m": top[4] / 1000, "max_alt_t": top[0],
                       "max_horizontal_speed_m_s": round(max(math.hypot(r[5], r[6])
                                                             for r in rows) / 100, 2),
                       "max_descent_rate_m_s": round(max(r[7] for r in rows) / 100, 2),
                       "end_dist_from_home_m": dist(rows[-1]),
                       "end_alt_m": rows[-1][4] / 1000,
                       "first_within_2m_of_home_t": next((r[0] for r in rows
                                                          if dist(r) < 2.0), None)})

    def window(name, value, frac=0.9):
        """[first, last] time within phase ``name`` where ``value(row)`` of
        GLOBAL_POSITION_INT is at least ``frac`` of its peak there."""
        p = phases.get(name)
        if p is None:
            return None
        rows = rec.between("GLOBAL_POSITION_INT", p["start"], p["end"])
        if not rows:
            return None
        peak = max(value(r) for r in rows)
        fast = [r for r in rows if value(r) >= frac * peak]
        return {"start": fast[0][0], "end": fast[-1][0], "peak": round(peak, 3),
                "median_in_window": median([value(r) for r in fast])}

    def currents(w):
        if w is None:
            return None
        s = rec.between("SYS_STATUS", w["start"], w["end"])
        b = rec.between("BATTERY_STATUS", w["start"], w["end"])
        return {"window": w, "median_sys_status_current_A": median(current_a(s)),
                "median_battery_status_current_A": median([r[3] / 100.0 for r in b
                                                            if r[3] >= 0]),
                "samples": len(s)}

    hover = phases.get("c_hover_20s")
    out = {
        "current_hover_10m": currents(hover and {"start": hover["start"],
                                                 "end": hover["end"]}),
        "current_cruise_at_speed": currents(window(
            "d_north_100m", lambda r: math.hypot(r[5], r[6]) / 100.0)),
        "current_climb_at_speed": currents(window("e_climb_to_20m", lambda r: -r[7] / 100.0)),
        "current_descent_at_speed": currents(window("e_descend_to_10m",
                                                    lambda r: r[7] / 100.0)),
        "hold_20m": currents(phases.get("e_hold_20m") and {
            "start": phases["e_hold_20m"]["start"], "end": phases["e_hold_20m"]["end"]}),
        "disarmed_ground": currents(phases.get("a_ground_disarmed") and {
            "start": phases["a_ground_disarmed"]["start"],
            "end": phases["a_ground_disarmed"]["end"]}),
        "mAh_per_phase": per_phase,
        "failsafe_tracks": tracks,
        "notes": ("windows for cruise/climb/descent: GLOBAL_POSITION_INT horizontal speed "
                  "(vx, vy) / climb rate (-vz) / descent rate (vz) at >= 90 % of its peak "
                  "in the phase; currents are SYS_STATUS current_battery (10 mA) and "
                  "BATTERY_STATUS current_battery (cA) in A; "
                  "current_consumed_delta_mAh is meaningless where battery_reset_inside; "
                  "failsafe_tracks: GLOBAL_POSITION_INT from the failsafe text to disarm, "
                  "distances from the first position report (home)"),
    }
    return out
