"""The MAVLink mission protocol, ground-station side: upload, download, clear.

Kept whole: one protocol (MAVLink's mission microservice), its three transfers sharing one
state machine base, timing and retries.

Each transfer is a small state machine that takes messages and the time and returns the
messages to send (no sockets here); :func:`run_transfer` drives one over a *channel*,
anything with ``send(msg)``, ``recv(timeout_s) -> msg | None``, ``sysid``, ``own_sysid``,
``own_compid`` and optionally ``clock()`` and ``srtt`` (:class:`~ftlbo_mav.link.endpoints.
Channel` on a real link, :class:`~ftlbo_mav.sim.loopback.LoopbackChannel` in virtual time).

What the vehicle side does, as ArduPilot does it (libraries/GCS_MAVLink/
MissionItemProtocol.cpp, GCS_Common.cpp), and what follows here:

- It asks for items with MISSION_REQUEST even after MISSION_ITEM_INT answers, re-asks
  about every second when an item does not come and cancels a stalled upload after 8 s.
  We answer MISSION_REQUEST and MISSION_REQUEST_INT alike, always with MISSION_ITEM_INT,
  and answer every request, duplicates and stale ones included.
- It accepts an item only if its seq is the one it waits for, else ACKs INVALID_SEQUENCE
  and keeps waiting: that ACK never ends an upload here. When a request seems lost we
  resend the last requested item early (after a few round-trip times, before the
  vehicle's 1 s re-request); an INVALID_SEQUENCE answer to that resend means the vehicle
  already has it and waits for the next one, which we then send.
- In its first seconds after boot it answers MISSION_COUNT with NO_SPACE: that is "not
  ready yet" within :attr:`Timing.not_ready_s`, then a clear error.
- After the last item it ACKs ACCEPTED; a resent last item after a lost ACCEPTED gets
  ACK ERROR (GCS_Common.cpp handle_mission_item: not receiving). The upload then ends
  *unconfirmed* and the read-back decides.
- It stores an item that comes before it asked for it, as long as its seq is the one it
  waits for (MissionItemProtocol::handle_mission_item checks the seq, not a request),
  and asks for the next at once. So an upload to ArduPilot sends a few
  items past the one asked for (:data:`SEND_AHEAD_ON_LINK`): a window of items each
  round trip, not one.
"""

from __future__ import annotations

import itertools
import math
import re
from collections.abc import Sequence

from ..mission.items import MissionItem
from .codec import MISSION_TYPE_MISSION, decode_item, encode_item
from .transfer import (  # re-exported: the protocol's public names live here
    RESULT_TEXT,
    MissionTransferError,
    Progress,
    R,
    Timing,
    _Transfer,
    describe_result,
    run_transfer,
)

__all__ = [
    "RESULT_TEXT", "Clear", "Download", "MissionTransferError", "Progress", "Timing", "Upload",
    "clear_mission", "describe_result", "download_mission", "read_items", "run_transfer",
    "upload_mission", "write_items",
]

CAPACITY_TEXT = re.compile(r"Only (\d+) items are supported")

SEND_AHEAD_ON_LINK = 3
"""Items sent ahead of the requests on one link, divided among the vehicles that share
it (at most :attr:`Timing.send_ahead <.transfer.Timing.send_ahead>` a transfer). A
shared radio's air is theirs together, and each copter takes a mission, a fence and a
rally point at once: what is in flight beyond what the air carries in a round trip only
waits in the radios' buffers, and its round trips, grown, make the resends come late
(``upload`` of the example's three copters through the good-day radio on the emulator,
20 seeds, mean / worst: one item ahead each 4.8 / 5.6 s, two 4.6 / 5.8 s, three
4.7 / 6.0 s, none 5.4 / 6.5 s)."""


DUPLICATE_RTTS = 1.5
"""An INVALID_SEQUENCE this many round trips or more after any item last went out twice is
taken for a lost item (:meth:`Upload._out_of_sequence`)."""


