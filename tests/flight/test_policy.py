"""The formation policy (flight/policy.py) on stand-in vehicles: who is stopped, how, what
follows, and that a vehicle that chose is never commanded."""

from __future__ import annotations

from dataclasses import dataclass, field

from ftlbo_mav.flight.departures import (
    LINK_BACK,
    LINK_LOST,
    MODE,
    NAVIGATION,
    NO_PROGRESS,
    DepartureWatch,
    Event,
)
from ftlbo_mav.flight.policy import FaultPolicy, Response
from ftlbo_mav.flight.vehicle import LinkLost


@dataclass
class Status:
    mode: str = "AUTO"
    armed: bool = True
    alt_m: float = 10.0
    ground_speed_m_s: float = 5.0


@dataclass
class StandIn:
    name: str
    sysid: int
    status: Status = field(default_factory=Status)
    sent: list = field(default_factory=list)
    link_up: bool = True

    def send_mode(self, mode: str) -> None:
        if not self.link_up:
            raise LinkLost(self.name, self.sysid, f"mode {mode}", "link down")
        self.sent.append(mode)

    def send_pause(self, pause: bool) -> None:
        self.sent.append("pause" if pause else "continue")


def fleet(n=3):
    return [StandIn(f"uav{i + 1}", i + 1) for i in range(n)]


def response(policy=FaultPolicy.RALLY, **kw):
    return Response(policy, t0=0.0, **kw)


def test_rally_stops_the_others_on_their_track_then_rtl_and_leaves_the_chooser_alone():
    vs, watch = fleet(), DepartureWatch(3)
    r = response()
    vs[2].status.mode = "LOITER"  # its pilot took it
    r.react([Event(2, MODE, "switched to LOITER", 10.0)], vs, watch, 10.0)
    assert [v.sent for v in vs] == [["pause"], ["pause"], []]
    r.step(vs, watch, 10.5)  # still moving: nothing yet
    assert vs[0].sent == ["pause"]
    for v in vs[:2]:
        v.status.ground_speed_m_s = 0.1
    r.step(vs, watch, 11.0)
    assert [v.sent for v in vs] == [["pause", "RTL"], ["pause", "RTL"], []]
    for v in vs[:2]:
        v.status.mode = "RTL"
    r.step(vs, watch, 11.2)
    lines = r.lines(vs)
    assert lines[0].startswith("uav1 (sysid 1): stopped on its track (pause) at t+10.0 s; RTL at")
    assert "mode at t+10.0 s (switched to LOITER); left to what it chose: not commanded" in lines[2]
    assert not r.ended(vs, 20.0)  # uav1 and uav2 still flying
    vs[0].status.armed = vs[1].status.armed = False
    assert r.ended(vs, 30.0)  # uav3 is its pilot's: not waited for
    assert vs[2].sent == []


def test_an_unsafe_return_line_lands_instead_and_says_why():
    vs, watch = fleet(), DepartureWatch(3)
    r = response(route_check=lambda j: "the straight line passes 0.4 m from an obstacle"
                 if j == 0 else None)
    r.react([Event(2, NO_PROGRESS, "stuck", 5.0)], vs, watch, 5.0)
    for v in vs:
        v.status.ground_speed_m_s = 0.0
    r.step(vs, watch, 6.0)
    # no progress is no choice: uav3 is answered as the others are
    assert [v.sent for v in vs] == [["pause", "LAND"], ["pause", "RTL"], ["pause", "RTL"]]
    assert "no RTL: the straight line passes 0.4 m" in r.lines(vs)[0]


def test_a_lost_vehicle_is_answered_once_its_link_is_back():
    vs, watch = fleet(), DepartureWatch(3)
    r = response(FaultPolicy.LAND)
    vs[1].link_up = False
    r.react([Event(1, LINK_LOST, "closed", 3.0)], vs, watch, 3.0)
    assert [v.sent for v in vs] == [["pause"], [], ["pause"]]
    assert r.ended(vs, 4.0) is False
    vs[0].status.armed = vs[2].status.armed = False
    assert not r.ended(vs, 4.0)  # the lost one is waited for a while
    assert r.ended(vs, 18.0)  # 15 s after its loss: gone
    vs[1].link_up = True
    r.react([Event(1, LINK_BACK, "heard from again", 6.0)], vs, watch, 6.0)
    assert vs[1].sent == ["pause"]
    assert not r.ended(vs, 6.0)
    assert "link back at t+6.0 s" in r.lines(vs)[1]


