import json

import numpy as np
import pytest
from click.testing import CliRunner

from ftlbo_mav.cli import main
from ftlbo_mav.flight.planned import PlanFolderError, load_planned_flight
from ftlbo_mav.flight.record import FlightRecord, Sample
from ftlbo_mav.flight.report import leg_range, render_report_png, summarize
from ftlbo_mav.mission.files import digest


@pytest.fixture(scope="module")
def plan_dir(tmp_path_factory):
    from tests.conftest import SMALL

    folder = tmp_path_factory.mktemp("plan")
    (folder / "s.toml").write_text(SMALL)
    result = CliRunner().invoke(main, ["plan", str(folder / "s.toml"), "-o", str(folder), "-q"])
    assert result.exit_code == 0, result.output
    return folder


def _fly_perfectly(planned, *, lag_uav: int | None = None) -> FlightRecord:
    """Every UAV along its planned points at 1 m/s, AUTO, sampled at 10 Hz."""
    record = FlightRecord()
    first, last = leg_range(planned)
    for n in range(planned.count):
        path = planned.paths[n]
        seg = np.linalg.norm(np.diff(path, axis=0), axis=1)
        s_of_point = np.concatenate([[0], np.cumsum(seg)])
        for t in np.arange(0, s_of_point[-1], 0.1):
            s = t - (0.5 if n == lag_uav else 0.0)
            enu = np.array([np.interp(max(s, 0), s_of_point, path[:, i]) for i in range(3)])
            lat, lon, alt = planned.frame.to_lla(enu)
            leg = min(first + int(np.searchsorted(s_of_point, t, side="right")) - 1, last)
            record.add(Sample(t, n + 1, float(lat), float(lon), float(alt), "AUTO", True, leg))
    return record


def test_perfect_flight_summary_and_csv_round_trip(plan_dir):
    planned = load_planned_flight(plan_dir)
    record = _fly_perfectly(planned)
    again = FlightRecord.from_csv(record.to_csv())
    assert len(again.samples) == len(record.samples)
    assert again.samples[5].lat_deg == pytest.approx(record.samples[5].lat_deg, abs=1e-8)
    assert record.rate_hz(1) == pytest.approx(10, rel=0.01)

    times, positions, seqs = again.grid([1, 2, 3], planned.frame, rate_hz=10)
    summary = summarize(planned, times, positions, seqs)
    assert summary["formation_error_rms_legs_m"] < 0.01
    assert summary["min_separation_airborne_m"] == pytest.approx(
        summary["planned_min_separation_m"], abs=0.01)
    assert summary["inside_obstacle"] is False
    png = render_report_png(planned, times, positions, seqs, summary)
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 20_000
    json.dumps(summary)


def test_a_lagging_uav_shows_as_formation_error(plan_dir):
    planned = load_planned_flight(plan_dir)
    times, positions, seqs = _fly_perfectly(planned, lag_uav=1).grid([1, 2, 3], planned.frame)
    summary = summarize(planned, times, positions, seqs)
    # 0.5 m behind: the slot error is 2/3 * 0.5 for it and 1/3 * 0.5 for the others
    assert 0.15 < summary["formation_error_rms_legs_m"] < 0.5


def test_folder_errors(tmp_path, plan_dir):
    with pytest.raises(PlanFolderError, match="no such file"):
        load_planned_flight(tmp_path)
    (tmp_path / "plan.json").write_text("{}")
    with pytest.raises(PlanFolderError, match="not a plan.json"):
        load_planned_flight(tmp_path)
    doc = json.loads((plan_dir / "plan.json").read_text())
    doc["uavs"][0]["mission_file"] = "missing.waypoints"
    (tmp_path / "plan.json").write_text(json.dumps(doc))
    with pytest.raises(PlanFolderError, match="missing.waypoints"):
        load_planned_flight(tmp_path)
    doc["uavs"][0]["mission_file"] = "hover.waypoints"
    (tmp_path / "plan.json").write_text(json.dumps(doc))
    for name in ("hover", "uav2", "uav3"):
        source = plan_dir / ("uav1" if name == "hover" else name)
        lines = source.with_suffix(".waypoints").read_text().splitlines()
        kept = [line for line in lines if "\t22\t" not in line]  # drop the takeoff
        kept = [kept[0]] + [f"{i}\t" + line.split("\t", 1)[1] for i, line in enumerate(kept[1:])]
        (tmp_path / f"{name}.waypoints").write_text("\n".join(kept) + "\n")
    with pytest.raises(PlanFolderError, match="SHA-256 differs"):  # not the plan's files
        load_planned_flight(tmp_path)
    for u in doc["uavs"]:  # as if plan.json had been written with them
        u["mission_sha256"] = digest((tmp_path / u["mission_file"]).read_text())
    (tmp_path / "plan.json").write_text(json.dumps(doc))
    with pytest.raises(PlanFolderError, match="no NAV_TAKEOFF"):
        load_planned_flight(tmp_path)


def test_sample_times_remove_link_jitter_using_the_vehicles_clock():
    from ftlbo_mav.flight.record import sample_times

    rng = np.random.default_rng(0)
    boot = np.arange(0, 20, 0.1) * 4.0  # a vehicle clock running 4x faster (time scale)
    true = 3.0 + boot / 4.0
    arrival = true + rng.uniform(0.002, 0.060, boot.size)  # loopback to radio-link jitter
    samples = [Sample(float(t), 1, 0.0, 0.0, 0.0, "AUTO", True, 3, float(b))
               for t, b in zip(arrival, boot)]
    fitted = sample_times(samples)
    assert np.abs(fitted - true).max() < 0.01 < np.abs(arrival - true).max()
    # without the vehicle's time stamps (or after a reboot) arrival times are used as they are
    plain = [Sample(s.t, 1, 0.0, 0.0, 0.0, "AUTO", True, 3) for s in samples]
    assert np.array_equal(sample_times(plain), arrival)
    rebooted = samples[:50] + [Sample(s.t, 1, 0, 0, 0, "AUTO", True, 3, s.boot_s - 30)
                               for s in samples[50:]]
    assert np.array_equal(sample_times(rebooted), arrival)


def test_the_keepers_rough_link_line_names_only_what_was_rough(plan_dir):
    from ftlbo_mav.flight.report import summary_lines

    keeper = {"off_reason": None, "enabled": True, "vehicles": {}, "link_gaps": 1,
              "rough_link_s": 21.0, "worst_jitter_s": 0.0, "worst_gap_s": 1.3}
    line = next(t for t in summary_lines({"keeper": keeper}, plan_dir)
                if t.startswith("formation keeper"))
    assert line == ("formation keeper: no vehicle needed to wait; stood aside 1x for link "
                    "gaps; no pauses for 21 s: the link's reports stopped for up to 1.3 s (a pause "
                    "could not be timed or undone)")
    keeper["worst_jitter_s"] = 0.31
    line = next(t for t in summary_lines({"keeper": keeper}, plan_dir)
                if t.startswith("formation keeper"))
    assert "the link's delays varied by up to 0.31 s and its reports stopped for up to " \
           "1.3 s" in line
