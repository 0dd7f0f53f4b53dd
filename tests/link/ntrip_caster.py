"""A fake NTRIP caster for tests and benchmarks: one mountpoint, Basic authentication,
NTRIP 2.0 (HTTP/1.1 200 OK, ``Content-Type: gnss/data``, chunked) or 1.0 (``ICY 200 OK``)
answers as the NTRIP 2.0 specification (RTCM 10410.1) describes them; an unknown
mountpoint gets the sourcetable, wrong credentials 401."""

from __future__ import annotations

import base64
import socket
import threading
import time
from collections.abc import Callable, Iterable


class FakeCaster:
    """``with FakeCaster(frames, mount=..., user=..., password=...) as caster:`` serves on
    ``caster.port`` (127.0.0.1). ``frames`` is called once per client and yields the
    bytes to send, each send ``interval_s`` apart. ``requests`` keeps every request head."""

    def __init__(self, frames: Callable[[], Iterable[bytes]], *, mount: str = "BASE1",
                 user: str = "me", password: str = "secret", interval_s: float = 0.0,
                 version: str = "2.0") -> None:
        self.frames, self.mount, self.interval_s, self.version = frames, mount, interval_s, version
        self.auth = base64.b64encode(f"{user}:{password}".encode()).decode()
        self.requests: list[str] = []
        self.sent = 0
        self._server = socket.create_server(("127.0.0.1", 0))
        self.port = self._server.getsockname()[1]
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._serve, daemon=True)

    def __enter__(self) -> FakeCaster:
        self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        try:
            self._server.shutdown(socket.SHUT_RDWR)  # wakes the accept()
        except OSError:
            pass
        self._server.close()
        self._thread.join(timeout=2)

    def _serve(self) -> None:
        while not self._stop.is_set():
            try:
                conn, _ = self._server.accept()
            except OSError:
                return
            threading.Thread(target=self._client, args=(conn,), daemon=True).start()

    def _client(self, conn: socket.socket) -> None:
        with conn:
            head = b""
            while b"\r\n\r\n" not in head:
                chunk = conn.recv(4096)
                if not chunk:
                    return
                head += chunk
            text = head.decode(errors="replace")
            self.requests.append(text)
            path = text.split(" ", 2)[1].lstrip("/") if text.startswith("GET ") else ""
            if path != self.mount:
                table = (f"STR;{self.mount};{self.mount};RTCM 3.3;;2;GPS+GLO;;VNM;"
                         "12.23;109.12;0;0;;none;B;N;9600;\r\n")
                conn.sendall(b"SOURCETABLE 200 OK\r\nContent-Type: gnss/sourcetable\r\n\r\n"
                             + table.encode() + b"ENDSOURCETABLE\r\n")
                return
            if f"Authorization: Basic {self.auth}" not in text:
                conn.sendall(b"HTTP/1.1 401 Unauthorized\r\n\r\n")
                return
            chunked = self.version == "2.0"
            conn.sendall(b"HTTP/1.1 200 OK\r\nContent-Type: gnss/data\r\n"
                         b"Transfer-Encoding: chunked\r\n\r\n"
                         if chunked else b"ICY 200 OK\r\n\r\n")
            time.sleep(0.05)  # the head alone first, as a caster's first write is
            try:
                for data in self.frames():
                    if self._stop.is_set():
                        return
                    conn.sendall(b"%x\r\n%s\r\n" % (len(data), data) if chunked else data)
                    self.sent += len(data)
                    if self.interval_s:
                        time.sleep(self.interval_s)
                if chunked:
                    conn.sendall(b"0\r\n\r\n")
            except OSError:
                return
