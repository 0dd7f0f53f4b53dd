"""One MAVLink connection and the vehicles on it: :class:`Link` and its :class:`Channel` s.

Kept whole: a Link's reader and the Channels it fills are one mechanism (what arrives is
sorted by sender into each vehicle's channel); splitting them would only cut it in two.

A :class:`Link` is one pymavlink connection (``tcp:127.0.0.1:5760``, ``udpin:0.0.0.0:14550``,
a serial port, an emulator in this process...) with a reader thread that sorts what
arrives by the sender's system id. One link may carry one vehicle (SITL's TCP ports) or
several (a telemetry radio, a router's UDP output). :meth:`Link.channel` gives the mission
protocol the messages of one vehicle. Connection strings are checked in
:mod:`.addresses`; :mod:`.discovery` finds which link each vehicle speaks on.
"""

from __future__ import annotations

import queue
import re
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass

# MAVLink 2 is chosen in ftlbo_mav/__init__.py, before pymavlink is imported.
from typing import Self

from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from .. import clock
from ..ardupilot.streams import StreamRequests, radio_slowdown
from ..errors import BadInput, FtlboError
from .addresses import in_process

GCS_SYSID = 255
GCS_COMPID = mavlink2.MAV_COMP_ID_MISSIONPLANNER  # 190
ASK_EVERY_S = 0.1  # how often the reader looks for telemetry to ask for (again)
MAVLINK1_MAGIC = 0xFE  # a MAVLink 1 frame's first byte (MAVLink 2: 0xFD)


class LinkError(FtlboError):
    """A link cannot be opened, or a requested vehicle is not on any link."""


class LinkDown(LinkError, ConnectionResetError):
    """A message could not be sent: the link is closed or broken (and not yet back).
    Also a ConnectionResetError, for callers that handle a broken socket as such."""


@dataclass(frozen=True)
class Heartbeat:
    """What a vehicle said about itself in its last HEARTBEAT."""

    sysid: int
    compid: int
    vehicle_type: int
    autopilot: int
    custom_mode: int
    base_mode: int
    system_status: int
    received_at: float
    mavlink1: bool = False  # it came as a MAVLink 1 frame (the port speaks nothing else)


def _is_vehicle(msg) -> bool:
    return msg.type != mavlink2.MAV_TYPE_GCS and msg.autopilot != mavlink2.MAV_AUTOPILOT_INVALID


def _open(url: str, *, timeout_s: float):
    """Open a pymavlink connection, retrying refused TCP connects until ``timeout_s``."""
    deadline = clock.monotonic() + timeout_s
    if url.startswith("emu:") and in_process(url) is None:
        raise LinkError(f"{url}: no emulator of that name in this process")
    device, baud = url, 115200
    serial = re.fullmatch(r"(/dev/[^,:]+|COM\d+),(\d+)", url)
    if serial:  # a serial port with its baud rate, as MAVProxy writes it: /dev/ttyUSB0,57600
        device, baud = serial.group(1), int(serial.group(2))
    while True:
        try:
            if (connect := in_process(url)) is not None:
                return connect(url, source_system=GCS_SYSID, source_component=GCS_COMPID)
            return mavutil.mavlink_connection(
                device,
                baud=baud,
                source_system=GCS_SYSID,
                source_component=GCS_COMPID,
                dialect="ardupilotmega",
                retries=0,  # one connect per call; the loop here retries quietly
                autoreconnect=False,
            )
        except (TimeoutError, ConnectionRefusedError) as exc:
            if clock.monotonic() >= deadline:
                raise LinkError(f"{url}: cannot connect ({exc.strerror or exc}); is the "
                                "vehicle (SITL, `ftlbo-mav sim`) running?") from None
            clock.sleep(0.2)
        except OSError as exc:
            raise LinkError(f"{url}: cannot open: {exc.strerror or exc}") from None
        except ValueError as exc:
            raise BadInput(f"--connect {url}: {exc}") from None
        except ImportError:
            raise LinkError(f"{url}: serial links need pyserial: "
                            "pip install 'ftlbo-mav[serial]'") from None