def test_continue_commands_nobody_and_the_budget_ends_it():
    vs, watch = fleet(), DepartureWatch(3)
    r = response(FaultPolicy.CONTINUE, budget_s=50.0)
    r.react([Event(0, MODE, "switched to RTL", 1.0)], vs, watch, 1.0)
    r.step(vs, watch, 5.0)
    assert all(v.sent == [] for v in vs)
    assert r.active and not r.ended(vs, 40.0) and r.ended(vs, 51.0)
    assert "carried on with its mission" in r.lines(vs)[1]


def test_before_the_legs_the_others_brake_and_a_dead_link_is_said():
    vs, watch = fleet(), DepartureWatch(3)
    for v in vs:
        v.status.mode = "GUIDED"
    vs[0].link_up = False  # its link broke as the answer went out
    r = response()
    r.react([Event(2, MODE, "switched to LAND", 1.0)], vs, watch, 1.0)
    assert vs[1].sent == ["BRAKE"]
    assert "could not be stopped" in r.lines(vs)[0]


class Homeward:
    """A stand-in for flight/homeward.GoingHome: uav2 has no way home, uav1's start is
    reported when the test says so."""

    def __init__(self) -> None:
        self.started_with = None
        self.pending = []
        self.plan = None

    def start(self, answered, left, now, *, doubt=None):
        self.started_with = (sorted(answered), sorted(left), now)

        class Plan:
            routes = {0: type("R", (), {"seconds": 40.0})()}

        self.plan = Plan()
        return {1: "no way home around the obstacles"}

    def results(self):
        out, self.pending = self.pending, []
        return out


def test_rally_goes_home_together_once_all_have_stopped_and_falls_back_per_vehicle():
    vs, watch = fleet(), DepartureWatch(3)
    home = Homeward()
    r = response(homeward=home, budget_s=50.0)
    vs[2].status.mode = "LOITER"  # its pilot took it: kept out, never commanded
    r.react([Event(2, MODE, "switched to LOITER", 10.0)], vs, watch, 10.0)
    vs[0].status.ground_speed_m_s = 0.1
    r.step(vs, watch, 10.5)  # uav2 still moving: no one goes yet, nor RTL
    assert home.started_with is None and [v.sent for v in vs[:2]] == [["pause"], ["pause"]]
    vs[1].status.ground_speed_m_s = 0.1
    r.step(vs, watch, 11.0)
    assert home.started_with == ([0, 1], [2], 11.0)
    # uav2 has no route: RTL as its line allows, at once; uav1 waits for its start home
    assert [v.sent for v in vs] == [["pause"], ["pause", "RTL"], []]
    assert r.budget_s >= 11.0 - 10.0 + 1.5 * 40.0  # watched until they are down
    home.pending = [(0, True, "flying home on a planned route (...)")]
    r.step(vs, watch, 12.0)
    lines = r.lines(vs)
    assert "flying home on a planned route (...) at t+12.0 s" in lines[0]
    assert "no route home: no way home around the obstacles; RTL at" not in lines[1]
    assert "no route home: no way home around the obstacles" in lines[1]
    assert vs[0].sent == ["pause"]  # AUTO on its route: no RTL asked for


def test_a_route_home_that_could_not_be_started_falls_back_to_rtl():
    vs, watch = fleet(), DepartureWatch(3)
    home = Homeward()
    r = response(homeward=home)
    r.react([Event(2, LINK_LOST, "closed", 5.0)], vs, watch, 5.0)
    for v in vs:
        v.status.ground_speed_m_s = 0.0
    r.step(vs, watch, 6.0)
    home.pending = [(0, False, "its route home was not uploaded (refused)")]
    r.step(vs, watch, 6.5)
    assert vs[0].sent == ["pause", "RTL"]
    assert "its route home was not uploaded (refused)" in r.lines(vs)[0]


