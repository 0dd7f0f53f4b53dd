"""The plan's [vehicle] parameters on one vehicle, over the loopback channel (virtual
time): read and compared, set where they differ and read back."""

from __future__ import annotations

import numpy as np
import pytest
from pymavlink.dialects.v20 import ardupilotmega as R

from ftlbo_mav.ardupilot.navigation import Navigation, vehicle_params
from ftlbo_mav.link.mission_protocol import Timing
from ftlbo_mav.link.params import ParamError, read_vehicle_params, set_vehicle_params
from ftlbo_mav.sim.faults import Faults
from ftlbo_mav.sim.loopback import LoopbackChannel
from ftlbo_mav.sim.vehicle import Vehicle

from .support import HOME

PLANNED = vehicle_params(Navigation())
TIMING = Timing(timeout_s=0.5, retries=3)


def channel(**kw) -> LoopbackChannel:
    return LoopbackChannel(Vehicle(sysid=2, home=(*HOME, 0.0)), **kw)


def test_a_vehicle_with_arducopters_defaults_holds_a_default_plans_values():
    assert read_vehicle_params(channel(), PLANNED, timing=TIMING) == []


def test_set_changes_only_what_differs_and_reads_it_back():
    ch = channel()
    assert ch.vehicle.autopilot.set_param("WPNAV_ACCEL", 500.0)
    assert read_vehicle_params(ch, PLANNED, timing=TIMING) == [("WPNAV_ACCEL", 500.0, 250.0)]
    sets = len([m for m in ch.received if m.get_type() == "PARAM_VALUE"])
    assert set_vehicle_params(ch, PLANNED, timing=TIMING) == [("WPNAV_ACCEL", 500.0, 250.0)]
    assert ch.vehicle.autopilot.nav_params().wp_accel == 2.5  # it flies with it now
    assert read_vehicle_params(ch, PLANNED, timing=TIMING) == []
    # read (all) + one PARAM_SET, answered with what it now holds (a read-back of its
    # own), then the read of this test (all)
    assert (len([m for m in ch.received if m.get_type() == "PARAM_VALUE"]) - sets
            == 2 * len(PLANNED) + 1)
    assert set_vehicle_params(ch, PLANNED, timing=TIMING) == []  # nothing left to set


def test_set_rides_out_a_lossy_link():
    ch = channel(faults=Faults(loss_up=0.3, loss_down=0.3))
    ch.vehicle.autopilot.set_param("WPNAV_JERK", 2.0)
    # at 30% loss each way an exchange gets through half the time: resent up to 10 times
    patient = Timing(timeout_s=0.2, retries=10)
    assert set_vehicle_params(ch, PLANNED, timing=patient) == [("WPNAV_JERK", 2.0, 1.0)]
    assert ch.vehicle.autopilot.get_param("WPNAV_JERK") == (1.0, 9)


def test_a_parameter_the_vehicle_does_not_have_is_a_param_error_and_nothing_is_set():
    ch = channel()
    ch.vehicle.autopilot.set_param("WPNAV_ACCEL", 500.0)
    with pytest.raises(ParamError, match="NO_SUCH_PARAM: not answered"):
        set_vehicle_params(ch, {**PLANNED, "NO_SUCH_PARAM": 1.0}, timing=TIMING)
    assert ch.vehicle.autopilot.get_param("WPNAV_ACCEL") == (500.0, 9)


