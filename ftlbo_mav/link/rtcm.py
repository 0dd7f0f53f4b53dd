"""RTK corrections through the bridge: RTCM3 frames as GPS_RTCM_DATA, for every copter.

The pure core: :func:`fragment` turns one RTCM3 frame into the GPS_RTCM_DATA messages
(``(flags, len, data)``) that carry it, :class:`Reassembler` rebuilds frames from them by
ArduPilot's rules. The edges: :func:`parse_source` (the ``--rtcm`` string),
:func:`tcp_frames` (a TCP stream cut into frames by pyrtcm's RTCMReader),
:func:`ntrip_frames` (an NTRIP caster, through pygnssutils' client) and
:class:`RtcmForwarder` (a thread that sends each frame on every link and counts).

The rules follow ArduPilot 4.5.6, libraries/AP_GPS/AP_GPS.cpp
``AP_GPS::handle_gps_rtcm_data`` (a message whose ``len`` exceeds 180 is ignored) and
``AP_GPS::handle_gps_rtcm_fragment``:

- flags bit 0 clear: the data is injected as it is, alone.
- flags bit 0 set: bits 1-2 are the fragment id, bits 3-7 the sequence id. A fragment
  whose sequence differs from the one being collected, or whose id was already
  received, discards what was collected. A fragment shorter than 180 bytes ends the
  message (count = its id + 1); four full fragments end it too. The message is
  injected once every fragment below the count has arrived.
- So a frame of an exact multiple of 180 bytes (fewer than 4 fragments) needs an empty
  final fragment; more than 4 * 180 = 720 bytes cannot be sent (dropped, counted).

Checked against an AP_GPS.cpp of the ArduPilot repository of the 4.5 era (the one with
``handle_gps_rtcm_data(chan, msg)``, ``rtcm_stats`` and ``AP_GPS_RTCM_DECODE_ENABLED``),
not pinned to the 4.5.6 tag. That version may also decode the injected RTCM (to drop
duplicates arriving on several links); the emulator does not model that.
"""

from __future__ import annotations

import math
import socket
import threading
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from urllib.parse import urlsplit

from pymavlink.dialects.v20 import ardupilotmega as R

from ..errors import BadInput, FtlboError

DATA_LEN = 180  # MAVLINK_MSG_GPS_RTCM_DATA_FIELD_DATA_LEN
MAX_FRAGMENTS = 4
MAX_FRAME = DATA_LEN * MAX_FRAGMENTS  # 720 bytes
SEQUENCES = 32  # 5 bits


class RtcmError(FtlboError):
    """The RTCM source cannot be opened or read."""


class TooLong(ValueError):
    """A frame longer than :data:`MAX_FRAME`: GPS_RTCM_DATA cannot carry it."""


def fragment(frame: bytes, sequence: int) -> list[tuple[int, int, bytes]]:
    """The GPS_RTCM_DATA ``(flags, len, data)`` of one frame, with ``sequence`` (0..31).

    Up to 180 bytes: one unfragmented message. Longer: fragments of 180 bytes, the
    last shorter, or empty when the length is a multiple of 180 below 720. Raises
    :class:`TooLong` past 720 bytes."""
    n = len(frame)
    if n > MAX_FRAME:
        raise TooLong(f"an RTCM frame of {n} bytes is longer than {MAX_FRAME}")
    if n <= DATA_LEN:
        return [(0, n, bytes(frame))]
    pieces = [frame[i:i + DATA_LEN] for i in range(0, n, DATA_LEN)]
    if n % DATA_LEN == 0 and len(pieces) < MAX_FRAGMENTS:
        pieces.append(b"")
    seq = (sequence % SEQUENCES) << 3
    return [(1 | (i << 1) | seq, len(p), bytes(p)) for i, p in enumerate(pieces)]


class Sequencer:
    """The sequence counter of one stream: each fragmented frame takes the next id."""

    def __init__(self) -> None:
        self.next = 0

    def messages(self, frame: bytes) -> list[tuple[int, int, bytes]]:
        out = fragment(frame, self.next)
        if out[0][0] & 1:
            self.next = (self.next + 1) % SEQUENCES
        return out


