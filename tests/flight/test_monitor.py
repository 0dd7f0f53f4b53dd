import io
import time
from dataclasses import replace
from types import SimpleNamespace

import numpy as np

from ftlbo_mav.flight.monitor import LiveView, Monitor
from ftlbo_mav.flight.planned import load_planned_flight
from ftlbo_mav.flight.status import Status

from ..conftest import EXAMPLE


def _vehicles(planned, shift=(0.0, 0.0, 0.0)):
    out = []
    for n, name in enumerate(planned.names):
        enu = planned.paths[n, 3] + (np.array(shift) if n == 1 else 0.0)
        lat, lon, alt = planned.frame.to_lla(enu)
        status = Status(mode="AUTO", armed=True, lat_deg=float(lat), lon_deg=float(lon),
                        alt_m=float(alt), seq=5, position_t=time.monotonic(),
                        heartbeat_t=time.monotonic())
        out.append(SimpleNamespace(name=name, sysid=n + 1, status=status))
    return out


def test_lines_show_each_vehicle_and_the_group():
    planned = load_planned_flight(EXAMPLE.with_suffix(""))
    monitor = Monitor(planned)
    monitor.vehicles = _vehicles(planned, shift=(0.6, 0.0, 0.0))
    lines = monitor.lines()
    assert len(lines) == 4
    assert lines[0].split()[:4] == ["uav1", "sysid", "1", "AUTO"]
    assert "item 5/8" in lines[0] and "slot" in lines[0]
    # uav2 0.6 m east of its slot: the centroid moves 0.2 m, its slot error is 0.4 m
    assert "slot  0.40 m" in lines[1]
    assert lines[3].startswith("formation error 0.28 m RMS")


def test_recording_and_views():
    planned = load_planned_flight(EXAMPLE.with_suffix(""))
    monitor = Monitor(planned)
    monitor.vehicles = _vehicles(planned)
    for v in monitor.vehicles:
        monitor(v)
    assert [s.sysid for s in monitor.record.samples] == [1, 2, 3]
    assert monitor.record.samples[0].seq == 5
    stream = io.StringIO()
    view = LiveView(monitor, stream)
    view.update()
    view.update()  # a pipe gets the view every few seconds, not at every call
    assert stream.getvalue().count("formation error") == 1
    view.message("starting")
    assert stream.getvalue().endswith("starting\n")


def test_without_a_plan_only_the_vehicles():
    planned = load_planned_flight(EXAMPLE.with_suffix(""))
    monitor = Monitor(None)
    monitor.vehicles = _vehicles(planned)
    lines = monitor.lines()
    assert len(lines) == 3 and "slot" not in lines[0]


def test_a_swarm_larger_than_the_screen_gets_a_summary_that_fits():
    planned = load_planned_flight(EXAMPLE.with_suffix(""))
    monitor = Monitor(planned)
    monitor.vehicles = _vehicles(planned, shift=(0.6, 0.0, 0.0))
    monitor.vehicles[2].status = replace(monitor.vehicles[2].status,
                                         heartbeat_t=time.monotonic() - 10.0)
    assert monitor.lines(max_lines=4) == monitor.lines()  # a line each and the group's fit
    lines = monitor.lines(max_lines=3)  # too few: the summary, at least 5 lines
    assert len(lines) == 5 and lines[0].startswith("3 vehicles: AUTO 3; 3 armed")
    assert lines[1] == "NO HEARTBEAT: uav3"
    assert lines[2] == "farthest from their slots (1 of 3):"
    assert lines[3].split()[0] == "uav2" and "slot  0.40 m" in lines[3]
    assert lines[-1].startswith("formation error 0.28 m RMS")


def test_the_keeper_summary_of_a_large_swarm_is_one_short_line():
    from ftlbo_mav.flight.report import keeper_line

    waited = {f"uav{i}": {"pauses": i % 4 + 1, "seconds_paused": 0.1 * i,
                          "largest_lead_m": -0.01 * i} for i in range(1, 51)}
    line = keeper_line(waited)
    assert line.startswith("50 vehicles waited 1-4x (0.1-5.0 s paused); longest: uav50 ")
    assert line.count("waited") == 4 and len(line) < 300
    few = keeper_line(dict(list(waited.items())[:2]))
    assert few == ("uav1 waited 2x (0.1 s paused, largest lead -0.01 m); "
                   "uav2 waited 3x (0.2 s paused, largest lead -0.02 m)")


def test_each_vehicles_battery_is_shown_recorded_and_summed_up():
    from ftlbo_mav.flight.record import FlightRecord
    from ftlbo_mav.flight.report import battery_summary

    planned = load_planned_flight(EXAMPLE.with_suffix(""))
    monitor = Monitor(planned)
    monitor.vehicles = _vehicles(planned)
    for v, pct in zip(monitor.vehicles, (97, 12, None)):
        v.status.battery_pct = pct
    lines = monitor.lines()
    assert "batt  97 %" in lines[0] and "batt  12 %" in lines[1] and "batt" not in lines[2]
    for v in monitor.vehicles:
        monitor(v)
    monitor.vehicles[0].status.battery_pct = 95
    monitor(monitor.vehicles[0])
    record = FlightRecord.from_csv(monitor.record.to_csv())  # flight.csv, as written
    assert record.battery(1) == (97, 95) and record.battery(3) is None
    summary = battery_summary(planned, record, [1, 2, 3])
    assert summary["uav1"] == {"first_pct": 97, "last_pct": 95, "used_pct": 2}
    assert "uav3" not in summary  # it never said
    # with the plan's [battery]: in mAh beside the mission's predicted charge
    from ftlbo_mav.energy import Battery
    from ftlbo_mav.flight.battery import MissionBattery

    with_battery = replace(planned, battery=MissionBattery(
        Battery(capacity_mah=5200.0, reserve_pct=25.0, hover_current_a=10.0),
        (150.0, 140.0, 140.0), (np.zeros(1),) * 3))
    summary = battery_summary(with_battery, record, [1, 2, 3])
    assert summary["uav1"]["used_mah"] == 104.0 and summary["uav1"]["predicted_mah"] == 150.0


def test_an_older_flight_csv_without_the_battery_reads():
    from ftlbo_mav.flight.record import FlightRecord

    text = ("t,sysid,lat_deg,lon_deg,alt_m,mode,armed,seq,boot_s\n"
            "0.1,1,12.0,109.0,0.0,AUTO,1,3,1.0\n")
    record = FlightRecord.from_csv(text)
    assert record.samples[0].battery_pct == -1 and record.battery(1) is None
