"""The radio router between SITL's TCP ports and the ground station (sim/router.py)
delivers frames in the order the radio does, to the microsecond."""

from __future__ import annotations

import asyncio
import time

from ftlbo_mav.sim.router import RadioRouter


def test_frames_a_microsecond_apart_are_delivered_in_the_radios_order():
    """The radio keeps each direction's order by making each arrival at least 1 us after
    the last; frames handed over in a burst (an item and the one sent ahead of it) must
    leave the router in that order, or ArduPilot takes the second for out of sequence."""
    router = RadioRouter.__new__(RadioRouter)  # no copters: only its timing
    router.scale = 1.0
    loop = asyncio.new_event_loop()
    router._loop = loop
    got = []
    try:
        first = time.monotonic() + 0.05
        for k in range(500):
            router._after(first + k * 1e-6, got.append, k)
        loop.run_until_complete(asyncio.sleep(0.1))
    finally:
        loop.close()
    assert got == list(range(500))
