"""How SITL's copters followed their position targets, from their own DataFlash logs.

``python -m sitl.tracking DIR [DIR ...] --out tracking.json`` reads each flight folder
that ``benchmarks/flight.py --keep DIR`` kept on SITL (``DIR/runN-STRATEGY``, one
``instanceN/logs/*.BIN`` per copter) and writes, per copter and for the time it flew in
AUTO, what AC_PosControl logged at 10 Hz (PSCN / PSCE: the target position TP, desired
velocity DV and acceleration DA that AC_WPNav set, and the copter's position P and
velocity V, in metres and seconds from the EKF origin), the parameters its position
controller ran with (PARM) and the drag coefficients SITL's frame printed at start
(``sitl.log``: "Suggested EK3_DRAG_BCOEF_* = ..., EK3_DRAG_MCOEF = ...").
``tests/conformance/test_tracking.py`` holds :mod:`ftlbo_mav.ardupilot.poscontrol` to it:
the recorded targets in, the recorded positions out.

``--climb``: the vertical instead (PSCD: target altitude TPU, desired climb DVU and
vertical acceleration DAU, the copter's altitude PU, climb VU and acceleration AU, up
from the EKF origin), from the takeoff's liftoff to ``--after`` seconds into AUTO, times
from AUTO's start (``tests/conformance/test_climb.py``: the vertical follower and the
stopping point AUTO starts from).

``--takeoff``: the horizontal (PSCN / PSCE, the fields above) from the takeoff's liftoff
to ``--after`` seconds into AUTO, times from AUTO's start, with the wind SITL blew
(SIM_WIND_*): how a copter lifting off in wind is blown off its target and comes back,
and the state it starts its first leg in (``tests/conformance/test_takeoff_wind.py``).
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path

from pymavlink import DFReader

PARAMS = ("PSC_POSXY_P", "PSC_VELXY_P", "PSC_VELXY_I", "PSC_VELXY_D", "PSC_VELXY_IMAX",
          "PSC_VELXY_FLTE", "PSC_VELXY_FLTD", "ANGLE_MAX", "ATC_INPUT_TC", "WPNAV_ACCEL",
          "WPNAV_SPEED", "WPNAV_JERK")
FIELDS = ("t", "TPN", "TPE", "DVN", "DVE", "DAN", "DAE", "PN", "PE", "VN", "VE")
AUTO = 3  # ArduCopter's mode number


def _header(m, names, params: dict, version: str | None) -> str | None:
    """A log's PARM (of ``names``, into ``params``) or MSG; returns the firmware version
    (the first "ArduCopter V..." message, else ``version``)."""
    if m.get_type() == "PARM" and m.Name in names:
        params[m.Name] = float(m.Value)
    elif m.get_type() == "MSG" and version is None and m.Message.startswith("ArduCopter V"):
        return m.Message
    return version


def read_log(path: Path) -> dict:
    """One copter's PSCN / PSCE rows in AUTO (times from AUTO's start), its PARMs and
    version."""
    log = DFReader.DFReader_binary(str(path), zero_time_base=True)
    params, version, rows, north = {}, None, [], None
    auto_since = None
    while True:
        m = log.recv_match(type=["PARM", "MODE", "PSCN", "PSCE", "MSG"])
        if m is None:
            break
        kind = m.get_type()
        if kind in ("PARM", "MSG"):
            version = _header(m, PARAMS, params, version)
        elif kind == "MODE":
            auto_since = m.TimeUS if m.ModeNum == AUTO else None
        elif auto_since is not None and kind == "PSCN":
            north = m
        elif auto_since is not None and kind == "PSCE" and north is not None:
            if north.TimeUS == m.TimeUS:
                rows.append([round((m.TimeUS - auto_since) / 1e6, 4),
                             *(round(float(getattr(north, f)), 4) for f in ("TPN",)),
                             round(float(m.TPE), 4), round(float(north.DVN), 4),
                             round(float(m.DVE), 4), round(float(north.DAN), 4),
                             round(float(m.DAE), 4), round(float(north.PN), 4),
                             round(float(m.PE), 4), round(float(north.VN), 4),
                             round(float(m.VE), 4)])
            north = None
    return {"version": version, "params": params, "rows": rows}


CLIMB_PARAMS = ("PSC_POSZ_P", "PSC_VELZ_P", "PSC_VELZ_I", "PSC_VELZ_FLTE", "PSC_ACCZ_P",
                "PSC_ACCZ_I", "PSC_ACCZ_IMAX", "PSC_ACCZ_FLTE", "WPNAV_ACCEL_Z", "PSC_JERK_Z",
                "MOT_THST_HOVER", "MOT_THST_EXPO")
CLIMB_FIELDS = ("t", "TPU", "DVU", "DAU", "PU", "VU", "AU")
LIFTOFF_M = 0.05  # above where it stood: the takeoff has left the ground


def read_climb(path: Path, after_s: float) -> dict:
    """One copter's PSCD rows from its liftoff to ``after_s`` into AUTO (times from
    AUTO's start, metres up), its PARMs (the last value logged) and version."""
    log = DFReader.DFReader_binary(str(path), zero_time_base=True)
    params, version, rows, auto_at, ground = {}, None, [], None, None
    while True:
        m = log.recv_match(type=["PARM", "MODE", "PSCD", "MSG"])
        if m is None:
            break
        kind = m.get_type()
        if kind in ("PARM", "MSG"):
            version = _header(m, CLIMB_PARAMS, params, version)
        elif kind == "MODE" and m.ModeNum == AUTO and auto_at is None:
            auto_at = m.TimeUS / 1e6
        elif kind == "PSCD":
            t = m.TimeUS / 1e6
            if ground is None:
                ground = -float(m.PD)
            if auto_at is not None and t > auto_at + after_s:
                break
            if rows or -float(m.PD) > ground + LIFTOFF_M:
                rows.append([t, *(round(-float(getattr(m, f)), 4)
                                  for f in ("TPD", "DVD", "DAD", "PD", "VD", "AD"))])
    if auto_at is None:
        raise SystemExit(f"{path}: never in AUTO")
    for r in rows:
        r[0] = round(r[0] - auto_at, 4)
    return {"version": version, "params": params, "rows": rows}


