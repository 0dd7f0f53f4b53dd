"""The vehicle side of the mission protocol, as ArduPilot implements it.

A plain state machine: :meth:`MissionServer.handle` takes one message addressed to the
vehicle, the link it came on and the time, and returns the replies as ``(link, message)``
pairs; :meth:`MissionServer.update` (called a few times a second) returns the re-requests
and cancellations that time brings. ArduPilot keeps one upload per vehicle, tied to the
link its MISSION_COUNT came on: acks about that upload go to *that* link, even when the
message was from another (recorded: mission_protocol.json ``g1``/``g2``). Every rule
copies ArduPilot 4.5 and names the function it copies, in
libraries/GCS_MAVLink/MissionItemProtocol.cpp unless said otherwise; what is kept of each
item is :mod:`ftlbo_mav.ardupilot.storage`'s model of AP_Mission.

One server per mission type, as ArduPilot has one MissionItemProtocol each
(GCS::get_prot_for_mission_type): the mission (MissionItemProtocol_Waypoints), the fence
(MissionItemProtocol_Fence: items collected during the upload and written at its end,
after AC_PolyFence_loader::validate_fence) and the rally points
(MissionItemProtocol_Rally: stored as they come); what each keeps is
:mod:`ftlbo_mav.ardupilot.fence`.
"""

from __future__ import annotations

from collections.abc import Hashable
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from ..ardupilot import fence as ap_fence
from ..ardupilot import storage
from ..ardupilot.commands import FLIGHT_PLAN_RECEIVED, no_space_text
from ..ardupilot.storage import SITL_MISSION_CAPACITY, WireItem

R = mavlink2
MISSION = R.MAV_MISSION_TYPE_MISSION
EVERY_LINK = "every link"  # GCS_SEND_TEXT: a STATUSTEXT for every active link
SENDER = None              # the link the handled message came on

Link = Hashable


@dataclass(frozen=True)
class MissionServerOptions:
    """``capacity``: items that fit (AP_Mission::num_commands_max: 650 in SITL).
    ``rerequest_s``: re-ask for a missing item (1 s, update()); ``upload_timeout_s``:
    cancel a stalled upload (8 s, MissionItemProtocol.h upload_timeout_ms).
    ``boot_no_space_s``: answer MISSION_COUNT with NO_SPACE ("Only 0 items are
    supported") for this long after boot, as ArduCopter SITL does for its first ~2.5 s
    (the vehicle sets it from its boot timeline)."""

    capacity: int = SITL_MISSION_CAPACITY
    rerequest_s: float = 1.0
    upload_timeout_s: float = 8.0
    boot_no_space_s: float = 0.0


StoredItem = WireItem  # an item as AP_Mission keeps it (read-back form)


def wire_item(msg) -> WireItem:
    """A MISSION_ITEM_INT or MISSION_ITEM as the wire carries it; MISSION_ITEM's degrees
    converted as AP_Mission::convert_MISSION_ITEM_to_MISSION_ITEM_INT does (``* 1.0e7f``
    in float32, truncated to int32) and its floats as float32."""
    if msg.get_type() == "MISSION_ITEM":
        x = storage.c_int(storage.f32(storage.f32(msg.x) * 1e7), 32, signed=True)
        y = storage.c_int(storage.f32(storage.f32(msg.y) * 1e7), 32, signed=True)
    else:
        x, y = int(msg.x), int(msg.y)
    f = storage.f32
    return WireItem(seq=msg.seq, command=msg.command, frame=msg.frame, x=x, y=y, z=f(msg.z),
                    param1=f(msg.param1), param2=f(msg.param2), param3=f(msg.param3),
                    param4=f(msg.param4), current=msg.current,
                    autocontinue=msg.autocontinue)


def _text(severity_text: tuple[int, str]):
    severity, text = severity_text
    return R.MAVLink_statustext_message(severity, text.encode())


_TIMEOUT_TEXT = {MISSION: "Mission upload timeout",
                 R.MAV_MISSION_TYPE_FENCE: "Fence upload timeout",  # MissionItemProtocol_*
                 R.MAV_MISSION_TYPE_RALLY: "Rally upload timeout"}  # ::timeout


