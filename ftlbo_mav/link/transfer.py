"""What every mission transfer shares: time-outs, errors, result sentences, the driver.

A transfer (:mod:`~ftlbo_mav.link.mission_protocol`: upload, read-back, clear) is a state
machine that takes messages and the time and returns messages to send; :func:`run_transfer`
drives one over a channel until it finishes.
"""

from __future__ import annotations

import statistics
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from .. import clock as ground_clock
from ..errors import FtlboError
from .codec import MISSION_TYPE_MISSION

R = mavlink2  # MAV_MISSION_RESULT constants live on the dialect module

RESULT_TEXT = {
    R.MAV_MISSION_ACCEPTED: "accepted",
    R.MAV_MISSION_ERROR: "the vehicle reported an error (ArduPilot: an item it could not "
                         "store, or a request while no transfer was running)",
    R.MAV_MISSION_UNSUPPORTED_FRAME: "an item's coordinate frame is not supported by the vehicle",
    R.MAV_MISSION_UNSUPPORTED: "an item's command is not supported by the vehicle",
    R.MAV_MISSION_NO_SPACE: "the vehicle has no space for this many items",
    R.MAV_MISSION_INVALID: "an item has an invalid parameter",
    R.MAV_MISSION_INVALID_PARAM1: "an item's param1 is out of range",
    R.MAV_MISSION_INVALID_PARAM2: "an item's param2 is out of range",
    R.MAV_MISSION_INVALID_PARAM3: "an item's param3 is out of range",
    R.MAV_MISSION_INVALID_PARAM4: "an item's param4 is out of range",
    R.MAV_MISSION_INVALID_PARAM5_X: "an item's latitude (x) is out of range",
    R.MAV_MISSION_INVALID_PARAM6_Y: "an item's longitude (y) is out of range",
    R.MAV_MISSION_INVALID_PARAM7: "an item's altitude (z) is out of range",
    R.MAV_MISSION_INVALID_SEQUENCE: "an item arrived out of sequence",
    R.MAV_MISSION_DENIED: "the vehicle denied the transfer (it is busy with another "
                          "ground station's transfer, or its mission is read-only)",
    R.MAV_MISSION_OPERATION_CANCELLED: "the vehicle cancelled the transfer (it waited too "
                                       "long for an item)",
}


def describe_result(code: int) -> str:
    """A MAV_MISSION_RESULT as a sentence a person understands."""
    name = R.enums["MAV_MISSION_RESULT"].get(code)
    label = name.name if name is not None else f"result {code}"
    return f"{RESULT_TEXT.get(code, 'unknown result code')} ({label})"


RESEND_RTTS = 2.5
"""A message unanswered after this many round trips (the median of the recent ones) is
taken for lost and sent again. Through a telemetry radio of 60 +- 40 ms each way the
round trips spread 0.10-0.25 s about a 0.17 s median: 2.5 of them wait out the slowest
answer, where 4 (0.68 s) made every lost frame of an upload cost a round trip or two
more (sim/radio.py; docs/link.md). A resend that was not needed costs a duplicate, which
ArduPilot answers and forgets (MissionItemProtocol: INVALID_SEQUENCE)."""


TAIL_RTTS = 1.5
"""Once every request of an exchange has been sent, the ones still unanswered are asked
again after this many round trips instead of :data:`RESEND_RTTS`: no later answer can
overtake them and show them lost (the fast resend's cue), so a lost last request or
answer waited out the whole timer. Through the good-day radio on SITL one copter in three
read its 33 flight parameters 1 s later than the others (2.5-2.7 s against 1.3-1.5 s),
one upload in two was a second late for it. A request asked twice is answered twice, and
the answer not waited for is ignored (parameters, read-back items)."""


@dataclass(frozen=True)
class Timing:
    """Time-outs and retry budgets of a transfer.

    ``timeout_s`` / ``retries``: a step (MISSION_COUNT answered, the next request, an
    item) that makes no progress is resent after ``timeout_s``, and fails after
    ``retries`` resends, i.e. after ``timeout_s * (retries + 1)`` without progress
    (QGroundControl's defaults are about 1.5 s and 5). Once a round trip has been timed,
    resends come sooner (every :data:`RESEND_RTTS` round trips, at least
    ``min_resend_s``), within the same
    time budget: on a fast lossy link a lost message costs a fraction of a second, not
    1.5 s, and the budget rides out long runs of losses. ``not_ready_s``: how long a
    vehicle may answer NO_SPACE (booting) or DENIED (busy) before that is final,
    retrying every ``not_ready_poll_s``. ``first_resend_s``: resend interval before any
    round trip has been timed (TCP starts at 1 s, RFC 6298; a lost MISSION_COUNT at 30%
    loss should not eat the budget in 1.5 s steps). ``adaptive=False``: always wait
    ``timeout_s`` before a resend (for vehicles that would store a resent item twice).
    ``send_ahead``: items an upload sends past the one the vehicle asks for (ArduPilot
    only: :data:`~.mission_protocol.SEND_AHEAD`; 0 is MAVLink's item-per-request).
    """

    timeout_s: float = 1.5
    retries: int = 5
    not_ready_s: float = 15.0
    not_ready_poll_s: float = 1.0
    min_resend_s: float = 0.2
    first_resend_s: float = 0.5
    adaptive: bool = True
    send_ahead: int = 3

    def resend_after(self, srtt: float, *, tail: bool = False) -> float:
        """Seconds before a resend once the round trip ``srtt`` (a median) is known;
        ``tail``: every request has been sent (:data:`TAIL_RTTS`)."""
        return min(self.timeout_s, max(self.min_resend_s,
                                       (TAIL_RTTS if tail else RESEND_RTTS) * srtt))

    @property
    def budget_s(self) -> float:
        """How long a step may go without progress before it fails."""
        return self.timeout_s * (self.retries + 1)