def test_parameters_are_asked_a_window_at_a_time_not_one_round_trip_each():
    """33 parameters over a link of 0.1 s each way: asked a window at a time, so a few
    round trips, not 33 (virtual time)."""
    from ftlbo_mav.link.params import PARAM_WINDOW

    ch = channel(faults=Faults(latency_s=0.1))
    t0 = ch.clock()
    assert read_vehicle_params(ch, PLANNED, timing=TIMING) == []
    round_trips = (ch.clock() - t0) / 0.2
    assert len(PLANNED) == 33 and round_trips <= 2 * -(-len(PLANNED) // PARAM_WINDOW) + 1


def test_a_shared_link_divides_the_window_among_its_vehicles():
    from ftlbo_mav.link.params import PARAM_ON_LINK, _exchange

    class Shared(LoopbackChannel):
        sharing = 4  # four vehicles heard on the link

    ch = Shared(Vehicle(sysid=2, home=(*HOME, 0.0)), faults=Faults(latency_s=0.1))
    sent = []
    send = ch.send
    ch.send = lambda msg: (sent.append((ch.clock(), msg)), send(msg))[1]
    got = _exchange(ch, {n: (lambda n=n: R.MAVLink_param_request_read_message(
        2, 1, n.encode(), -1)) for n in PLANNED}, TIMING)
    assert all(v is not None for v in got.values())
    at_start = [t for t, _m in sent if t == sent[0][0]]
    assert len(at_start) == PARAM_ON_LINK // 4  # then one more as each answer comes


class _StaleFirst:
    """A vehicle whose answer to PARAM_SET is overtaken by a PARAM_VALUE sent before it
    (the old value, still on its way): only a read-back tells what it holds."""

    sysid = 1

    def __init__(self) -> None:
        self.held, self.sent, self.queue = {"FENCE_ALT_MAX": 100.0}, [], []

    def send(self, msg) -> None:
        self.sent.append(msg.get_type())
        name = msg.param_id if isinstance(msg.param_id, str) else msg.param_id.decode()
        name = name.rstrip("\x00")
        if msg.get_type() == "PARAM_SET":
            self.queue.append((name, self.held[name]))  # the stale one arrives first
            self.held[name] = msg.param_value
        else:
            self.queue.append((name, self.held[name]))

    def recv(self, _timeout):
        from pymavlink.dialects.v20 import ardupilotmega as R

        if not self.queue:
            return None
        name, value = self.queue.pop(0)
        return R.MAVLink_param_value_message(name.encode(), value, 9, 1, 0)


def test_an_answer_that_differs_from_the_set_is_read_back_before_it_counts():
    from ftlbo_mav.link.params import set_params

    ch = _StaleFirst()
    set_params(ch, {"FENCE_ALT_MAX": 8.0}, timing=TIMING)
    assert ch.sent == ["PARAM_SET", "PARAM_REQUEST_READ"] and ch.held["FENCE_ALT_MAX"] == 8.0


def test_a_lost_answer_is_asked_again_after_a_few_round_trips_not_the_whole_time_out():
    """Over a lossy link of 0.1 s each way, a read learns the round trip from its answers
    and asks again after 2.5 of them: 33 parameters with a fifth of the frames lost take a
    few seconds, not the time-out (3 s here) for every loss (virtual time)."""
    from ftlbo_mav.link.params import read_params

    slow = Timing(timeout_s=3.0, retries=3)
    ch = channel(faults=Faults(latency_s=0.1, loss_up=0.1, loss_down=0.1),
                 rng=np.random.default_rng(4))
    t0 = ch.clock()
    got = read_params(ch, PLANNED, timing=slow)
    took = ch.clock() - t0
    assert all(v is not None for v in got.values())
    assert took < 3.0, took
    # without learning it (a vehicle that stores a resend twice: adaptive off) a loss costs
    # the time-out
    ch = channel(faults=Faults(latency_s=0.1, loss_up=0.1, loss_down=0.1),
                 rng=np.random.default_rng(4))
    t0 = ch.clock()
    read_params(ch, PLANNED, timing=Timing(timeout_s=3.0, retries=3, adaptive=False))
    assert ch.clock() - t0 >= 3.0


def _lose_first_request_for(ch, lost: str) -> list[float]:
    """Make ``ch`` lose the first request for parameter ``lost``; the times every request
    for it was sent, filled as they are."""
    sent: list[float] = []
    send = ch.send

    def lossy(msg) -> None:
        name = msg.param_id if isinstance(msg.param_id, str) else msg.param_id.decode()
        if name.rstrip("\x00") == lost:
            sent.append(ch.clock())
            if len(sent) == 1:
                return  # lost
        send(msg)

    ch.send = lossy
    return sent


def test_a_request_an_answer_overtook_is_asked_again_at_once():
    """ArduPilot answers reads in the order they come and the link keeps the order: the
    answer to the second request, come before the first's, says the first was lost. It
    is asked again then (0.2 s, one round trip), not after the resend timer (virtual
    time)."""
    from ftlbo_mav.link.params import read_params

    ch = channel(faults=Faults(latency_s=0.1))
    sent = _lose_first_request_for(ch, next(iter(PLANNED)))
    t0 = ch.clock()
    got = read_params(ch, PLANNED, timing=TIMING)
    assert all(v is not None for v in got.values())
    assert len(sent) == 2 and sent[1] - t0 == pytest.approx(0.2, abs=0.02)


def test_the_last_request_lost_is_asked_again_after_a_round_trip_and_a_half():
    """No answer can overtake the last request of a read: when it is lost, it is asked
    again :data:`~ftlbo_mav.link.transfer.TAIL_RTTS` round trips after the last answer
    that came (0.3 s on a link of 0.1 s each way), not the 2.5 of a request with others
    behind it (0.5 s; virtual time)."""
    from ftlbo_mav.link.params import read_params
    from ftlbo_mav.link.transfer import RESEND_RTTS, TAIL_RTTS

    ch = channel(faults=Faults(latency_s=0.1))
    sent = _lose_first_request_for(ch, list(PLANNED)[-1])
    got = read_params(ch, PLANNED, timing=TIMING)
    assert all(v is not None for v in got.values())
    assert len(sent) == 2
    waited = sent[1] - sent[0]  # from the last answer that came: TAIL_RTTS round trips
    assert TAIL_RTTS * 0.2 - 0.01 <= waited < RESEND_RTTS * 0.2 - 0.1