class Link:
    """One MAVLink connection shared by every vehicle that speaks on it.

    A reader thread receives, keeps the last HEARTBEAT of each vehicle and hands each
    message to the :class:`Channel` of its sender; it also sends a ground-station
    HEARTBEAT every second (a ``udpout`` peer learns our address from it). Use as a
    context manager; :meth:`close` stops the thread and closes the connection.
    """

    def __init__(self, url: str, *, signing_key: bytes | None = None,
                 connect_timeout_s: float = 5.0, reconnect: bool = True,
                 reconnect_every_s: float = 0.5):
        self.url = url
        self.signing_key = signing_key
        self._conn = self._prepare(_open(url, timeout_s=connect_timeout_s))
        # a TCP peer that closes (a vehicle that reboots, a radio bridge that drops) is
        # connected to again every ``reconnect_every_s`` while the link is open; other
        # links (UDP, serial) simply resume when messages arrive again
        self.reconnect = reconnect and url.startswith(("tcp:", "emu:"))
        self.reconnect_every_s = reconnect_every_s
        self.closed_by_peer = False
        self.down_since: float | None = None  # monotonic time the peer closed, while down
        self.reconnects = 0
        self._send_lock = threading.Lock()
        self._subs_lock = threading.Lock()
        self._queues: dict[int, list[queue.SimpleQueue]] = {}
        self.heartbeats: dict[int, Heartbeat] = {}
        self.versions: dict[int, int] = {}  # AUTOPILOT_VERSION flight_sw_version by sysid
        # per system id: last GPS fix type and whether pre-arm checks pass
        self.readiness: dict[int, dict] = {}
        # called with every message received (from the reader thread): a ground-station
        # relay forwards them (flight/forward.py)
        self.taps: list = []
        # per system id: the telemetry asked for on this link (ardupilot/streams.py)
        self.streams: dict[int, StreamRequests] = {}
        self._streams_lock = threading.Lock()
        # what went over the link: bytes received per system id, bytes sent; the last
        # RADIO_STATUS of the ground's telemetry radio (system id 51, a SiK radio) and
        # ArduPilot's flow control applied to what this station sends on its own (its
        # HEARTBEAT, the stream requests): slower while the radio's buffer fills
        # (ardupilot/streams.py radio_slowdown)
        self.bytes_in: dict[int, int] = {}
        self.bytes_out = 0
        self.radio_status = None
        self.radio_status_t = 0.0
        self.slowdown_ms = 0
        self._stop = clock.Event()
        self._thread: clock.Thread | None = None
        self._next_beat = self._next_ask = 0.0  # when the reader's duties are due
        if self._pushed and clock.virtual() is not None:
            # an emulator in this process on a simulated clock hands its bytes over: the
            # reader's own duties (HEARTBEAT, stream requests, reconnecting) are calls
            # the clock makes in their turn, with no thread to wake
            self._retry_at: float | None = None
            clock.call_later(0.0, self._duty, name=f"link {url}")
        else:
            self._thread = clock.Thread(target=self._run, name=f"link {url}", daemon=True)
            self._thread.start()

    def _prepare(self, conn):
        if self.signing_key is not None:
            # Sign what we send; accept what arrives whether signed or not (a vehicle
            # with signing enabled signs its replies, one without does not).
            conn.setup_signing(self.signing_key, sign_outgoing=True,
                               allow_unsigned_callback=lambda _mav, _msgid: True)
        # pymavlink prints and retries on a closed TCP peer; here the reader notes it
        # (and reconnects, see _run) instead
        conn.handle_eof = conn.handle_disconnect = self._peer_closed
        self._pushed = hasattr(conn, "on_data")
        if self._pushed:  # an emulator in this process hands its bytes over
            conn.on_data = self._drain
        return conn

    @property
    def up(self) -> bool:
        """False from the moment the peer closed until the link is connected again."""
        return not self.closed_by_peer

    # -- lifetime
    def close(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
        try:
            self._conn.close()
        except OSError:
            pass

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # -- sending and receiving
    def send(self, msg) -> None:
        """Send one message (a pymavlink message object) from the ground station's ids;
        :class:`LinkDown` when the link is closed or broken."""
        with self._send_lock:
            if self.closed_by_peer:
                raise LinkDown(f"{self.url}: link down (closed by the other end)")
            try:
                self._conn.mav.send(msg)
            except (OSError, ValueError) as exc:
                raise LinkDown(f"{self.url}: link down ({exc})") from None
            self.bytes_out += len(msg.get_msgbuf())

    def write_raw(self, data: bytes) -> None:
        """Send an already packed MAVLink frame unchanged (a relayed ground station's)."""
        with self._send_lock:
            if self.closed_by_peer:
                raise LinkDown(f"{self.url}: link down (closed by the other end)")
            try:
                self._conn.write(data)
            except (OSError, ValueError) as exc:
                raise LinkDown(f"{self.url}: link down ({exc})") from None

    def want(self, sysid: int, rates) -> None:
        """Have vehicle ``sysid`` send these messages (``{msgid: hz}``) on this link,
        asking (and re-asking until they arrive) from the reader thread."""
        with self._streams_lock:
            beat = self.heartbeats.get(sysid)
            req = self.streams.setdefault(
                sysid, StreamRequests(sysid, beat.compid if beat else 1))
            req.want(rates)

    def unwant(self, sysid: int, msgids) -> None:
        """Have vehicle ``sysid`` stop sending these messages on this link (asked for with
        :meth:`want`): what they cost of a shared radio's air time is not left behind."""
        with self._streams_lock:
            req = self.streams.get(sysid)
            out = req.stop(msgids) if req else []
        for m in out:
            self.send(m)

    def missing_streams(self, sysid: int) -> list[str]:
        with self._streams_lock:
            req = self.streams.get(sysid)
            return req.missing(clock.monotonic()) if req else []

    def _ask_streams(self, now: float) -> None:
        with self._streams_lock:
            out = [m for req in self.streams.values() for m in req.due(now)]
        for m in out:
            try:
                self.send(m)
            except LinkError:
                return

    def channel(self, sysid: int, *,
                on_message: Callable[[object], None] | None = None) -> Channel:
        """The messages of vehicle ``sysid`` on this link, from now on (handed to
        ``on_message`` as they are read, if given)."""
        return Channel(self, sysid, on_message=on_message)

    def _subscribe(self, sysid: int, q: queue.SimpleQueue) -> None:
        with self._subs_lock:
            self._queues.setdefault(sysid, []).append(q)

    def _unsubscribe(self, sysid: int, q: queue.SimpleQueue) -> None:
        with self._subs_lock:
            subs = self._queues.get(sysid, [])
            if q in subs:
                subs.remove(q)

    def _duty(self) -> None:
        """:meth:`_run`'s loop on a virtual clock, each pass a scheduled call: the same
        duties at the same times (:meth:`_duties`; connecting again
        ``reconnect_every_s`` after the peer closed and after each failed try)."""
        if self._stop.is_set():
            return
        name = f"link {self.url}"
        now = clock.monotonic()
        if self.closed_by_peer:
            if not self.reconnect:
                return
            # the first try as long after it closed, each next one as long after the last
            at = (self._retry_at if self._retry_at is not None
                  else (self.down_since or now) + self.reconnect_every_s)
            if now < at - 1e-9:
                self._retry_at = at
                clock.call_later(at - now, self._duty, name=name)
                return
            self._connect_again()
            if self.closed_by_peer:
                self._retry_at = now + self.reconnect_every_s
                clock.call_later(self.reconnect_every_s, self._duty, name=name)
                return
        self._retry_at = None
        clock.call_later(max(0.0, self._duties(now) - now), self._duty, name=name)

    def _duties(self, now: float) -> float:
        """HEARTBEAT every second, the stream requests every :data:`ASK_EVERY_S` (both
        slower while the radio's buffer fills), when due; when the next one is due."""
        if now >= self._next_beat:
            self._next_beat = now + 1.0 + self.slowdown_ms / 1000.0
            try:
                self.send(mavlink2.MAVLink_heartbeat_message(
                    mavlink2.MAV_TYPE_GCS, mavlink2.MAV_AUTOPILOT_INVALID, 0, 0,
                    mavlink2.MAV_STATE_ACTIVE, 3))
            except LinkError:
                pass
        if now >= self._next_ask:
            self._next_ask = now + max(ASK_EVERY_S, self.slowdown_ms / 1000.0)
            self._ask_streams(now)
        return min(self._next_beat, self._next_ask)

    def _run(self) -> None:
        while not self._stop.is_set():
            if self.closed_by_peer:
                if not self.reconnect or self._stop.wait(self.reconnect_every_s):
                    return
                self._connect_again()
                continue
            now = clock.monotonic()
            due = self._duties(now)
            try:
                # what arrives is handed over at once (_drain) on an in-process link:
                # the reader wakes only for its own duties
                self._conn.select(max(0.0, due - now) if self._pushed else 0.05)
                while (msg := self._conn.recv_msg()) is not None:
                    self._dispatch(msg)
            except (OSError, ValueError):
                if not self.closed_by_peer and self._stop.wait(0.1):
                    return

    def _drain(self) -> None:
        """What has arrived, read and handed out now (by whoever brought it)."""
        conn = self._conn
        try:
            while conn.pending() and (msg := conn.recv_msg()) is not None:
                self._dispatch(msg)
        except (OSError, ValueError):
            pass  # a link that broke: the reader thread finds out and reconnects

    def _connect_again(self) -> None:
        """One attempt to open the TCP connection again (the peer closed it)."""
        try:
            conn = self._prepare(_open(self.url, timeout_s=0.0))
        except LinkError:
            return
        with self._send_lock:
            try:
                self._conn.close()
            except OSError:
                pass
            self._conn = conn
            self.closed_by_peer, self.down_since = False, None
            self.reconnects += 1

    def _peer_closed(self) -> None:
        if not self.closed_by_peer:
            self.closed_by_peer, self.down_since = True, clock.monotonic()
        raise ConnectionResetError(f"{self.url}: closed by the other end")

    def _dispatch(self, msg) -> None:
        kind = msg.get_type()
        if kind == "BAD_DATA":
            return
        for tap in self.taps:
            tap(msg)
        src = msg.get_srcSystem()
        self.bytes_in[src] = self.bytes_in.get(src, 0) + len(msg.get_msgbuf())
        if kind == "RADIO_STATUS":
            self.radio_status, self.radio_status_t = msg, clock.monotonic()
            self.slowdown_ms = radio_slowdown(self.slowdown_ms, int(msg.txbuf))
            return
        req = self.streams.get(src)
        if req is not None:
            with self._streams_lock:
                req.seen(msg.get_msgId(), clock.monotonic())
                if (kind == "COMMAND_ACK"
                        and msg.command == mavlink2.MAV_CMD_SET_MESSAGE_INTERVAL):
                    req.on_ack(None, msg.result)
        if kind == "HEARTBEAT" and _is_vehicle(msg):
            self.heartbeats[src] = Heartbeat(
                sysid=src, compid=msg.get_srcComponent(), vehicle_type=msg.type,
                autopilot=msg.autopilot, custom_mode=msg.custom_mode,
                base_mode=msg.base_mode, system_status=msg.system_status,
                received_at=clock.monotonic(), mavlink1=msg.get_msgbuf()[0] == MAVLINK1_MAGIC)
        elif kind == "AUTOPILOT_VERSION":
            self.versions[src] = int(msg.flight_sw_version)
        elif kind == "GPS_RAW_INT":
            self.readiness.setdefault(src, {})["gps_fix"] = msg.fix_type
        elif kind == "SYS_STATUS":
            self.readiness.setdefault(src, {})["prearm"] = bool(
                msg.onboard_control_sensors_health & mavlink2.MAV_SYS_STATUS_PREARM_CHECK)
        with self._subs_lock:
            subs = list(self._queues.get(src, ()))
        for q in subs:
            q.put(msg)


class Channel:
    """One vehicle's messages on a link: what the mission protocol talks through.

    ``recv`` returns only messages from ``sysid`` that are addressed to us (or to
    everyone); ``send`` sends on the link. Close it (or use ``with``) to unsubscribe.
    """

    def __init__(self, link: Link, sysid: int, *,
                 on_message: Callable[[object], None] | None = None):
        self.link = link
        self.sysid = sysid
        self.own_sysid = GCS_SYSID
        self.own_compid = GCS_COMPID
        self.srtt: float | None = None  # round trip measured by the last transfer
        # with ``on_message``, each message for us is handed to it by whoever read it
        # (nothing to ``recv``): on a virtual clock a thread per vehicle only waiting for
        # its messages would cost a turn for every few
        self._q = clock.SimpleQueue() if on_message is None else _Handed(on_message,
                                                                         self.own_sysid)
        link._subscribe(sysid, self._q)

    def send(self, msg) -> None:
        self.link.send(msg)

    @property
    def sharing(self) -> int:
        """How many vehicles share this channel's link (heard on it; at least 1): a
        shared radio's buffer is theirs together, so what one vehicle's exchange keeps
        outstanding at once is divided among them (:mod:`.params`, read-backs). Divided by
        fewer (every 3 vehicles one share), 10 copters overflowed an emulated 2 KiB radio
        buffer at 3,000 B/s and their uploads failed (docs/link.md)."""
        return max(1, len(self.link.heartbeats))

    def recv(self, timeout_s: float):
        """The next message for us from this vehicle, or ``None`` after ``timeout_s``."""
        deadline = clock.monotonic() + max(0.0, timeout_s)
        while True:
            try:
                msg = self._q.get(timeout=max(0.0, deadline - clock.monotonic()))
            except queue.Empty:
                return None
            target = getattr(msg, "target_system", 0)
            if target in (0, self.own_sysid):
                return msg

    def close(self) -> None:
        self.link._unsubscribe(self.sysid, self._q)

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


class _Handed:
    """A :class:`Channel`'s subscription that hands each message for us to a function."""

    __slots__ = ("fn", "own_sysid")

    def __init__(self, fn: Callable[[object], None], own_sysid: int) -> None:
        self.fn, self.own_sysid = fn, own_sysid

    def put(self, msg) -> None:
        if getattr(msg, "target_system", 0) in (0, self.own_sysid):
            self.fn(msg)


def open_links(urls: Sequence[str], *, signing_key: bytes | None = None,
               connect_timeout_s: float = 5.0, reconnect: bool = True) -> list[Link]:
    """Open every link, closing those already opened if one fails."""
    links: list[Link] = []
    try:
        for url in urls:
            links.append(Link(url, signing_key=signing_key, connect_timeout_s=connect_timeout_s,
                              reconnect=reconnect))
    except BaseException:
        for link in links:
            link.close()
        raise
    return links