class Reassembler:
    """AP_GPS::handle_gps_rtcm_fragment: ``add`` returns the injected bytes or None."""

    def __init__(self) -> None:
        self.buffer = bytearray(MAX_FRAME)
        self.sequence = 0
        self.received = 0  # bit mask of fragment ids
        self.count = 0
        self.total = 0
        self.discarded = 0
        self.used = 0

    def add(self, flags: int, data: bytes) -> bytes | None:
        if len(data) > DATA_LEN:
            return None  # handle_gps_rtcm_data: invalid packet
        if not flags & 1:
            return bytes(data)
        frag, seq = (flags >> 1) & 0x03, (flags >> 3) & 0x1F
        if self.received and (self.sequence != seq or self.received & (1 << frag)):
            self.count = 0
            self.discarded += bin(self.received).count("1")
            self.received = 0
        self.sequence = seq
        self.received |= 1 << frag
        start = DATA_LEN * frag
        self.buffer[start:start + len(data)] = data
        if len(data) < DATA_LEN:
            self.count, self.total = frag + 1, start + len(data)
        elif self.received == 0x0F:
            self.count, self.total = 4, MAX_FRAME
        if self.count and self.received == (1 << self.count) - 1:
            self.used += bin(self.received).count("1")
            out = bytes(self.buffer[:self.total])
            self.count = self.received = 0
            return out
        return None


@dataclass(frozen=True)
class Source:
    """A parsed ``--rtcm``: ``kind`` "serial", "tcp" or "ntrip"."""

    kind: str
    host: str = ""
    port: int = 0
    device: str = ""
    user: str = ""
    password: str = ""
    mountpoint: str = ""


def parse_source(text: str) -> Source:
    """``tcp://host:port``, ``ntrip://user:pass@host:port/MOUNT`` or a serial device."""
    if "://" not in text:
        if not text.strip():
            raise BadInput("--rtcm: empty source")
        return Source("serial", device=text)
    parts = urlsplit(text)
    try:
        port = parts.port
    except ValueError:
        raise BadInput(f"--rtcm {text}: the port is not a number 1..65535") from None
    if parts.scheme not in ("tcp", "ntrip"):
        raise BadInput(f"--rtcm {text}: use tcp://host:port, "
                       "ntrip://user:pass@host:port/MOUNTPOINT or a serial port")
    if not parts.hostname or not port:
        raise BadInput(f"--rtcm {text}: give a host and a port")
    if parts.scheme == "tcp":
        return Source("tcp", host=parts.hostname, port=port)
    mount = parts.path.strip("/")
    if not mount:
        raise BadInput(f"--rtcm {text}: an NTRIP source needs /MOUNTPOINT")
    return Source("ntrip", host=parts.hostname, port=port, user=parts.username or "",
                  password=parts.password or "", mountpoint=mount)


def stream_frames(stream) -> Iterator[bytes]:
    """The RTCM3 frames of a byte stream (``read(n)``), cut by pyrtcm's RTCMReader."""
    from pyrtcm import RTCMReader

    reader = RTCMReader(stream, quitonerror=0, parsed=0)  # frames by CRC; not decoded
    for raw, _parsed in reader:
        if raw is None:
            return
        yield raw


def tcp_frames(source: Source, *, timeout_s: float = 5.0) -> Iterator[bytes]:
    """Frames from a TCP stream until it closes."""
    try:
        sock = socket.create_connection((source.host, source.port), timeout=timeout_s)
    except OSError as exc:
        raise RtcmError(f"--rtcm tcp://{source.host}:{source.port}: cannot connect: "
                        f"{exc.strerror or exc}") from None
    with sock, sock.makefile("rb") as stream:
        yield from stream_frames(stream)


def message(flags: int, length: int, data: bytes):
    """A GPS_RTCM_DATA message (data padded to 180 bytes on the wire)."""
    return R.MAVLink_gps_rtcm_data_message(flags, length, data.ljust(DATA_LEN, b"\0"))


