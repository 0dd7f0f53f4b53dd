"""What the formation does when one vehicle leaves the plan.

:class:`FaultPolicy` is the operator's choice (``fly --on-departure``):

- ``rally`` (default): the others stop where they are, within one watch cycle of the
  departure: on the legs with MAV_CMD_DO_PAUSE_CONTINUE, which stops the copter *on its
  planned track* (AC_WPNav shapes its track clock to zero), elsewhere with BRAKE (which
  stops along the direction of flight, off the track in a turn). Once all have stopped
  (or after ``stop_s``) they go home together (``homeward``, :mod:`.homeward`): routes
  planned at that moment, each on its own layer, clear of the obstacles on the predicted
  flown path, of one another on one clock and of the vehicle that left, flown as
  uploaded missions that end in NAV_LAND at home. A vehicle that has no such route (or
  whose route could not be uploaded) goes to its rally point instead: ArduCopter's RTL,
  which climbs where it is and flies a straight line to the nearer of home and the
  vehicle's rally points (ArduCopter/mode_rtl.cpp, AP_Rally::calc_best_rally_or_home_location)
  -- but only where that line keeps the plan's clearance from every obstacle and 2 m
  from the other vehicles (``route_check``); where it does not, the vehicle lands where
  it stopped, and its line says why;
- ``land``: the others stop, then land where they are (LAND: straight down, and the
  obstacles are vertical cylinders);
- ``continue``: the others carry on with their missions; the flight ends when they have.

A vehicle whose position is in doubt (a ``navigation`` departure: its GPS jumped, its fix
or accuracy fell short, its EKF doubts itself) is not flown on its own estimate, whatever
the policy. ArduCopter flies every mode on the estimate and EKF3 takes a jump of the GPS up
over seconds (:mod:`ftlbo_mav.sim.gps`, recorded on SITL): a copter held where its estimate
is drifts, where it truly is, by as much as its GPS jumped, the other way. So it stops as
the others do (on its track: stops alike keep them apart), holds there while the others
leave its reach (its keep-out grown by its doubt and shifted the way it drifts,
:func:`~ftlbo_mav.flight.homeward.keep_out`; their ways home first fly straight out of
it and land out of it), at most :data:`DOUBT_HOLD_S`, then lands where it is (LAND,
straight down). Before, a route home planned from its estimate carried the error to the
others' landing spots (ArduCopter 4.5.6 SITL, a 3 m glitch: it landed 0.05 m from
another).

The vehicle that left is never commanded against what its pilot, its failsafe or another
station chose (:data:`~ftlbo_mav.flight.departures.VEHICLE_CHOSE`). One that left
without choosing (its link was lost and came back, it made no progress) is answered as
the others are. :class:`Response` carries the policy out over the watch's cycles and
writes, per vehicle, what happened and what was done.
"""

from __future__ import annotations

import enum
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from .. import clock
from .departures import LINK_BACK, LINK_LOST, NAVIGATION, DepartureWatch, Event
from .vehicle import FlightError, FlightVehicle

STOPPED_M_S = 0.3
STOP_AGAIN_S = 1.0  # a vehicle not slowing this long after its pause is paused again
HOME_BUDGET_FACTOR = 1.5  # the flight home is watched this many times its predicted length
DOUBT_HOLD_S = 30.0  # a vehicle in doubt holds at most this long for the others to leave
LAND_SPEED_M_S = 0.5  # LAND's slowest descent (ArduCopter's LAND_SPEED default), for its budget


class FaultPolicy(enum.Enum):
    RALLY = "rally"
    LAND = "land"
    CONTINUE = "continue"

    @property
    def then_mode(self) -> str | None:
        return {FaultPolicy.RALLY: "RTL", FaultPolicy.LAND: "LAND"}.get(self)


@dataclass
class _Answer:
    """What the flight does with one vehicle: ``stage`` stop -> then -> sent, or, going
    home together, stop -> home -> sent."""

    stage: str = "stop"
    mode: str | None = None  # the mode it is sent to once stopped
    since: float = 0.0
    sent_t: float = 0.0
    speed_at_send: float = 0.0  # its ground speed when its pause was sent
    tries: int = 0
    done: list[str] = field(default_factory=list)


