"""The control endpoint through which `ftlbo-mav abort` reaches a running flight."""

from __future__ import annotations

import json
import socket

import pytest

from ftlbo_mav.flight.control import ControlError, ControlServer, request_abort


def test_an_abort_request_reaches_the_flight_and_its_answer_comes_back():
    calls = []

    def on_abort(mode, sysids):
        calls.append((mode, sysids))
        return {1: mode, 2: "NOT CONFIRMED"}, [7]

    with ControlServer(on_abort, port=0) as server:
        results, unknown = request_abort("LAND", [1, 2, 7], port=server.port)
    assert calls == [("LAND", [1, 2, 7])]
    assert results == {1: "LAND", 2: "NOT CONFIRMED"} and unknown == [7]


def test_no_flight_listening_is_none_not_an_error():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    assert request_abort("RTL", [1], port=port) is None


@pytest.mark.parametrize("request_line,problem", [
    (b"not json\n", "bad request"),
    (json.dumps({"command": "arm"}).encode() + b"\n", "unknown command"),
    (json.dumps({"command": "abort", "mode": "AUTO"}).encode() + b"\n", "mode 'AUTO'"),
    (json.dumps({"command": "abort", "sysids": "1..3"}).encode() + b"\n", "sysids"),
])
def test_bad_requests_are_answered_with_a_reason_and_abort_nothing(request_line, problem):
    calls = []
    with ControlServer(lambda m, s: calls.append(m) or ({}, []), port=0) as server:
        with socket.create_connection(("127.0.0.1", server.port), timeout=2) as conn:
            conn.sendall(request_line)
            reply = json.loads(conn.makefile("rb").readline())
    assert problem in reply["error"] and calls == []


def test_a_port_in_use_is_a_clear_error():
    with ControlServer(lambda m, s: ({}, []), port=0) as first:
        with pytest.raises(ControlError, match="another `ftlbo-mav fly`"):
            ControlServer(lambda m, s: ({}, []), port=first.port)
