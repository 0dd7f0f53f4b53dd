"""The collective return (flight/homeward.py, planning/homeward.py): when a flight ends
early the vehicles ``fly`` still answers for fly home on routes planned at that moment and
land at their homes, keeping the clearance and ``min_separation``, the vehicle that left
kept out. Judged on a second link to every vehicle (SITL's SERIAL1): SIM_STATE, the
simulator's true position, where the back end sends it.

The emulator, or ArduPilot SITL when ARDUPILOT_SITL is set (docs/flight.md has the SITL
runs).
"""

from __future__ import annotations

from contextlib import contextmanager

import numpy as np
import pytest
from pymavlink.dialects.v20 import ardupilotmega as R

from ftlbo_mav import clock
from ftlbo_mav.ardupilot.modes import mode_name
from ftlbo_mav.flight.planned import load_planned_flight
from ftlbo_mav.flight.record import fitted_times
from ftlbo_mav.planning.homeward import INSIDE_MARGIN_M

from .fleet import BACKEND, vehicles
from .test_departures import (
    HOMES,
    OPTIONS,
    SecondPort,
    _fly_with,
    _upload,
    example,  # noqa: F401 - the fixtures plan_dir builds on
    plan_dir,  # noqa: F401
)

pytestmark = pytest.mark.sitl

SPEEDUP = 1.0  # SITL in real time; the emulator on a virtual clock

LANDED_WITHIN_M = 1.0  # issue 29: every remaining vehicle lands within 1 m of its home


def _in_auto_for(track, seconds: float, time_scale: float) -> None:
    """Until ``track``'s vehicle has flown ``seconds`` (its time) in AUTO; ``time_scale``:
    the vehicles' seconds per second of the test's clock."""
    assert track.wait(lambda p: p.armed and p.mode == "AUTO", 120.0)
    clock.sleep(seconds / time_scale)


class Track(SecondPort):
    """A vehicle's second link that records, for the whole test, where the vehicle says it
    is (GLOBAL_POSITION_INT at 10 Hz, its arrival times refitted on the vehicle's own
    ``time_boot_ms``: an emulator run faster than real time delivers them in bursts) and
    its modes."""

    def __init__(self, url: str, sysid: int) -> None:
        super().__init__(url, sysid)
        self.rows: list[tuple[float, float, float, float, float]] = []  # t, boot, lat, lon, alt
        self.modes: list[tuple[float, str]] = []  # (t, mode) at every change
        self.stop = clock.Event()
        self.thread = clock.Thread(self._run, name=f"track uav{sysid}")
        self.thread.start()

    ASKS = ((R.MAVLINK_MSG_ID_GLOBAL_POSITION_INT, 1e5),)
    """The messages asked for (id, interval in microseconds), again every 5 s."""

    def _run(self) -> None:
        next_ask = 0.0
        while not self.stop.is_set():
            now = clock.monotonic()
            if now >= next_ask:
                for msgid, interval_us in self.ASKS:
                    self.conn.mav.command_long_send(self.sysid, 1,
                                                    R.MAV_CMD_SET_MESSAGE_INTERVAL, 0, msgid,
                                                    interval_us, 0, 0, 0, 0, 0)
                next_ask = now + 5.0
            try:
                msg = self.conn.recv_match(blocking=False)
                if msg is None:
                    self.conn.select(0.05)
                    continue
            except OSError:
                return  # its vehicle is gone
            if msg.get_srcSystem() != self.sysid:
                continue
            if msg.get_type() == "HEARTBEAT" and msg.type != R.MAV_TYPE_GCS:
                mode = mode_name(msg.custom_mode)
                if mode != self.mode:
                    self.modes.append((now, mode))
                self.mode = mode
                self.armed = bool(msg.base_mode & R.MAV_MODE_FLAG_SAFETY_ARMED)
            else:
                self.record(msg, now)

    def record(self, msg, now: float) -> None:
        """One message other than HEARTBEAT, received at ``now``."""
        if msg.get_type() == "GLOBAL_POSITION_INT":
            self.rows.append((now, msg.time_boot_ms / 1000.0, msg.lat * 1e-7,
                              msg.lon * 1e-7, msg.relative_alt / 1000.0))

    def wait(self, predicate, timeout_s: float) -> bool:
        """As :meth:`SecondPort.wait`, on what the recording thread reads."""
        deadline = clock.monotonic() + timeout_s
        while clock.monotonic() < deadline:
            if predicate(self):
                return True
            clock.sleep(0.02)
        return False

    def enu(self, frame, since: float = -np.inf) -> np.ndarray:
        """``(T, 4)``: time (refitted), east, north, up above home, from ``since`` on."""
        if len(self.rows) < 3:
            return np.zeros((0, 4))
        t, boot, lat, lon, alt = np.array(self.rows, float).T
        _, first = np.unique(boot, return_index=True)  # a report seen twice: once
        t, boot, lat, lon, alt = (v[first] for v in (t, boot, lat, lon, alt))
        t = fitted_times(t, boot)
        keep = t >= since
        return np.column_stack([t[keep], frame.to_enu(lat_deg=lat[keep], lon_deg=lon[keep],
                                                      alt_m=alt[keep])])

    def home_started(self, frame, after: float) -> float:
        """When it set off home after ``after``: put back in AUTO (its route home), or,
        where its BRAKE was too short for a HEARTBEAT to show it (an emulator run fast),
        when it had stopped (on its track) before."""
        for (_t0, before), (t, mode) in zip(self.modes, self.modes[1:]):
            if t > after and mode == "AUTO" and before != "AUTO":
                return t
        track = self.enu(frame, after)
        speed = np.hypot(*np.diff(track[:, 1:3], axis=0).T) / np.maximum(
            np.diff(track[:, 0]), 1e-6)
        stopped = np.flatnonzero(speed < 0.3)
        assert len(stopped), f"uav{self.sysid} never stopped after the fault"
        return float(track[stopped[0], 0])

    def close(self) -> None:
        self.stop.set()
        self.thread.join(timeout=2.0)
        super().close()