class RtcmForwarder:
    """``with RtcmForwarder(frames, links):`` sends each frame on every link (one send
    per link reaches every copter on it: GPS_RTCM_DATA has no target) until the block
    ends. Counts ``frames``, ``bytes`` (RTCM bytes sent) and ``dropped``."""

    def __init__(self, frames, links: Sequence) -> None:
        self.frames_in = frames
        self.links = list(links)
        self.frames = 0
        self.bytes = 0
        self.dropped = 0
        self.error: str | None = None
        self._sequencer = Sequencer()
        self._stop = threading.Event()
        self._started = 0.0
        self._thread = threading.Thread(target=self._run, name="rtcm", daemon=True)

    def __enter__(self) -> RtcmForwarder:
        self._started = time.monotonic()
        self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        self._thread.join(timeout=2.0)

    def bytes_per_s(self) -> float:
        elapsed = time.monotonic() - self._started
        return self.bytes / elapsed if elapsed > 0 else 0.0

    def summary(self) -> dict:
        """What it sent, as summary.json's ``rtcm`` says it."""
        return {"frames": self.frames, "bytes": self.bytes, "dropped": self.dropped,
                "bytes_per_s": round(self.bytes_per_s(), 1), "error": self.error}

    def send(self, frame: bytes) -> None:
        try:
            parts = self._sequencer.messages(frame)
        except TooLong:
            self.dropped += 1
            return
        for link in self.links:
            for flags, length, data in parts:
                try:
                    link.send(message(flags, length, data))
                except OSError:
                    pass
        self.frames += 1
        self.bytes += len(frame)

    def _run(self) -> None:
        try:
            for frame in self.frames_in:
                if self._stop.is_set():
                    return
                self.send(frame)
        except (OSError, RtcmError) as exc:
            self.error = str(exc)


def serial_frames(source: Source, *, baud: int = 115200) -> Iterator[bytes]:
    """Frames from a serial port (a base station's radio), via pyserial."""
    import serial

    try:
        port = serial.Serial(source.device, baud, timeout=1.0)
    except (OSError, serial.SerialException) as exc:
        raise RtcmError(f"--rtcm {source.device}: cannot open: {exc}") from None
    with port:
        yield from stream_frames(port)


def ntrip_frames(source: Source, *, timeout_s: float = 10.0) -> Iterator[bytes]:
    """Frames from an NTRIP caster through pygnssutils' GNSSNTRIPClient (NTRIP 1.0 and
    2.0, Basic authentication), which puts each frame it decodes on a queue.

    Raises :class:`RtcmError` when the caster refuses (its status line: 401, a
    sourcetable for an unknown mountpoint) or sends nothing for ``timeout_s``. Ends when
    the caster closes the stream. Two things pygnssutils 1.3 does that a caster's user
    should know (tests/link/test_ntrip.py shows both): the first read after the
    response head is not forwarded, and a message pyrtcm cannot decode is dropped."""
    import queue

    from pygnssutils import GNSSNTRIPClient

    where = f"--rtcm ntrip://{source.host}:{source.port}/{source.mountpoint}"
    out: queue.Queue = queue.Queue()
    stop = threading.Event()  # run()'s default Event is shared by every client
    # The client's own socket timeout stops it without a word (a log line): give it longer
    # than ours, so a silent caster is always ours to report.
    client = GNSSNTRIPClient(retries=0, timeout=math.ceil(timeout_s) + 3)
    client.run(server=source.host, port=source.port, https=0, mountpoint=source.mountpoint,
               ntripuser=source.user or "anon", ntrippassword=source.password or "password",
               ggainterval=-1, output=out, stopevent=stop)
    last = time.monotonic()
    try:
        while True:
            try:
                item = out.get(timeout=0.2)
            except queue.Empty:
                if not client.connected:  # refused, or a sourcetable: it has stopped
                    _check_refusal(client, where)
                    return
                if time.monotonic() - last >= timeout_s:
                    raise RtcmError(f"{where}: nothing received for {timeout_s:g} s") from None
                continue
            raw = item[0] if isinstance(item, tuple) else item
            if isinstance(raw, list):  # the sourcetable, parsed: the client stops
                continue
            if not raw:  # pygnssutils reads b"" for ever once the caster closed
                return
            yield bytes(raw)
            last = time.monotonic()
    finally:
        client.stop()


def _check_refusal(client, where: str) -> None:
    """Raise what a stopped NTRIP client was told: nothing, a status, a sourcetable."""
    status = client.status
    if not status:
        raise RtcmError(f"{where}: cannot connect")
    if status["code"] != 200:
        raise RtcmError(f"{where}: the caster answered {status['code']} "
                        f"{status['description']}")
    if client.is_sourcetable:
        raise RtcmError(f"{where}: no such mountpoint (the caster sent its sourcetable)")


def frames_from(source: Source) -> Iterator[bytes]:
    """The frames of a parsed ``--rtcm`` source."""
    return {"tcp": tcp_frames, "serial": serial_frames, "ntrip": ntrip_frames}[source.kind](
        source)
