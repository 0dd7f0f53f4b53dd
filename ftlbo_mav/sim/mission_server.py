"""The vehicle side of the mission protocol, as ArduPilot implements it.

A plain state machine: :meth:`MissionServer.handle` takes one message addressed to the
vehicle and the time and returns the replies; :meth:`MissionServer.update` (called a few
times a second) returns the re-requests and cancellations that time brings. Every rule
below copies ArduPilot 4.5 and names the function it copies, in
libraries/GCS_MAVLink/MissionItemProtocol.cpp unless said otherwise.
"""

from __future__ import annotations

from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from ..link.codec import POSITION_COMMANDS

R = mavlink2
MISSION = R.MAV_MISSION_TYPE_MISSION
# AP_Mission::mavlink_int_to_mission_cmd keeps only the altitude frame: the *_INT twins
# are stored, and read back, as their plain frames.
_STORED_FRAME = {5: 0, 6: 3, 11: 10}


@dataclass(frozen=True)
class MissionServerOptions:
    """``capacity``: items that fit (AP_Mission::num_commands_max; a 15-item mission fits
    any real vehicle). ``rerequest_s``: re-ask for a missing item (1 s, update());
    ``upload_timeout_s``: cancel a stalled upload (8 s, MissionItemProtocol.h
    upload_timeout_ms). ``boot_no_space_s``: answer MISSION_COUNT with NO_SPACE for this
    long after boot, as ArduCopter SITL does in its first seconds."""

    capacity: int = 700
    rerequest_s: float = 1.0
    upload_timeout_s: float = 8.0
    boot_no_space_s: float = 0.0


@dataclass(frozen=True)
class StoredItem:
    """One item as AP_Mission keeps it: x, y 1e-7 degrees; altitude in whole centimetres."""

    command: int
    frame: int
    param1: float
    param2: float
    param3: float
    param4: float
    x: int
    y: int
    z: float


def _store(msg) -> StoredItem:
    """As AP_Mission stores it and mission_cmd_to_mavlink_int returns it: the *_INT frames as
    their plain twins; frame GLOBAL (0) for a command without a position."""
    if msg.get_type() == "MISSION_ITEM":  # AP_Mission::convert_MISSION_ITEM_to_MISSION_ITEM_INT
        x, y = round(msg.x * 1e7), round(msg.y * 1e7)
    else:
        x, y = msg.x, msg.y
    return StoredItem(
        command=msg.command,
        frame=(_STORED_FRAME.get(msg.frame, msg.frame) if msg.command in POSITION_COMMANDS
               else R.MAV_FRAME_GLOBAL),
        param1=msg.param1, param2=msg.param2, param3=msg.param3, param4=msg.param4,
        # Location::alt is int32 centimetres (libraries/AP_Common/Location.h)
        x=x, y=y, z=round(msg.z * 100.0) / 100.0,
    )