class MissionServer:
    """ArduPilot's MissionItemProtocol_Waypoints (or _Fence, _Rally with ``mission_type``)
    for one vehicle."""

    def __init__(self, *, sysid: int, home: tuple[float, float, float] | None,
                 options: MissionServerOptions = MissionServerOptions(), boot_time: float = 0.0,
                 mission_type: int = MISSION):
        self.sysid = sysid
        self.mission_type = mission_type
        self._new_fence: list[WireItem] = []  # the fence being uploaded
        self.home = home  # lat_deg, lon_deg, alt_m AMSL; None until the vehicle has one
        self.options = options
        self.boot_time = boot_time
        self.items: list[WireItem] = []  # slot 0 is home's; read back as the live home
        self.receiving = False
        self.request_i = 0
        self.request_last = 0
        self.dest = (0, 0)  # sysid, compid of the uploading ground station
        self.link: Link = None  # the link of the upload (MissionItemProtocol::link)
        self.timelast_receive = 0.0
        self.timelast_request = 0.0
        self._item_warning_sent = False
        self._request_warning_sent = False
        self.version = 0  # counts changes of ``items``
        self._incoming: Link = 0

    # -- replies
    def _ack(self, to: tuple[int, int], result: int, link: Link = SENDER) -> list:
        return [(link, R.MAVLink_mission_ack_message(to[0], to[1], result, self.mission_type))]

    def _request(self) -> list:
        # ArduPilot asks with MISSION_REQUEST, not MISSION_REQUEST_INT (queued_request_send)
        return [(self.link, R.MAVLink_mission_request_message(
            self.dest[0], self.dest[1], self.request_i, self.mission_type))]

    def _free(self) -> None:
        self.receiving = False
        self.link = None

    def max_items(self, now: float) -> int:
        """AP_Mission::num_commands_max: 0 until storage is initialised after boot."""
        if self.mission_type != MISSION:
            return self.options.capacity
        return 0 if now - self.boot_time < self.options.boot_no_space_s else self.options.capacity

    # -- the protocol
    def handle(self, msg, now: float, link: Link = 0) -> list:
        """Replies as ``(link, message)``: ``SENDER`` (None) for the link ``msg`` came on."""
        kind = msg.get_type()
        sender = (msg.get_srcSystem(), msg.get_srcComponent())
        if kind not in _HANDLERS:
            return []
        if getattr(msg, "mission_type", MISSION) != self.mission_type:
            # not this protocol's (GCS_MAVLINK: no protocol for the type -> UNSUPPORTED)
            return self._ack(sender, R.MAV_MISSION_UNSUPPORTED)
        self._incoming = link  # the handlers' (msg, sender, now) signature stays
        return getattr(self, _HANDLERS[kind])(msg, sender, now)

    def _count(self, msg, sender, now) -> list:  # handle_mission_count
        if self.receiving:
            if sender != self.dest:
                return self._ack(sender, R.MAV_MISSION_DENIED)  # someone else is uploading
            self._free()  # the same GCS restarts (on any link)
        if msg.count > self.max_items(now):
            return self._ack(sender, R.MAV_MISSION_NO_SPACE) + [
                (EVERY_LINK, _text(no_space_text(self.max_items(now))))]
        if msg.count < len(self.items) and self.mission_type != ap_fence.MISSION_TYPE_FENCE:
            del self.items[msg.count:]  # truncate(packet); the fence's truncate does nothing
            self.version += 1
        self._new_fence = list(self.items[:msg.count])  # allocate_receive_resources
        if msg.count == 0:  # transfer_is_complete
            return self._complete(sender, SENDER)
        self.receiving = True  # init_send_requests
        self.request_i, self.request_last = 0, msg.count - 1
        self.dest, self.link = sender, self._incoming
        self.timelast_receive = self.timelast_request = now
        self._item_warning_sent = self._request_warning_sent = False
        return self._request()

    def _write_partial(self, msg, sender, now) -> list:  # handle_mission_write_partial_list
        """Items ``start_index``..``end_index`` replaced in place, asked for one by one as
        an upload's; no check for an upload under way (it is taken over)."""
        count = len(self.items)
        if (msg.start_index > count or msg.end_index > count
                or msg.end_index < msg.start_index):
            return [(EVERY_LINK, _text((R.MAV_SEVERITY_WARNING, "Flight plan update rejected")))
                    ] + self._ack(sender, R.MAV_MISSION_ERROR)
        self._new_fence = list(self.items)  # allocate_update_resources
        self.receiving = True  # init_send_requests
        self.request_i, self.request_last = msg.start_index, msg.end_index
        self.dest, self.link = sender, self._incoming
        self.timelast_receive = self.timelast_request = now
        self._item_warning_sent = self._request_warning_sent = False
        return self._request()

    def _item(self, msg, sender, now) -> list:
        if not self.receiving:  # GCS_Common.cpp GCS_MAVLINK::handle_mission_item
            return self._ack(sender, R.MAV_MISSION_ERROR)
        out = []
        if msg.get_type() == "MISSION_ITEM" and not self._item_warning_sent:
            self._item_warning_sent = True  # send_mission_item_warning
            out.append((EVERY_LINK, _text((R.MAV_SEVERITY_WARNING,
                                           "got MISSION_ITEM; GCS should send MISSION_ITEM_INT"))))
        # handle_mission_item: these acks go to the upload's link (send_mission_ack(msg, ..))
        if msg.seq != self.request_i:
            return out + self._ack(sender, R.MAV_MISSION_INVALID_SEQUENCE, self.link)
        if sender != self.dest:
            return out + self._ack(sender, R.MAV_MISSION_DENIED, self.link)
        item = wire_item(msg)
        if self.mission_type == ap_fence.MISSION_TYPE_FENCE:
            result = ap_fence.check_fence_item(item)  # replace_item into the new fence
        elif msg.seq > len(self.items):
            result = R.MAV_MISSION_ERROR  # beyond the end of the command list
        elif self.mission_type == ap_fence.MISSION_TYPE_RALLY:
            result = ap_fence.check_rally_item(item)
        else:
            # MissionItemProtocol_Waypoints::replace_item / append_item: the item is
            # converted (AP_Mission::mavlink_int_to_mission_cmd: storage.check), then
            # DO_JUMP targets are checked
            result = storage.check(item)
            if result == R.MAV_MISSION_ACCEPTED:
                result = storage.check_jump(item, stored_count=len(self.items),
                                            last_seq=self.request_last)
        if result != R.MAV_MISSION_ACCEPTED:
            # the transfer stops here; items already replaced stay (half-overwritten)
            replies = out + self._ack(sender, result, self.link)
            self._free()
            return replies
        kept = ap_fence.stored_item(item, self.mission_type)
        if self.mission_type == ap_fence.MISSION_TYPE_FENCE:
            if msg.seq < len(self._new_fence):
                self._new_fence[msg.seq] = item
            else:
                self._new_fence.append(item)
        else:
            self.version += 1
            if msg.seq < len(self.items):
                self.items[msg.seq] = kept
            else:
                self.items.append(kept)
        self.timelast_receive = now
        self.request_i += 1
        if self.request_i > self.request_last:  # transfer_is_complete, on the upload's link
            return out + self._complete(sender, self.link)
        self.timelast_request = now
        return out + self._request()

    def _complete(self, sender, link: Link) -> list:
        """transfer_is_complete: ``complete()`` (the fence is validated and written now;
        the mission says "Flight plan received"), the ACK, resources freed."""
        self._free()
        texts = []
        result = R.MAV_MISSION_ACCEPTED
        if self.mission_type == MISSION:
            texts = [(link, _text(FLIGHT_PLAN_RECEIVED))]
        elif self.mission_type == ap_fence.MISSION_TYPE_FENCE:
            problem = ap_fence.validate_fence(self._new_fence)
            if problem is None:
                self.items = [ap_fence.stored_fence_item(it) for it in self._new_fence]
                self.version += 1
            else:
                result = R.MAV_MISSION_ERROR
                texts = [(EVERY_LINK, _text((R.MAV_SEVERITY_WARNING, problem)))]
        self._new_fence = []
        return self._ack(sender, result, link) + texts

    def _request_list(self, msg, sender, now) -> list:  # handle_mission_request_list
        if self.receiving:
            return self._ack(sender, R.MAV_MISSION_DENIED)
        return [(SENDER, R.MAVLink_mission_count_message(sender[0], sender[1], len(self.items),
                                                         self.mission_type))]

    def home_item(self) -> WireItem:
        """Item 0 as read back: the live home (AP_Mission::read_cmd_from_storage), or an
        empty NAV_WAYPOINT while the vehicle has none (mission_items.json
        ``before_home_set``)."""
        if self.home is None:
            return WireItem(seq=0, command=R.MAV_CMD_NAV_WAYPOINT, frame=R.MAV_FRAME_GLOBAL,
                            x=0, y=0, z=0.0)
        lat, lon, alt = self.home
        return storage.home_item(lat_e7=round(lat * 1e7), lon_e7=round(lon * 1e7),
                                 alt_cm=round(alt * 100))

    def _read(self, msg, sender, now) -> list:  # handle_mission_request(_int)
        if self.receiving:
            return self._ack(sender, R.MAV_MISSION_DENIED)
        seq = msg.seq
        if self.mission_type != MISSION and seq >= len(self.items):
            # MissionItemProtocol_Fence::get_item: beyond the stored items INVALID_SEQUENCE
            # (the last + 1: ERROR); MissionItemProtocol_Rally::get_item INVALID_SEQUENCE
            fence_last = self.mission_type == ap_fence.MISSION_TYPE_FENCE and seq == len(self.items)
            return self._ack(sender, R.MAV_MISSION_ERROR if fence_last
                             else R.MAV_MISSION_INVALID_SEQUENCE)
        if seq != 0 and seq >= len(self.items):  # MissionItemProtocol_Waypoints::get_item
            return ([(SENDER, R.MAVLink_mission_count_message(sender[0], sender[1],
                                                              len(self.items), MISSION))]
                    + self._ack(sender, R.MAV_MISSION_ERROR))
        it = self.home_item() if seq == 0 and self.mission_type == MISSION else self.items[seq]
        kind = self.mission_type
        if msg.get_type() == "MISSION_REQUEST":  # answered with a float MISSION_ITEM
            out = []
            if not self._request_warning_sent:
                self._request_warning_sent = True
                out.append((EVERY_LINK, _text((R.MAV_SEVERITY_WARNING,
                                               "got MISSION_REQUEST; use MISSION_REQUEST_INT!"))))
            return out + [(SENDER, R.MAVLink_mission_item_message(
                sender[0], sender[1], seq, it.frame, it.command, 0, it.autocontinue,
                it.param1, it.param2, it.param3, it.param4, it.x * 1e-7, it.y * 1e-7, it.z,
                kind))]
        return [(SENDER, R.MAVLink_mission_item_int_message(
            sender[0], sender[1], seq, it.frame, it.command, 0, it.autocontinue,
            it.param1, it.param2, it.param3, it.param4, it.x, it.y, it.z, kind))]

    def _clear(self, msg, sender, now) -> list:  # handle_mission_clear_all
        if self.receiving:
            return self._ack(sender, R.MAV_MISSION_ERROR)
        self.items.clear()  # AP_Mission::clear -> truncate(0)
        self.version += 1
        return self._ack(sender, R.MAV_MISSION_ACCEPTED)

    def update(self, now: float) -> list:
        """Re-request a missing item; cancel a stalled upload (MissionItemProtocol::update),
        as ``(link, message)`` pairs."""
        if not self.receiving:
            return []
        if now - self.timelast_receive > self.options.upload_timeout_s:
            link = self.link  # MissionItemProtocol_Waypoints::timeout says so first
            self._free()
            self._new_fence = []
            text = _TIMEOUT_TEXT.get(self.mission_type, "Mission upload timeout")
            return [(link, _text((R.MAV_SEVERITY_WARNING, text)))] + (
                self._ack(self.dest, R.MAV_MISSION_OPERATION_CANCELLED, link))
        if now - self.timelast_request > self.options.rerequest_s:
            self.timelast_request = now
            return self._request()
        return []


_HANDLERS = {
    "MISSION_COUNT": "_count",
    "MISSION_WRITE_PARTIAL_LIST": "_write_partial",
    "MISSION_ITEM_INT": "_item",
    "MISSION_ITEM": "_item",
    "MISSION_REQUEST_LIST": "_request_list",
    "MISSION_REQUEST_INT": "_read",
    "MISSION_REQUEST": "_read",
    "MISSION_CLEAR_ALL": "_clear",
}