class MissionTransferError(FtlboError):
    """A transfer failed; names the vehicle and the step."""

    def __init__(self, sysid: int, step: str, problem: str, *, result: int | None = None):
        self.sysid = sysid
        self.step = step
        self.problem = problem
        self.result = result
        super().__init__(f"vehicle {sysid}: {step}: {problem}")


Progress = Callable[[str, int, int], None]  # (step, done, total)


def _quiet(_step: str, _done: int, _total: int) -> None:
    pass


class _Transfer:
    """Common state: deadline, retry count, outcome."""

    step = "transfer"

    def __init__(self, *, sysid: int, compid: int, own: tuple[int, int], timing: Timing,
                 progress: Progress | None, srtt: float | None = None,
                 mission_type: int = MISSION_TYPE_MISSION, sharing: int = 1):
        self.sysid, self.compid = sysid, compid
        self.sharing = sharing  # vehicles on the link (Channel.sharing)
        self.mission_type = mission_type  # MAV_MISSION_TYPE: mission, fence or rally
        self.own_sysid, self.own_compid = own
        self.timing = timing
        self.progress = progress or _quiet
        self.deadline = 0.0
        self.last_progress = 0.0
        self.finished = False
        self.error: MissionTransferError | None = None
        self.last_result: int | None = None  # last refusal, for the message
        # round-trip time, seconds (None: not timed yet): the median of recent samples,
        # since a sample that spans the vehicle's own re-request (1 s later) looks valid
        self.srtt = srtt
        self._samples: deque[float] = deque([srtt] if srtt is not None else [], maxlen=9)

    def _fail(self, problem: str, *, result: int | None = None) -> list:
        self.finished = True
        self.error = MissionTransferError(self.sysid, self.step, problem, result=result)
        return []

    def _done(self) -> list:
        self.finished = True
        return []

    def _rtt_sample(self, rtt: float) -> None:
        self._samples.append(rtt)
        self.srtt = statistics.median(self._samples)

    def _resend_s(self, *, tail: bool = False) -> float:
        """When to resend a seemingly lost message: :data:`RESEND_RTTS` round trips
        (:data:`TAIL_RTTS` with ``tail``: nothing is left to ask), within bounds."""
        if not self.timing.adaptive:
            return self.timing.timeout_s
        if self.srtt is None:
            return min(self.timing.timeout_s, self.timing.first_resend_s)
        return self.timing.resend_after(self.srtt, tail=tail)

    def _out_of_budget(self, now: float) -> bool:
        return now - self.last_progress >= self.timing.budget_s - 1e-9

    def _gave_up(self, what: str) -> list:
        t = self.timing
        if self.last_result is not None:
            return self._fail(f"{what} kept failing for {t.budget_s:g} s, last answer: "
                              f"{describe_result(self.last_result)}", result=self.last_result)
        return self._fail(f"no answer to {what} within {t.budget_s:g} s ({t.retries} retries "
                          f"of {t.timeout_s:g} s): is the vehicle still there (link, signing "
                          "key)?")

    def _ours(self, msg) -> bool:
        """A message about this transfer's mission type (STATUSTEXT has none: ours)."""
        return getattr(msg, "mission_type", self.mission_type) == self.mission_type

    def start(self, now: float) -> list:
        raise NotImplementedError

    def on_message(self, msg, now: float) -> list:
        raise NotImplementedError

    def on_timeout(self, now: float) -> list:
        raise NotImplementedError


def run_transfer(machine: _Transfer, channel):
    """Drive ``machine`` over ``channel`` until it finishes; raise its error if it failed.

    Time is the channel's ``clock()`` when it has one (virtual time in tests), else
    the ground clock (:func:`ftlbo_mav.clock.monotonic`).
    """
    clock = getattr(channel, "clock", ground_clock.monotonic)
    for msg in machine.start(clock()):
        channel.send(msg)
    while not machine.finished:
        msg = channel.recv(max(0.0, machine.deadline - clock()))
        now = clock()
        out = machine.on_message(msg, now) if msg is not None else []
        if not machine.finished and now >= machine.deadline:
            out = out + machine.on_timeout(now)
        for m in out:
            channel.send(m)
    if getattr(channel, "srtt", None) is None or machine.srtt is not None:
        channel.srtt = machine.srtt  # the next transfer starts from the measured round trip
    if machine.error is not None:
        raise machine.error
    return machine
