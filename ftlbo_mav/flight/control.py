"""Abort from anywhere: the control endpoint that ``fly`` opens for other terminals.

SITL's TCP ports, like a telemetry radio, serve one ground station at a time, and ``fly``
holds them. So that ``ftlbo-mav abort`` typed in a second terminal still reaches every
vehicle at once, ``fly`` listens on ``127.0.0.1:5750`` (``--control-port``; loopback
only) for one-line JSON requests and answers each with one line:

    -> {"command": "abort", "mode": "RTL", "sysids": [1, 2, 3]}
    <- {"results": {"1": "RTL", "2": "RTL", "3": "RTL"}, "unknown": []}

``results`` holds the vehicles of this flight, each with the mode it confirmed or
``"NOT CONFIRMED"``; ``unknown`` the requested ids this flight does not hold. The abort
goes out on ``fly``'s own links, with ``fly``'s own abort (every vehicle switched in one
burst, then confirmed), and ``fly`` stops commanding the vehicles from then on.
"""

from __future__ import annotations

import json
import socket
import threading
from collections.abc import Callable, Sequence
from typing import Self

from ..errors import FtlboError

DEFAULT_CONTROL_PORT = 5750
ABORT_MODES = ("RTL", "LAND")


class ControlError(FtlboError):
    """The control endpoint cannot be opened or gave a malformed answer."""


class ControlServer:
    """Listens on ``127.0.0.1:port`` while a flight runs; ``on_abort(mode, sysids)`` does
    the abort and returns ``({sysid: confirmed mode or "NOT CONFIRMED"}, unknown_ids)``.

    ``port=0`` takes any free port (see :attr:`port`). Use as a context manager.
    """

    def __init__(self, on_abort: Callable[[str, Sequence[int] | None], tuple[dict, list]], *,
                 port: int = DEFAULT_CONTROL_PORT, host: str = "127.0.0.1") -> None:
        self.on_abort = on_abort
        self._sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self._sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            self._sock.bind((host, port))
        except OSError as exc:
            self._sock.close()
            raise ControlError(f"control endpoint {host}:{port}: {exc.strerror or exc} "
                               "(is another `ftlbo-mav fly` running? pick another "
                               "--control-port)") from None
        self._sock.listen(4)
        self._sock.settimeout(0.2)
        self.host, self.port = self._sock.getsockname()[:2]
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._serve, name="control endpoint",
                                        daemon=True)

    def __enter__(self) -> Self:
        self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        self._thread.join(timeout=2.0)
        self._sock.close()

    def _serve(self) -> None:
        while not self._stop.is_set():
            try:
                conn, _addr = self._sock.accept()
            except TimeoutError:
                continue
            except OSError:
                return
            threading.Thread(target=self._handle, args=(conn,), daemon=True).start()

    def _handle(self, conn: socket.socket) -> None:
        with conn:
            conn.settimeout(5.0)
            try:
                line = conn.makefile("rb").readline(4096)
                reply = self._answer(line)
            except (OSError, ValueError) as exc:
                reply = {"error": f"bad request: {exc}"}
            try:
                conn.sendall((json.dumps(reply) + "\n").encode())
            except OSError:
                pass

    def _answer(self, line: bytes) -> dict:
        request = json.loads(line)
        if not isinstance(request, dict) or request.get("command") != "abort":
            return {"error": "unknown command (expected {\"command\": \"abort\", ...})"}
        mode = request.get("mode", "RTL")
        if mode not in ABORT_MODES:
            return {"error": f"mode {mode!r}: expected one of {', '.join(ABORT_MODES)}"}
        sysids = request.get("sysids")
        if sysids is not None and not (isinstance(sysids, list)
                                       and all(isinstance(s, int) for s in sysids)):
            return {"error": "sysids: expected a list of system ids"}
        results, unknown = self.on_abort(mode, sysids)
        return {"results": {str(k): v for k, v in results.items()}, "unknown": unknown}


def request_abort(mode: str, sysids: Sequence[int] | None, *,
                  port: int = DEFAULT_CONTROL_PORT, host: str = "127.0.0.1",
                  timeout_s: float = 5.0) -> tuple[dict[int, str], list[int]] | None:
    """Ask a running ``fly`` to abort. ``None`` when no flight listens there; else the
    confirmed mode per system id and the ids that flight does not hold."""
    try:
        conn = socket.create_connection((host, port), timeout=0.5)
    except (ConnectionRefusedError, TimeoutError):
        return None
    except OSError as exc:
        raise ControlError(f"control endpoint {host}:{port}: {exc.strerror or exc}") from None
    with conn:
        conn.settimeout(timeout_s)
        request = {"command": "abort", "mode": mode,
                   "sysids": list(sysids) if sysids is not None else None}
        try:
            conn.sendall((json.dumps(request) + "\n").encode())
            line = conn.makefile("rb").readline(65536)
            reply = json.loads(line)
        except (OSError, ValueError) as exc:
            raise ControlError(f"control endpoint {host}:{port}: no valid answer ({exc})") \
                from None
    if "error" in reply:
        raise ControlError(f"control endpoint {host}:{port}: {reply['error']}")
    return {int(k): v for k, v in reply["results"].items()}, list(reply["unknown"])