class MissionServer:
    """ArduPilot's MissionItemProtocol_Waypoints for one vehicle."""

    def __init__(self, *, sysid: int, home: tuple[float, float, float],
                 options: MissionServerOptions = MissionServerOptions(), boot_time: float = 0.0):
        self.sysid = sysid
        self.home = home  # lat_deg, lon_deg, alt_m above mean sea level
        self.options = options
        self.boot_time = boot_time
        self.items: list[StoredItem] = []  # slot 0 is home's; read back as the live home
        self.receiving = False
        self.request_i = 0
        self.request_last = 0
        self.dest = (0, 0)  # sysid, compid of the uploading ground station
        self.timelast_receive = 0.0
        self.timelast_request = 0.0

    # -- replies
    def _ack(self, to: tuple[int, int], result: int) -> list:
        return [R.MAVLink_mission_ack_message(to[0], to[1], result, MISSION)]

    def _request(self) -> list:
        # ArduPilot asks with MISSION_REQUEST, not MISSION_REQUEST_INT (queued_request_send)
        return [R.MAVLink_mission_request_message(self.dest[0], self.dest[1], self.request_i,
                                                  MISSION)]

    def _free(self) -> None:
        self.receiving = False

    # -- the protocol
    def handle(self, msg, now: float) -> list:
        kind = msg.get_type()
        sender = (msg.get_srcSystem(), msg.get_srcComponent())
        if kind not in _HANDLERS:
            return []
        if getattr(msg, "mission_type", MISSION) != MISSION:
            # only the waypoint protocol is emulated (GCS_MAVLINK: no protocol -> UNSUPPORTED)
            return self._ack(sender, R.MAV_MISSION_UNSUPPORTED)
        return getattr(self, _HANDLERS[kind])(msg, sender, now)

    def _count(self, msg, sender, now) -> list:  # handle_mission_count
        if self.receiving and sender != self.dest:
            return self._ack(sender, R.MAV_MISSION_DENIED)  # someone else is uploading
        if now - self.boot_time < self.options.boot_no_space_s:
            return self._ack(sender, R.MAV_MISSION_NO_SPACE)  # storage not ready yet
        if msg.count > self.options.capacity:
            return self._ack(sender, R.MAV_MISSION_NO_SPACE)
        del self.items[msg.count:]  # truncate(packet)
        if msg.count == 0:
            return self._ack(sender, R.MAV_MISSION_ACCEPTED)  # transfer_is_complete
        self.receiving = True  # init_send_requests
        self.request_i, self.request_last = 0, msg.count - 1
        self.dest = sender
        self.timelast_receive = self.timelast_request = now
        return self._request()

    def _item(self, msg, sender, now) -> list:
        if not self.receiving:  # GCS_Common.cpp GCS_MAVLINK::handle_mission_item
            return self._ack(sender, R.MAV_MISSION_ERROR)
        if msg.seq != self.request_i:  # handle_mission_item
            return self._ack(sender, R.MAV_MISSION_INVALID_SEQUENCE)
        if sender != self.dest:
            return self._ack(sender, R.MAV_MISSION_DENIED)
        stored = _store(msg)
        if msg.seq < len(self.items):
            self.items[msg.seq] = stored  # replace_item
        elif msg.seq == len(self.items):
            self.items.append(stored)  # append_item
        else:
            self._free()
            return self._ack(sender, R.MAV_MISSION_ERROR)
        self.timelast_receive = now
        self.request_i += 1
        if self.request_i > self.request_last:
            self._free()  # transfer_is_complete
            return self._ack(sender, R.MAV_MISSION_ACCEPTED)
        self.timelast_request = now
        return self._request()

    def _request_list(self, msg, sender, now) -> list:  # handle_mission_request_list
        if self.receiving:
            return self._ack(sender, R.MAV_MISSION_DENIED)
        return [R.MAVLink_mission_count_message(sender[0], sender[1], len(self.items), MISSION)]

    def _read(self, msg, sender, now) -> list:  # handle_mission_request(_int)
        if self.receiving:
            return self._ack(sender, R.MAV_MISSION_DENIED)
        seq = msg.seq
        if seq != 0 and seq >= len(self.items):  # MissionItemProtocol_Waypoints::get_item
            return ([R.MAVLink_mission_count_message(sender[0], sender[1], len(self.items),
                                                     MISSION)]
                    + self._ack(sender, R.MAV_MISSION_ERROR))
        if seq == 0:  # slot 0 is always the current home (AP_Mission::read_cmd_from_storage)
            lat, lon, alt = self.home
            it = StoredItem(R.MAV_CMD_NAV_WAYPOINT, R.MAV_FRAME_GLOBAL, 0, 0, 0, 0,
                            round(lat * 1e7), round(lon * 1e7), alt)
        else:
            it = self.items[seq]
        if msg.get_type() == "MISSION_REQUEST":  # answered with a float MISSION_ITEM
            return [R.MAVLink_mission_item_message(
                sender[0], sender[1], seq, it.frame, it.command, 0, 1,
                it.param1, it.param2, it.param3, it.param4, it.x * 1e-7, it.y * 1e-7, it.z,
                MISSION)]
        return [R.MAVLink_mission_item_int_message(
            sender[0], sender[1], seq, it.frame, it.command, 0, 1,
            it.param1, it.param2, it.param3, it.param4, it.x, it.y, it.z, MISSION)]

    def _clear(self, msg, sender, now) -> list:  # handle_mission_clear_all
        if self.receiving:
            return self._ack(sender, R.MAV_MISSION_ERROR)
        self.items.clear()  # AP_Mission::clear -> truncate(0)
        return self._ack(sender, R.MAV_MISSION_ACCEPTED)

    def update(self, now: float) -> list:
        """Re-request a missing item; cancel a stalled upload (MissionItemProtocol::update)."""
        if not self.receiving:
            return []
        if now - self.timelast_receive > self.options.upload_timeout_s:
            self._free()
            return self._ack(self.dest, R.MAV_MISSION_OPERATION_CANCELLED)
        if now - self.timelast_request > self.options.rerequest_s:
            self.timelast_request = now
            return self._request()
        return []


_HANDLERS = {
    "MISSION_COUNT": "_count",
    "MISSION_ITEM_INT": "_item",
    "MISSION_ITEM": "_item",
    "MISSION_REQUEST_LIST": "_request_list",
    "MISSION_REQUEST_INT": "_read",
    "MISSION_REQUEST": "_read",
    "MISSION_CLEAR_ALL": "_clear",
}