class Response:
    """The policy at work: ``react`` to the watch's events, ``step`` every cycle,
    ``ended`` once nothing is left to wait for; ``lines`` for the report."""

    def __init__(self, policy: FaultPolicy, *, stop_s: float = 3.0, budget_s: float = 50.0,
                 lost_wait_s: float = 15.0, confirm_tries: int = 5,
                 t0: float | None = None,
                 route_check: Callable[[int], str | None] = lambda _j: None,
                 landing: Callable[[int], bool] = lambda _j: False,
                 homeward=None, doubt: Callable[[int], float] = lambda _j: 0.0,
                 clear_of: Callable[[int], bool] = lambda _j: True) -> None:
        self.policy = policy
        self.doubt = doubt  # vehicle -> how far from its estimate it may truly be (m)
        self.doubtful: dict[int, float] = {}  # in doubt: landed where it is, kept out
        self.clear_of = clear_of  # vehicle in doubt -> every other one is out of its reach
        # the collective return (flight/homeward.GoingHome), for the rally policy; None:
        # each vehicle RTL or LAND as its line allows
        self.homeward = homeward
        self.home_started = False
        self.home_tried: set[int] = set()  # the vehicles whose way home was planned
        self.landing = landing  # vehicle -> already on its mission's final landing
        self.route_check = route_check  # vehicle -> why RTL from here is not safe, or None
        self.stop_s, self.budget_s, self.confirm_tries = stop_s, budget_s, confirm_tries
        self.lost_wait_s = lost_wait_s  # how long a lost link is waited for
        self.t0 = clock.monotonic() if t0 is None else t0
        self.first_t: float | None = None
        self.left: dict[int, list[Event]] = {}  # vehicle -> its departures
        self.chose: set[int] = set()  # left by its own choice: never commanded
        self.lost: dict[int, float] = {}  # link down now: since when
        self.answers: dict[int, _Answer] = {}
        self.history: dict[int, list[str]] = {}  # what was done, kept after a choice

    @property
    def active(self) -> bool:
        return self.first_t is not None

    def _at(self, t: float) -> str:
        return f"t+{t - self.t0:.1f} s"

    # -- events
    def react(self, events: Sequence[Event], vehicles: Sequence[FlightVehicle],
              watch: DepartureWatch, now: float) -> None:
        for e in events:
            if e.kind == LINK_BACK:
                self.lost.pop(e.index, None)
                if e.index in self.answers:
                    self.answers[e.index].done.append(f"link back at {self._at(e.t)}")
                elif self.active:
                    self._answer(e.index, vehicles, watch, now,
                                 note=f"link back at {self._at(e.t)}")
                continue
            self.left.setdefault(e.index, []).append(e)
            if e.kind == NAVIGATION and e.index not in self.doubtful:
                self.doubtful[e.index] = self.doubt(e.index)
                a = self.answers.get(e.index)
                if a is not None and a.mode != "LAND":  # answered before: answered anew
                    self.history.setdefault(e.index, []).extend(self.answers.pop(e.index).done)
            if e.kind == LINK_LOST:
                self.lost[e.index] = e.t
            if e.vehicle_chose:
                self.chose.add(e.index)
                gone = self.answers.pop(e.index, None)  # its own choice now stands
                if gone is not None:
                    self.history.setdefault(e.index, []).extend(gone.done)
            watch.expect(e.index, None)
            watch.legs(e.index, False)
            watch.stop_landing_check(e.index)
            if e.index in self.doubtful:  # whatever the policy, as soon as it is named
                self._answer(e.index, vehicles, watch, now)
            if self.first_t is None:
                self.first_t = e.t
                if self.policy is not FaultPolicy.CONTINUE:
                    for j in range(len(vehicles)):
                        self._answer(j, vehicles, watch, now)
            elif self.policy is not FaultPolicy.CONTINUE:
                self._answer(e.index, vehicles, watch, now)

    def _answer(self, j: int, vehicles: Sequence[FlightVehicle], watch: DepartureWatch,
                now: float, *, note: str | None = None) -> None:
        """Stop vehicle j (BRAKE) unless it chose otherwise, cannot be reached or landed
        (one in doubt too: :meth:`_doubt_step` lands it)."""
        if ((self.policy is FaultPolicy.CONTINUE and j not in self.doubtful)
                or j in self.chose or j in self.lost or j in self.answers):
            return
        v = vehicles[j]
        if not v.status.armed:
            return
        if self.landing(j) and v.status.mode == "AUTO":
            self.history.setdefault(j, []).append("already on its final landing: left to land")
            return
        a = self.answers[j] = _Answer(since=now)
        if note:
            a.done.append(note)
        watch.stop_landing_check(j)
        watch.legs(j, False)
        watch.expect(j, None)
        on_track = v.status.mode == "AUTO"
        a.sent_t, a.speed_at_send = now, v.status.ground_speed_m_s
        try:
            if on_track:  # stays in AUTO, stops on its track (ModeAuto::pause)
                v.send_pause(True)
                a.done.append(f"stopped on its track (pause) at {self._at(now)}")
            else:
                v.send_mode("BRAKE")
                a.done.append(f"stopped (BRAKE) at {self._at(now)}")
        except FlightError as exc:
            a.done.append(f"could not be stopped ({exc})")
            a.stage = "failed"

    # -- every cycle
    def step(self, vehicles: Sequence[FlightVehicle], watch: DepartureWatch,
             now: float) -> None:
        if self.policy is FaultPolicy.RALLY and self.homeward is not None:
            self._home(vehicles, watch, now)
        for j, a in self.answers.items():
            v = vehicles[j]
            then = self.policy.then_mode
            speed = v.status.ground_speed_m_s
            if (a.stage == "stop" and v.status.mode == "AUTO" and now - a.sent_t >= STOP_AGAIN_S
                    and speed >= STOPPED_M_S and speed >= 0.9 * a.speed_at_send):
                # not slowing: a pause lost on the way (a radio's burst, an outage) leaves
                # it flying its mission (a paused AC_WPNav slows within a second or two)
                a.sent_t, a.speed_at_send = now, speed
                try:
                    v.send_pause(True)
                except FlightError:
                    pass  # its link: the watch reports that
            if j in self.doubtful:
                self._doubt_step(j, a, v, watch, now)
                continue
            if a.stage == "stop" and then is not None and not self._going_home(j):
                slow = v.status.ground_speed_m_s < STOPPED_M_S
                if slow or now - a.since >= self.stop_s:
                    a.stage, a.tries = "then", 0
                    why = self.route_check(j) if then == "RTL" else None
                    if why is not None:
                        a.mode = "LAND"
                        a.done.append(f"no RTL: {why}")
                    else:
                        a.mode = then
            then = a.mode
            if a.stage == "then":
                if v.status.mode == then:
                    a.stage = "sent"
                    a.done.append(f"{then} at {self._at(now)}"
                                  + (" (to its rally point or home)" if then == "RTL" else ""))
                    watch.expect(j, then)
                elif a.tries >= self.confirm_tries:
                    a.stage = "failed"
                    a.done.append(f"did not switch to {then} (still {v.status.mode})")
                elif now - a.sent_t >= 1.0:
                    a.sent_t, a.tries = now, a.tries + 1
                    try:
                        v.send_mode(then)
                    except FlightError:
                        pass  # its link: the watch reports that

    def _doubt_step(self, j: int, a: _Answer, v: FlightVehicle, watch: DepartureWatch,
                    now: float) -> None:
        """Vehicle j, in doubt, stopped with the others (on its track: their stops alike
        keep them apart), holds there while the others leave its reach (their ways home
        begin by leaving it), at most :data:`DOUBT_HOLD_S`, then lands where it is: its
        descent, drifting as EKF3 takes its jump up, never crosses the layer of a copter
        still beside it."""
        if a.stage == "stop" and (v.status.ground_speed_m_s < STOPPED_M_S
                                  or now - a.since >= self.stop_s):
            a.stage, a.since = "hold", now
            a.done.append(f"its position in doubt by {self.doubtful[j]:.1f} m: holding where "
                          f"it stopped until the others are out of its reach")
            # watched until it is down: its hold, then LAND's descent from where it is
            descent_s = max(v.status.alt_m, 0.0) / LAND_SPEED_M_S
            self.budget_s = max(self.budget_s, now - (self.first_t or now) + DOUBT_HOLD_S
                                + descent_s + 10.0)
        if a.stage == "hold":
            clear = self.clear_of(j)
            if clear or now - a.since >= DOUBT_HOLD_S:
                a.stage, a.mode, a.tries, a.sent_t = "then", "LAND", 0, now - 1.0
                a.done.append(("the others out of its reach" if clear else
                               f"the others still in its reach after {DOUBT_HOLD_S:g} s")
                              + f": landing where it is (LAND), not flown on its estimate, "
                              f"at {self._at(now)}")
        if a.stage == "then" and v.status.mode != "LAND" and now - a.sent_t >= 1.0:
            if a.tries >= self.confirm_tries:
                a.stage = "failed"
                a.done.append(f"did not switch to LAND (still {v.status.mode})")
                return
            a.sent_t, a.tries = now, a.tries + 1
            try:
                v.send_mode("LAND")
            except FlightError:
                pass  # its link: the watch reports that
        elif a.stage == "then" and v.status.mode == "LAND":
            a.stage = "sent"
            a.done.append(f"LAND at {self._at(now)}")
            watch.expect(j, "LAND")

    def _going_home(self, j: int) -> bool:
        """Vehicle j waits for (or is in) the collective return, not for its own RTL."""
        return (self.policy is FaultPolicy.RALLY and self.homeward is not None
                and (not self.home_started or self.answers[j].stage == "home"
                     or j not in self.home_tried))

    def _home(self, vehicles: Sequence[FlightVehicle], watch: DepartureWatch,
              now: float) -> None:
        """The collective return: started once every vehicle stopped has come to rest (or
        ``stop_s`` after it was stopped); each one's outcome taken as it comes."""
        # the first answered go together once all have stopped; one answered later (its
        # link back) once it has stopped, its route clear of those already on their way
        stopping = {j: a for j, a in self.answers.items()
                    if a.stage == "stop" and j not in self.home_tried and j not in self.doubtful}
        ready = bool(stopping) and all(
            vehicles[j].status.ground_speed_m_s < STOPPED_M_S or now - a.since >= self.stop_s
            for j, a in stopping.items())
        if ready:
            self.home_started = True
            self.home_tried.update(stopping)
            left = [j for j in self.left if j not in self.answers or j in self.doubtful]
            try:
                refused = self.homeward.start(list(stopping), left, now, doubt=self.doubtful)
            except Exception as exc:  # noqa: BLE001 - never leave the others in the air
                refused = {j: f"the routes home could not be planned ({exc})" for j in stopping}
            plan = getattr(self.homeward, "plan", None)
            if plan is not None and plan.routes:  # watched until they are down, and some
                longest = max(r.seconds for r in plan.routes.values())
                self.budget_s = max(self.budget_s,
                                    now - self.first_t + HOME_BUDGET_FACTOR * longest + 10.0)
            for j, a in stopping.items():
                if j in refused:
                    a.done.append(f"no route home: {refused[j]}")
                    a.since = now - self.stop_s  # RTL or LAND now, as its line allows
                else:
                    a.stage = "home"
        for j, started, line in self.homeward.results():
            a = self.answers.get(j)
            if a is None or a.stage != "home":
                continue
            a.done.append(line + f" at {self._at(now)}" if started else line)
            if started:
                a.stage, a.mode = "sent", "AUTO"
                watch.expect(j, "AUTO")
            else:
                a.stage, a.since = "stop", now - self.stop_s  # RTL or LAND, as it allows

    def ended(self, vehicles: Sequence[FlightVehicle], now: float) -> bool:
        """Every vehicle the flight answers for has landed, or the budget is spent. Not
        waited for: one that left by its own choice (its pilot or failsafe flies it now);
        one whose link is down is waited for ``lost_wait_s`` after it was lost (it may
        still fly its mission and come back), then reported gone."""
        if not self.active:
            return False
        if now - self.first_t >= self.budget_s:
            return True
        return all(not v.status.armed or j in self.chose
                   or (j in self.lost and now - self.lost[j] >= self.lost_wait_s)
                   for j, v in enumerate(vehicles))

    # -- the report
    def lines(self, vehicles: Sequence[FlightVehicle]) -> list[str]:
        """One line per vehicle: what happened, what was done, where it is now."""
        out = []
        for j, v in enumerate(vehicles):
            what: list[str] = []
            for e in self.left.get(j, []):
                what.append(f"{e.kind} at {self._at(e.t)} ({e.detail})")
            if j in self.left:
                if j in self.chose:
                    what.append("left to what it chose: not commanded")
                elif j in self.lost:
                    what.append(f"gone: not heard from again within "
                                f"{clock.monotonic() - self.left[j][0].t:.0f} s")
            what += self.history.get(j, [])
            if j in self.answers:
                what += self.answers[j].done
            s = v.status
            if j in self.lost:
                state = "link down"
            elif s.armed:
                state = f"still flying in {s.mode} at {s.alt_m:.1f} m when the flight ended"
            else:
                state = "landed (disarmed)"
            if not what:
                what.append("carried on with its mission"
                            if self.policy is FaultPolicy.CONTINUE else "nothing to do")
            out.append(f"{v.name} (sysid {v.sysid}): " + "; ".join(what) + f"; {state}")
        return out