@contextmanager
def _tracked(folder):
    """Three vehicles with the plan in ``folder`` uploaded and a :class:`Track` on each
    one's second link: ``(fleet, tracks)``; the tracks closed after."""
    with vehicles(3, homes=HOMES, speedup=SPEEDUP, virtual=True, **OPTIONS) as fleet:
        _upload(folder, fleet.urls)
        tracks = [Track(url, i + 1) for i, url in enumerate(fleet.serial1_urls)]
        try:
            yield fleet, tracks
        finally:
            for t in tracks:
                t.close()


def _judge_home(planned, tracks, returning, gone, fault_t: float) -> dict:
    """:func:`_judge` over the ``returning`` vehicles' tracks from where each set off
    home after the fault."""
    frame = planned.frame
    return _judge(planned, {j: tracks[j].enu(frame, tracks[j].home_started(frame, fault_t))
                            for j in returning}, gone)


def _at(track: np.ndarray, t: np.ndarray) -> np.ndarray:
    return np.column_stack([np.interp(t, track[:, 0], track[:, k]) for k in (1, 2, 3)])


def _judge(planned, tracks: dict[int, np.ndarray], gone: np.ndarray) -> dict:
    """Over the flights home (``tracks``, each from where it started home): each vehicle's
    landing distance from its home, the smallest clearance from the obstacles, the
    smallest separation between two of them and the smallest distance to ``gone``
    ``(3,)`` (the vehicle that left: where it was last seen)."""
    out = {"landed_m": {}, "clearance_m": np.inf, "separation_m": np.inf, "from_gone_m": np.inf}
    for j, tr in tracks.items():
        home = planned.paths[j][0][:2]
        out["landed_m"][j] = round(float(np.hypot(*(tr[-1, 1:3] - home))), 3)
        d = np.hypot(*(tr[:, None, 1:3] - planned.centres[None]).transpose(2, 0, 1))
        airborne = tr[:, 3] > 0.3
        out["clearance_m"] = min(out["clearance_m"],
                                 float((d - planned.radii)[airborne].min()))
        gap = np.linalg.norm(tr[:, 1:] - gone, axis=1)
        # the way home may begin closer than min_separation (the vehicle flew on into the
        # spot of the one that left before it was stopped): then it may come 0.5 m
        # closer than it began (planning/homeward.py INSIDE_MARGIN_M), no more
        out["from_gone_m"] = min(out["from_gone_m"], float(gap[airborne].min()))
        out.setdefault("gone_allowed_m", {})[j] = round(
            min(planned.min_separation_m, float(gap[0]) - INSIDE_MARGIN_M), 3)
        out.setdefault("gone_kept", {})[j] = bool(gap[airborne].min()
                                                  >= out["gone_allowed_m"][j] - 1e-3)
    pairs = list(tracks.items())
    for a, (_i, ta) in enumerate(pairs):
        for _j, tb in pairs[a + 1:]:
            t = np.linspace(min(ta[0, 0], tb[0, 0]), max(ta[-1, 0], tb[-1, 0]), 4000)
            pa, pb = _at(ta, t), _at(tb, t)
            up = (pa[:, 2] > 0.3) | (pb[:, 2] > 0.3)
            out["separation_m"] = min(out["separation_m"], float(
                np.linalg.norm(pa - pb, axis=1)[up].min()))
    return {k: (round(v, 3) if isinstance(v, float) else v) for k, v in out.items()}


