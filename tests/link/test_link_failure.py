"""Issue 12: a link that breaks under a transfer (the socket raises) ends that vehicle's
upload with a result naming the cause and what it may hold, never an exception."""

from __future__ import annotations

import pytest

from ftlbo_mav.link.mission_protocol import Timing
from ftlbo_mav.link.swarm import upload_and_verify
from tests.link.support import make_mission


class BrokenChannel:
    """A channel whose link fails after ``sends`` messages (a reset TCP connection)."""

    sysid, own_sysid, own_compid, srtt = 2, 255, 190, None

    def __init__(self, sends: int, error: OSError):
        self.left, self.error = sends, error

    def send(self, msg) -> None:
        if self.left <= 0:
            raise self.error
        self.left -= 1

    def recv(self, timeout_s: float):
        return None


@pytest.mark.parametrize("error", [BrokenPipeError(32, "Broken pipe"),
                                   ConnectionResetError(104, "Connection reset by peer"),
                                   OSError(9, "Bad file descriptor")])
def test_a_link_that_breaks_is_a_result_with_the_cause_and_what_the_vehicle_holds(error):
    items = make_mission()
    ok, message = upload_and_verify(BrokenChannel(0, error), items,
                                    timing=Timing(timeout_s=0.05, retries=1))
    assert not ok
    assert error.strerror in message and f"0 of {len(items)} items" in message
    assert "ftlbo-mav download --sysid 2" in message