class Upload(_Transfer):
    """MISSION_COUNT, then an item for every request, until ACK ACCEPTED.

    ``acknowledged`` is False when the upload ended without the vehicle's ACCEPTED
    (see the module notes): only the read-back can then tell. ``highest`` is the highest
    item the vehicle asked for (-1: it never asked for one), counted from the first sent.

    ``first``: replace the stored items from this seq on, in place, instead of the whole
    mission (MISSION_WRITE_PARTIAL_LIST; MissionItemProtocol::handle_mission_write_partial_list
    asks for them as for an upload); ``items`` are then those items, with their seqs.
    """

    step = "upload"

    def __init__(self, items: Sequence[MissionItem], *, first: int | None = None, **kw):
        super().__init__(**kw)
        if not items:
            raise ValueError("an upload needs at least one item")
        self.first = first
        self.items = list(items)
        self.n = len(self.items)
        self.highest = -1
        self.sent_at: dict[int, float] = {}  # first time each item went out
        self.sends: dict[int, int] = {}      # how often each item went out
        self.count_sends = 0
        self.last_sent = False     # the last item went out at least once
        self.resent = False        # the current step's item was resent
        self.probing = False       # waiting to see how the vehicle answers a resend
        self.waiting_ready = False
        self.acknowledged = False
        self.started_at = 0.0
        self.count_sent_at = 0.0
        self.capacity: int | None = None  # what the vehicle said it holds, if it did
        # items sent past the one asked for (module notes), and the order each last went in
        self.ahead = (max(0, min(self.timing.send_ahead, SEND_AHEAD_ON_LINK // self.sharing))
                      if self.timing.adaptive else 0)
        self.order: dict[int, int] = {}
        self._sending = itertools.count()
        self.dup_at = -math.inf  # when an item last went out again

    def _count(self, now: float) -> list:
        self.count_sent_at = now
        self.count_sends += 1
        self.deadline = now + self._resend_s()
        if self.first is not None:
            return [R.MAVLink_mission_write_partial_list_message(
                self.sysid, self.compid, self.first, self.first + self.n - 1,
                self.mission_type)]
        return [R.MAVLink_mission_count_message(self.sysid, self.compid, self.n,
                                                self.mission_type)]

    def _item(self, seq: int, now: float) -> list:
        self.sent_at.setdefault(seq, now)
        self.order[seq] = next(self._sending)
        self.sends[seq] = self.sends.get(seq, 0) + 1
        if self.sends[seq] > 1:
            self.dup_at = now
        if seq == self.n - 1:
            self.last_sent = True
        return [encode_item(self.items[seq], target_system=self.sysid,
                            target_component=self.compid, mission_type=self.mission_type)]

    def start(self, now: float) -> list:
        self.started_at = self.last_progress = now
        self.progress("upload", 0, self.n)
        return self._count(now)

    def on_message(self, msg, now: float) -> list:
        kind = msg.get_type()
        if not self._ours(msg):
            return []
        if kind in ("MISSION_REQUEST", "MISSION_REQUEST_INT"):
            return self._on_request(msg.seq - (self.first or 0), now)
        if kind == "MISSION_ACK":
            return self._on_ack(msg.type, now)
        if kind == "STATUSTEXT":
            return self._on_text(msg.text, now)
        return []

    def _on_text(self, text: str, now: float) -> list:
        """ArduPilot says why it answered NO_SPACE: "Only N items are supported"
        (MissionItemProtocol::handle_mission_count). N = 0 while it boots; otherwise the
        mission is too long for it, which no retry changes."""
        m = CAPACITY_TEXT.search(text or "")
        if m is None:
            return []
        self.capacity = int(m.group(1))
        if self.waiting_ready and 0 < self.capacity < self.n:
            return self._fail(
                f"the vehicle holds at most {self.capacity} mission items and this mission "
                f"has {self.n} (MAV_MISSION_NO_SPACE, \"{text.strip()}\"); nothing was "
                "sent and its mission is unchanged", result=R.MAV_MISSION_NO_SPACE)
        return []

    def _on_request(self, seq: int, now: float) -> list:
        if not 0 <= seq < self.n:
            return []
        self.waiting_ready = False
        if seq > self.highest:  # progress
            # Karn's rule: time only the answer to something sent exactly once
            if seq == 0 and self.count_sends == 1:
                self._rtt_sample(now - self.count_sent_at)
            elif self.sends.get(seq - 1) == 1:
                self._rtt_sample(now - self.sent_at[seq - 1])
            self.highest = seq
            self.last_progress = now
            self.resent = self.probing = False
            self.progress("upload", seq, self.n)
            if self.ahead:
                return self._ahead(seq, now)
        if seq == self.highest:
            self.deadline = now + self._resend_s()
        return self._item(seq, now)  # every request is answered, stale ones too

    def _ahead(self, seq: int, now: float) -> list:
        """A new request, sending ahead: the next :attr:`ahead` items not sent yet, when the
        one asked for is on its way. It is when it went after the last sending of the one
        before it (a link keeps each direction's order); one that went before arrived out
        of sequence (ArduPilot answered INVALID_SEQUENCE and forgot it), and so did those
        sent ahead after it: it goes again with the window behind it, in order."""
        self.deadline = now + self._resend_s()
        went = self.order.get(seq)
        window = range(seq, min(self.n, seq + 1 + self.ahead))
        if went is None or (seq > 0 and went < self.order.get(seq - 1, went)):
            return [m for q in window for m in self._item(q, now)]
        return [m for q in window[1:] if q not in self.sends for m in self._item(q, now)]

    def _on_ack(self, result: int, now: float) -> list:
        if result == R.MAV_MISSION_ACCEPTED:
            if not self.last_sent:
                return []  # a stale ACK from an earlier transfer
            self.acknowledged = True
            self.progress("upload", self.n, self.n)
            return self._done()
        if result == R.MAV_MISSION_INVALID_SEQUENCE:
            # A duplicated or stale item reached the vehicle; it goes on waiting
            # (MissionItemProtocol::handle_mission_item). In answer to our resend it means
            # the vehicle has that item already and its request for the next was lost.
            if self.probing and self.highest + 1 < self.n:
                self.probing = False
                return self._item(self.highest + 1, now)
            return self._out_of_sequence(now)
        if result == R.MAV_MISSION_ERROR and not self.sends:
            return []  # about an item of an earlier transfer (none of ours went yet)
        if result == R.MAV_MISSION_ERROR and self.last_sent:
            # A (resent or duplicated) last item reached a vehicle that had finished
            # (GCS_Common.cpp handle_mission_item: not receiving -> ERROR): ACCEPTED was
            # lost. Or the last item could not be stored: the read-back tells which.
            self.progress("upload", self.n, self.n)
            return self._done()
        if result == R.MAV_MISSION_NO_SPACE and self.highest < 0:
            if now - self.started_at < self.timing.not_ready_s:
                # ArduPilot answers NO_SPACE in its first seconds after boot: not ready yet.
                self.waiting_ready = True
                self.deadline = now + self.timing.not_ready_poll_s
                return []
            return self._fail(
                f"{describe_result(result)} for {self.n} items, for "
                f"{self.timing.not_ready_s:g} s: the mission is too long for it, or it has "
                "not finished booting", result=result)
        where = f" at item {self.highest}" if self.highest >= 0 else ""
        return self._fail(f"{describe_result(result)}{where}", result=result)

    def _out_of_sequence(self, now: float) -> list:
        """INVALID_SEQUENCE with no item sent twice for :data:`DUPLICATE_RTTS` round trips:
        an item sent ahead reached the vehicle before the one it waits for, which was
        lost (ArduPilot acknowledges each item out of sequence at once and asks for the
        next one only from its update loop, so the ACK can come before the request). The
        last item asked for goes again at once with the window behind it, in order,
        instead of after the resend timer (on SITL through the good-day radio a lost
        item sent ahead cost 0.7 s, 2.5 round trips, of a mission's upload). An
        acknowledgement of a duplicate (a resend, or the answer to a stale request) comes
        within those round trips of it, and is not taken for a loss."""
        if (not self.ahead or self.highest < 0 or self.srtt is None
                or now - self.dup_at < DUPLICATE_RTTS * self.srtt):
            return []
        self.deadline = now + self._resend_s()
        window = range(self.highest, min(self.n, self.highest + 1 + self.ahead))
        return [m for q in window if q in self.sends for m in self._item(q, now)]

    def _lost(self, seq: int, asked: float, now: float) -> list:
        """Ask again at once for the items asked before ``seq`` (no later than ``asked``)
        and not answered: ArduPilot answers requests in the order they come, and a link
        keeps each direction's order (a radio, TCP), so an answer that overtook them
        means they, or their requests, were lost (TCP's fast retransmit; otherwise each
        waited out the resend timer, 2.5 round trips, and through a shared radio losing
        3 % of frames nearly every read-back lost one). A link that reorders costs a
        duplicate request, which the answer ignores."""
        lost = [q for q, t in self.asked.items() if q < seq and t <= asked]
        self.retried.update(lost)
        return [self._request(q, now) for q in lost]

    def on_timeout(self, now: float) -> list:
        if self.waiting_ready:
            self.waiting_ready = False
            self.last_progress = now
            return self._count(now)
        if self._out_of_budget(now):
            if self.highest < 0:
                return self._gave_up("MISSION_COUNT")
            return self._gave_up(f"item {self.highest} (no request for the next one)")
        if self.highest < 0:
            return self._count(now)
        self.resent = self.probing = True
        self.deadline = now + self._resend_s()
        return self._item(self.highest, now)


READ_WINDOW = 8
READ_ON_LINK = 24
"""MISSION_REQUEST_INTs outstanding at once in a read-back: up to READ_WINDOW, and
READ_ON_LINK divided among the vehicles that share the link (a shared radio's buffer is
theirs together: 10 copters asking 8 each overflowed a 2 KiB buffer; 24 answers of ~50
bytes fit it, so three copters still ask 8 each, ten 2). ArduPilot answers each on its own
(MissionItemProtocol::handle_mission_request_int keeps no state while sending), so a
read-back asks for a window of items at once: one round trip for the window, not one an
item (through a shared radio, 60 ms each way, 8 items took 1.7 s)."""


class Download(_Transfer):
    """MISSION_REQUEST_LIST, then MISSION_REQUEST_INT for the items, :data:`READ_WINDOW`
    at once, then ACK ACCEPTED. ``only``: just these seqs, without the count or the ACK
    (:attr:`items` then has them in that order)."""

    step = "read-back"

    def __init__(self, *, only: Sequence[int] | None = None, expect: int | None = None,
                 **kw):
        super().__init__(**kw)
        self.only = None if only is None else list(only)
        # the count a read-back expects (what was just uploaded): its first items are
        # asked for with the count, not a round trip after it
        self.expect = expect if only is None and expect else None
        # a window of its own: READ_WINDOW shared among the vehicles on the link
        self.window = max(1, min(READ_WINDOW, READ_ON_LINK // self.sharing))
        self.count: int | None = None
        self.got: dict[int, MissionItem] = {}
        self.asked: dict[int, float] = {}  # seq -> when last asked, for those not answered
        self.retried: set[int] = set()  # asked again (Karn's rule: no round trip from them)
        self.asked_at = 0.0
        self.resent = False
        self.started_at = 0.0
        self.waiting_ready = False
        if self.only is not None:
            self.count = max(self.only) + 1
            self.got = {seq: None for seq in range(self.count) if seq not in self.only}

    @property
    def items(self) -> list[MissionItem]:
        """The items received so far, in order, up to the first one missing."""
        if self.only is not None:
            return [self.got[seq] for seq in self.only if seq in self.got]
        out = []
        while len(out) in self.got:
            out.append(self.got[len(out)])
        return out

    def _request(self, seq: int, now: float):
        self.asked[seq] = now
        return R.MAVLink_mission_request_int_message(self.sysid, self.compid, seq,
                                                     self.mission_type)

    def _ask(self, now: float) -> list:
        """Ask for what is missing: the count, else the window's unasked items."""
        self.asked_at = now
        self.deadline = now + self._resend_s()
        out = []
        if self.count is None:
            out.append(R.MAVLink_mission_request_list_message(self.sysid, self.compid,
                                                              self.mission_type))
            if self.expect is None or self.asked or self.got:
                return out
        for seq in range(self.count if self.count is not None else self.expect):
            if len(self.asked) >= self.window:
                break
            if seq not in self.got and seq not in self.asked:
                out.append(self._request(seq, now))
        if self.count is not None and len(self.got) + len(self.asked) >= self.count:
            self.deadline = now + self._resend_s(tail=True)  # all asked: no cue will come
        return out

    def _finish(self) -> list:
        self.finished = True
        if self.only is not None:
            return []
        return [R.MAVLink_mission_ack_message(self.sysid, self.compid, R.MAV_MISSION_ACCEPTED,
                                              self.mission_type)]

    def _progressed(self, now: float, *, rtt: float | None) -> list:
        if rtt is not None:
            self._rtt_sample(rtt)
        self.last_progress = now
        if self.count is None:  # items expected, the count not come yet
            return []
        self.progress("read-back", len(self.got), self.count)
        if len(self.got) >= self.count:
            return self._finish()
        return self._ask(now)

    def start(self, now: float) -> list:
        self.started_at = self.last_progress = now
        return self._ask(now)

    def on_message(self, msg, now: float) -> list:
        kind = msg.get_type()
        if not self._ours(msg):
            return []
        if kind == "MISSION_COUNT":
            if self.count is None or (msg.count != self.count and not self.got):
                self.count = msg.count
                for seq in [q for q in self.got if q >= msg.count]:  # asked for too many
                    del self.got[seq]
                for seq in [q for q in self.asked if q >= msg.count]:
                    del self.asked[seq]
                self.waiting_ready = False
                rtt = None if self.resent else now - self.asked_at  # Karn's rule
                self.resent = False
                return self._progressed(now, rtt=rtt)
            return []
        if kind in ("MISSION_ITEM_INT", "MISSION_ITEM"):
            seq = msg.seq
            known = self.count if self.count is not None else self.expect
            if known is not None and 0 <= seq < known and seq not in self.got:
                self.got[seq] = decode_item(msg)
                asked = self.asked.pop(seq, None)
                rtt = (now - asked if asked is not None and seq not in self.retried
                       else None)
                out = self._progressed(now, rtt=rtt)
                return out if self.finished or asked is None else out + self._lost(seq, asked,
                                                                                   now)
            return []  # a duplicate or stale answer
        if kind == "MISSION_ACK" and msg.type != R.MAV_MISSION_ACCEPTED:
            # A read is harmless to repeat, and an ACK here is often stale (ERROR or
            # INVALID_SEQUENCE for a late duplicate of an uploaded item), so none ends the
            # read-back: it is kept for the message if the budget runs out. DENIED means
            # busy receiving an upload (handle_mission_request_list): ask again later.
            self.last_result = msg.type
            if msg.type == R.MAV_MISSION_DENIED and now - self.started_at < self.timing.not_ready_s:
                self.waiting_ready = True
                self.deadline = now + self.timing.not_ready_poll_s
        return []

    def _lost(self, seq: int, asked: float, now: float) -> list:
        """Ask again at once for the items asked before ``seq`` (no later than ``asked``)
        and not answered: ArduPilot answers requests in the order they come, and a link
        keeps each direction's order (a radio, TCP), so an answer that overtook them
        means they, or their requests, were lost (TCP's fast retransmit; otherwise each
        waited out the resend timer, 2.5 round trips, and through a shared radio losing
        3 % of frames nearly every read-back lost one). A link that reorders costs a
        duplicate request, which the answer ignores."""
        lost = [q for q, t in self.asked.items() if q < seq and t <= asked]
        self.retried.update(lost)
        return [self._request(q, now) for q in lost]

    def on_timeout(self, now: float) -> list:
        if self.waiting_ready:
            self.waiting_ready = False
            self.last_progress = now
            self.asked.clear()
            return self._ask(now)
        if self._out_of_budget(now):
            missing = next((q for q in range(self.count or 0) if q not in self.got), 0)
            return self._gave_up("MISSION_REQUEST_LIST" if self.count is None
                                 else f"MISSION_REQUEST_INT {missing}")
        self.resent = True
        again = list(self.asked)  # every unanswered request of the window, again
        self.retried.update(again)
        out = self._ask(now)
        return out + [self._request(seq, now) for seq in again]


class Clear(_Transfer):
    """MISSION_CLEAR_ALL until ACK ACCEPTED."""

    step = "clear"

    def _send(self, now: float) -> list:
        self.deadline = now + self.timing.timeout_s
        return [R.MAVLink_mission_clear_all_message(self.sysid, self.compid, self.mission_type)]

    def start(self, now: float) -> list:
        self.last_progress = now
        return self._send(now)

    def on_message(self, msg, now: float) -> list:
        if msg.get_type() != "MISSION_ACK" or not self._ours(msg):
            return []
        if msg.type == R.MAV_MISSION_ACCEPTED:
            return self._done()
        # ERROR: the vehicle is still receiving (an upload it will cancel) or the ACK is
        # stale; INVALID_SEQUENCE: stale. Clearing is harmless to repeat: keep asking.
        self.last_result = msg.type
        return []

    def on_timeout(self, now: float) -> list:
        if self._out_of_budget(now):
            return self._gave_up("MISSION_CLEAR_ALL")
        return self._send(now)


def _kw(channel, timing: Timing | None, progress: Progress | None, compid: int,
        mission_type: int = MISSION_TYPE_MISSION) -> dict:
    return {"sysid": channel.sysid, "compid": compid,
            "sharing": getattr(channel, "sharing", 1),
            "own": (channel.own_sysid, channel.own_compid), "timing": timing or Timing(),
            "progress": progress, "srtt": getattr(channel, "srtt", None),
            "mission_type": mission_type}


def upload_mission(channel, items: Sequence[MissionItem], *, timing: Timing | None = None,
                   progress: Progress | None = None, compid: int = 1,
                   mission_type: int = MISSION_TYPE_MISSION) -> bool:
    """Upload ``items`` to the vehicle on ``channel``; True when the vehicle ACKed ACCEPTED.

    ``mission_type``: MAV_MISSION_TYPE_MISSION (0), _FENCE (1) or _RALLY (2). False means
    the upload ended without that ACK (it was lost): verify by read-back.
    Raises :class:`MissionTransferError` when the vehicle refused or stopped answering.
    """
    machine = run_transfer(Upload(items, **_kw(channel, timing, progress, compid, mission_type)),
                           channel)
    return machine.acknowledged


def write_items(channel, items: Sequence[MissionItem], *, timing: Timing | None = None,
                compid: int = 1) -> bool:
    """Replace stored mission items in place (``items``: consecutive, with their seqs;
    MISSION_WRITE_PARTIAL_LIST), as :func:`upload_mission`: True when ACKed ACCEPTED.
    Confirm with :func:`read_items`."""
    first = items[0].seq
    if [it.seq for it in items] != list(range(first, first + len(items))):
        raise ValueError("write_items needs consecutive items")
    machine = run_transfer(Upload(items, first=first, **_kw(channel, timing, None, compid)),
                           channel)
    return machine.acknowledged


def read_items(channel, seqs: Sequence[int], *, timing: Timing | None = None,
               compid: int = 1) -> list[MissionItem]:
    """The stored mission items ``seqs``, read back (MISSION_REQUEST_INT each)."""
    machine = Download(only=seqs, **_kw(channel, timing, None, compid))
    return run_transfer(machine, channel).items


def download_mission(channel, *, timing: Timing | None = None, progress: Progress | None = None,
                     compid: int = 1, mission_type: int = MISSION_TYPE_MISSION,
                     expect: int | None = None) -> list[MissionItem]:
    """Read the vehicle's mission (item 0 is what the vehicle says is home), fence or
    rally points back. ``expect``: how many items it should hold (a read-back of what was
    sent): the first of them are asked for with the count."""
    machine = Download(expect=expect, **_kw(channel, timing, progress, compid, mission_type))
    return run_transfer(machine, channel).items


def clear_mission(channel, *, timing: Timing | None = None, compid: int = 1,
                  mission_type: int = MISSION_TYPE_MISSION) -> None:
    """MISSION_CLEAR_ALL, acknowledged. Confirm with :func:`download_mission`."""
    run_transfer(Clear(**_kw(channel, timing, None, compid, mission_type)), channel)