def test_a_vehicle_answered_late_goes_home_on_its_own_route_once_it_has_stopped():
    vs, watch = fleet(), DepartureWatch(3)
    home = Homeward()
    calls = []
    real = home.start
    home.start = lambda answered, left, now, doubt=None: calls.append(
        (sorted(answered), now)) or real(answered, left, now)
    r = response(homeward=home)
    vs[1].link_up = False
    r.react([Event(1, LINK_LOST, "closed", 5.0)], vs, watch, 5.0)
    for v in vs:
        v.status.ground_speed_m_s = 0.0
    r.step(vs, watch, 6.0)
    assert calls == [([0, 2], 6.0)]
    vs[1].link_up = True
    vs[1].status.ground_speed_m_s = 4.0
    r.react([Event(1, LINK_BACK, "heard again", 9.0)], vs, watch, 9.0)
    assert vs[1].sent == ["pause"]
    r.step(vs, watch, 9.5)  # still moving: not yet
    assert len(calls) == 1 and vs[1].sent == ["pause"]
    vs[1].status.ground_speed_m_s = 0.1
    r.step(vs, watch, 10.0)
    assert calls[1] == ([1], 10.0)  # its own way home, clear of the others' (the planner)
    assert "no route home" in r.lines(vs)[1]  # the stand-in refuses uav2: RTL as it allows
    assert vs[1].sent == ["pause", "RTL"]


def test_a_stop_that_does_not_slow_the_vehicle_is_sent_again():
    """A pause lost on a radio (a burst, an outage) leaves the copter flying its mission:
    one not slowing a second after its pause is paused again; one slowing is not."""
    vs, watch = fleet(), DepartureWatch(3)
    r = response()
    r.react([Event(2, MODE, "switched to LOITER", 10.0)], vs, watch, 10.0)
    vs[2].status.mode = "LOITER"
    vs[1].status.ground_speed_m_s = 2.0  # slowing
    r.step(vs, watch, 11.0)
    assert vs[0].sent == ["pause", "pause"] and vs[1].sent == ["pause"]
    r.step(vs, watch, 11.5)
    assert vs[0].sent == ["pause", "pause"]  # a second between


def test_a_copter_in_doubt_holds_where_it_stopped_until_the_others_are_clear_then_lands():
    vs, watch = fleet(), DepartureWatch(3)
    clear = {"now": False}
    starts = []

    class Home:
        plan = None

        def start(self, answered, left, now, *, doubt=None):
            starts.append((sorted(answered), sorted(left), dict(doubt or {})))
            return {}

        def results(self):
            return []

    r = response(homeward=Home(), doubt=lambda j: 3.0, clear_of=lambda j: clear["now"])
    r.react([Event(0, NAVIGATION, "GPS position jumped 3.0 m", 10.0)], vs, watch, 10.0)
    assert [v.sent for v in vs] == [["pause"], ["pause"], ["pause"]]  # stopped alike
    for v in vs:
        v.status.ground_speed_m_s = 0.1
    r.step(vs, watch, 11.0)
    # the others go home, the one in doubt kept out by its doubt; it holds
    assert starts == [([1, 2], [0], {0: 3.0})]
    assert vs[0].sent == ["pause"]
    # watched until it is down: its hold and LAND's descent from 10 m at 0.5 m/s
    assert r.budget_s >= 1.0 + 30.0 + 20.0
    r.step(vs, watch, 12.0)
    assert vs[0].sent == ["pause"]
    clear["now"] = True
    r.step(vs, watch, 13.0)
    assert vs[0].sent == ["pause", "LAND"]
    vs[0].status.mode = "LAND"
    r.step(vs, watch, 13.2)
    line = r.lines(vs)[0]
    assert ("its position in doubt by 3.0 m: holding where it stopped until the others are "
            "out of its reach; the others out of its reach: landing where it is (LAND)") in line


def test_a_copter_in_doubt_lands_even_when_the_others_carry_on():
    vs, watch = fleet(), DepartureWatch(3)
    r = response(FaultPolicy.CONTINUE, doubt=lambda j: 2.0)
    r.react([Event(1, NAVIGATION, "fix lost", 10.0)], vs, watch, 10.0)
    assert [v.sent for v in vs] == [[], ["pause"], []]
    vs[1].status.ground_speed_m_s = 0.0
    r.step(vs, watch, 11.0)  # the others are clear (default): it lands at once
    assert vs[1].sent == ["pause", "LAND"]