TAKEOFF_PARAMS = PARAMS + ("SIM_WIND_SPD", "SIM_WIND_DIR", "SIM_WIND_TURB", "SIM_WIND_T")


def read_takeoff(path: Path, after_s: float) -> dict:
    """One copter's PSCN / PSCE rows from its liftoff (PSCD: LIFTOFF_M above where it
    stood) to ``after_s`` into AUTO (times from AUTO's start), its PARMs and version."""
    log = DFReader.DFReader_binary(str(path), zero_time_base=True)
    params, version, rows, auto_at, ground, lifted, north = {}, None, [], None, None, None, None
    while True:
        m = log.recv_match(type=["PARM", "MODE", "PSCN", "PSCE", "PSCD", "MSG"])
        if m is None:
            break
        kind = m.get_type()
        if kind in ("PARM", "MSG"):
            version = _header(m, TAKEOFF_PARAMS, params, version)
        elif kind == "MODE" and m.ModeNum == AUTO and auto_at is None:
            auto_at = m.TimeUS / 1e6
        elif kind == "PSCD":
            if ground is None:
                ground = -float(m.PD)
            if lifted is None and -float(m.PD) > ground + LIFTOFF_M:
                lifted = m.TimeUS / 1e6
        elif kind == "PSCN":
            north = m
        elif kind == "PSCE" and north is not None and north.TimeUS == m.TimeUS:
            t = m.TimeUS / 1e6
            if auto_at is not None and t > auto_at + after_s:
                break
            if lifted is not None:
                rows.append([t, *(round(float(getattr(north if f.endswith("N") else m, f)), 4)
                                  for f in FIELDS[1:])])
            north = None
    if auto_at is None or lifted is None:
        raise SystemExit(f"{path}: no liftoff or never in AUTO")
    for r in rows:
        r[0] = round(r[0] - auto_at, 4)
    return {"version": version, "params": params, "liftoff_s": round(lifted - auto_at, 4),
            "rows": rows}


def drag_coefficients(sitl_log: Path) -> dict:
    """The drag SITL's frame printed at start."""
    text = sitl_log.read_text(errors="replace")
    found = re.search(r"EK3_DRAG_BCOEF_\* = ([0-9.]+), EK3_DRAG_MCOEF = ([0-9.]+)", text)
    if not found:
        raise SystemExit(f"{sitl_log}: no drag coefficients printed")
    return {"bcoef": float(found[1]), "mcoef": float(found[2])}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("flights", nargs="+", type=Path,
                        help="flight folders kept by benchmarks/flight.py --keep")
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--note", default="", help="how the flights were flown")
    parser.add_argument("--climb", action="store_true",
                        help="the vertical from the takeoff into AUTO (PSCD) instead")
    parser.add_argument("--after", type=float, default=3.0,
                        help="--climb: seconds of AUTO kept")
    parser.add_argument("--takeoff", action="store_true",
                        help="the horizontal from the takeoff into AUTO (PSCN/PSCE) instead")
    args = parser.parse_args(argv)
    if args.takeoff:
        flights = _flights(args.flights, lambda instance, log: read_takeoff(log, args.after))
        about = (f"the horizontal position controller's own log (PSCN/PSCE at 10 Hz, metres "
                 f"from the EKF origin) from the takeoff's liftoff to {args.after:g} s into "
                 f"AUTO, t from AUTO's start; `python -m sitl.tracking --takeoff`")
        fields = FIELDS
    elif args.climb:
        flights = _flights(args.flights, lambda instance, log: read_climb(log, args.after))
        about = (f"the vertical position controller's own log (PSCD at 10 Hz, metres up) "
                 f"from the takeoff's liftoff to {args.after:g} s into AUTO, t from AUTO's "
                 f"start; `python -m sitl.tracking --climb`")
        fields = CLIMB_FIELDS
    else:
        flights = _flights(args.flights, lambda instance, log: read_log(log) | {
            "drag": drag_coefficients(instance / "sitl.log")})
        about = ("the position controller's own log (PSCN/PSCE at 10 Hz) in AUTO; "
                 "`python -m sitl.tracking`")
        fields = FIELDS
    version = next((c["version"] for f in flights for c in f["copters"] if c["version"]), "?")
    doc = {"about": f"{version} SITL (copter.parm), {about}. {args.note}",
           "fields": list(fields), "flights": flights}
    args.out.write_text(json.dumps(doc, separators=(",", ":")) + "\n")
    print(f"wrote {args.out}", file=sys.stderr)
    return 0


def _flights(folders, read) -> list[dict]:
    """Each kept flight's copters, ``read(instance folder, its last DataFlash log)``."""
    flights = []
    for folder in folders:
        copters = []
        for instance in sorted(folder.glob("instance*")):
            logs = sorted((instance / "logs").glob("*.BIN"))
            if not logs:
                raise SystemExit(f"{instance}: no DataFlash log")
            copter = read(instance, logs[-1]) | {"instance": instance.name}
            copters.append(copter)
            print(f"{folder.name}/{instance.name}: {len(copter['rows'])} rows",
                  file=sys.stderr)
        flights.append({"flight": folder.name, "copters": copters})
    return flights


if __name__ == "__main__":
    raise SystemExit(main())
