"""The emulator inside the ground station's process, on its virtual clock: reached by
``emu:`` connection strings through the same Link, upload and pymavlink parser as over
TCP; a killed vehicle drops its links and refuses new ones."""

from __future__ import annotations

import pytest

from ftlbo_mav import clock
from ftlbo_mav.clock import VirtualClock
from ftlbo_mav.errors import BadInput
from ftlbo_mav.link.addresses import check_url
from ftlbo_mav.link.discovery import discover
from ftlbo_mav.link.endpoints import Link, LinkError
from ftlbo_mav.link.swarm import upload_swarm
from ftlbo_mav.sim.inprocess import InProcessSimulator
from ftlbo_mav.sim.radio import RadioOptions


def _homes(planned):
    return [(m[0].lat_deg, m[0].lon_deg, 0.0) for m in planned.missions]


def test_the_plan_uploads_verified_in_simulated_seconds(planned):
    with VirtualClock(start_s=0.0), InProcessSimulator(homes=_homes(planned)) as sim:
        assert [check_url(u) for u in sim.urls] == sim.urls
        results = upload_swarm(planned.assignments(), sim.urls)
        assert all(r.verified for r in results), [r.message for r in results]
        held = [len(v.autopilot.mission) for v in sim.vehicles]
        assert held == [len(m) for m in planned.missions]
        assert 0.0 < clock.monotonic() < 30.0  # the vehicles' time, not the machine's


def test_a_killed_vehicle_drops_its_link_and_refuses_to_connect_again(planned):
    with VirtualClock(start_s=0.0), InProcessSimulator(homes=_homes(planned)) as sim:
        links = [Link(u) for u in sim.urls]
        try:
            assert set(discover(links, [1, 2, 3], timeout_s=3.0)[0]) == {1, 2, 3}
            sim.kill(1)
            clock.sleep(3.0)  # the links try to connect again every 0.5 s meanwhile
            assert [k.up for k in links] == [True, False, True]
            assert links[1].reconnects == 0
        finally:
            for k in links:
                k.close()
        with pytest.raises(LinkError, match="gone"):
            Link(sim.urls[1], connect_timeout_s=0.0)


def test_a_dropped_link_is_seen_at_once_and_connected_again_half_a_second_later(planned):
    """The links' own duties are calls on the simulated clock (no reader threads): the
    same times as the reader thread keeps, the close noticed when it happens."""
    with VirtualClock(start_s=0.0), InProcessSimulator(homes=_homes(planned)) as sim:
        links = [Link(u) for u in sim.urls]
        try:
            discover(links, [1, 2, 3], timeout_s=3.0)
            clock.sleep(0.013)
            sim.drop(0)
            t0 = clock.monotonic()
            assert not links[0].up and links[0].down_since == t0 and links[1].up
            clock.sleep(0.49)
            assert links[0].reconnects == 0 and not links[0].up
            clock.sleep(0.02)
            assert links[0].reconnects == 1 and links[0].up and links[0].down_since is None
            clock.sleep(1.5)  # heard from again on the new connection
            assert clock.monotonic() - links[0].heartbeats[1].received_at <= 1.0
        finally:
            for k in links:
                k.close()


def test_its_connection_strings_are_its_own_and_only_while_it_runs(planned):
    with VirtualClock(start_s=0.0):
        sim = InProcessSimulator(homes=_homes(planned))
        with sim:
            url = sim.urls[0]
            with pytest.raises(LinkError, match="no such emulated vehicle"):
                Link(f"{sim.key}/7")
        with pytest.raises(BadInput, match="not a kind of link"):
            check_url(url)  # gone with it
        with pytest.raises(LinkError, match="no emulator of that name"):
            Link(url)


def test_it_runs_only_on_a_virtual_clock(planned):
    with pytest.raises(RuntimeError, match="VirtualClock"), \
            InProcessSimulator(homes=_homes(planned)):
        pass


def test_the_shared_link_brings_every_vehicle_through_the_radio_timed_on_the_clock(planned):
    """``emu:KEY/link``: all three vehicles on one connection, their frames through the
    radio's air time and latency (the same figures as over UDP, sim/server.py), each
    radio's RADIO_STATUS once a second; one ground station at a time."""
    with VirtualClock(start_s=0.0), InProcessSimulator(homes=_homes(planned),
                                                       radio=RadioOptions()) as sim:
        link = Link(sim.link_url)
        try:
            assert set(discover([link], [1, 2, 3], timeout_s=3.0)[0]) == {1, 2, 3}
            with pytest.raises(LinkError, match="in use"):
                Link(sim.link_url, connect_timeout_s=0.0)
            clock.sleep(5.0)
        finally:
            link.close()
        counts = sim.radio.counts
        assert counts.delivered["down"] >= 3 * 5  # every vehicle's heartbeat, 5 s long
        for way in ("up", "down"):  # every frame sent arrived or was lost on the air
            assert counts.delivered[way] + counts.lost[way] == counts.sent[way] > 0
    with VirtualClock(start_s=0.0), InProcessSimulator(homes=_homes(planned)) as sim:
        assert sim.link_url is None
        with pytest.raises(LinkError, match="no shared link"):
            Link(f"{sim.key}/link", connect_timeout_s=0.0)