def _check(result, planned, judged, returning) -> None:
    out = result.output
    assert result.exit_code == 1, out
    assert "Traceback" not in out
    for j in returning:
        line = next(x for x in out.splitlines() if x.strip().startswith(f"uav{j + 1} ("))
        assert "flying home on a planned route" in line, line
        assert line.endswith("landed (disarmed)"), line
        assert judged["landed_m"][j] <= LANDED_WITHIN_M, judged
    assert judged["clearance_m"] >= planned.clearance_m, judged
    assert judged["separation_m"] >= planned.min_separation_m, judged
    assert all(judged["gone_kept"].values()), judged


def test_a_vehicle_lost_mid_leg_the_others_fly_home_and_land_there(plan_dir):  # noqa: F811
    planned = load_planned_flight(plan_dir)
    times = {}
    with _tracked(plan_dir) as (fleet, tracks):

        def fault():
            _in_auto_for(tracks[0], 5.0, fleet.time_scale)
            times["fault"] = clock.monotonic()
            fleet.kill(1)  # uav2's autopilot dies (SITL: its process, by pid)
            tracks[1].stop.set()  # its second link is gone with it
            return times["fault"]

        result, _took = _fly_with(plan_dir, fleet.urls, fault, "--lost-wait", "3")
        for j in (0, 2):
            assert tracks[j].wait(lambda p: not p.armed, 5.0)
        clock.sleep(0.5)
    gone = tracks[1].enu(planned.frame)[-1, 1:]
    judged = _judge_home(planned, tracks, (0, 2), gone, times["fault"])
    print(f"[{BACKEND}] lost mid-leg, the others home: {judged}")
    _check(result, planned, judged, (0, 2))


def test_a_mode_taken_over_the_others_fly_home_around_it(plan_dir):  # noqa: F811
    planned = load_planned_flight(plan_dir)
    times = {}
    with _tracked(plan_dir) as (fleet, tracks):

        def fault():
            _in_auto_for(tracks[2], 5.0, fleet.time_scale)
            times["fault"] = clock.monotonic()
            tracks[2].set_mode("BRAKE")  # uav3's pilot takes it over and holds it there
            return times["fault"]

        try:
            result, _took = _fly_with(plan_dir, fleet.urls, fault)
            for j in (0, 1):
                assert tracks[j].wait(lambda p: not p.armed, 5.0)
            held = tracks[2].enu(planned.frame)[-1, 1:]
        finally:
            tracks[2].set_mode("LAND")
    judged = _judge_home(planned, tracks, (0, 1), held, times["fault"])
    print(f"[{BACKEND}] mode taken over, the others home: {judged}")
    _check(result, planned, judged, (0, 1))
    assert "uav3 (sysid 3): mode: switched to BRAKE" in result.output


def test_a_vehicle_lost_in_the_take_off_the_others_come_down_at_home(plan_dir):  # noqa: F811
    planned = load_planned_flight(plan_dir)
    with _tracked(plan_dir) as (fleet, tracks):

        def fault():
            assert tracks[0].wait(lambda p: p.armed, 120.0)
            clock.sleep(1.0 / fleet.time_scale)  # climbing
            fleet.kill(1)
            tracks[1].stop.set()
            return clock.monotonic()

        result, _took = _fly_with(plan_dir, fleet.urls, fault, "--lost-wait", "3")
        for j in (0, 2):
            assert tracks[j].wait(lambda p: not p.armed, 5.0)
    out = result.output
    print(f"[{BACKEND}] lost in the take-off:\n{out}")
    assert result.exit_code == 1, out
    assert "Traceback" not in out
    for j in (0, 2):
        track = tracks[j].enu(planned.frame)
        assert float(np.hypot(*(track[-1, 1:3] - planned.paths[j][0][:2]))) <= LANDED_WITHIN_M
        line = next(x for x in out.splitlines() if x.strip().startswith(f"uav{j + 1} ("))
        assert line.endswith("landed (disarmed)"), line
