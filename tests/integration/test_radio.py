"""The example through one telemetry radio for the whole swarm (issue 28): one radio
(sim/radio.py: 6,000 B/s for both ways, 60 +- 40 ms, 3 % of frames lost, 2 KiB buffers)
between the ground station and the copters, ``upload`` and ``fly --link sik-64`` over
it. The radio is the emulator's own shared link, or the router (sim/router.py) between
the copters' TCP ports and the ground station: the emulator's, or ArduPilot SITL's."""

from __future__ import annotations

import json
import re

import pytest
from click.testing import CliRunner

from ftlbo_mav import clock
from ftlbo_mav.cli import main
from ftlbo_mav.sim.radio import ROUGH_DAY, RadioOptions

from .fleet import BACKEND, vehicles
from .test_departures import HOMES, example, plan_dir  # noqa: F401 - fixtures

pytestmark = pytest.mark.sitl

# the router between TCP ports runs on the wall clock: the emulator behind it at 12x (the
# keeper measures in real time: off, as in the other fast flights)
SPEEDUP = 1.0 if BACKEND == "sitl" else 12.0
# at 12x the ground station's timing (its threads, the links) is 12 times coarser in the
# copters' seconds, and a formation flown without the keeper drifts past the plan's
# 0.77 m: this test is not about the formation (test_departures.py is)
LOOSE = ["--formation-bound", "5"] if BACKEND == "emulator" else []
# the emulator's own radio is flown on the virtual clock (sim/inprocess.py): the flight
# costs its computation, and a machine busy with other tests cannot make it late; the
# router's flight (12x of the wall clock: a second's stall of the machine is 12 s of the
# copters' legs gone by) runs alone, after the others (pyproject's `solo`)
VARIANTS = ([False, pytest.param(True, marks=pytest.mark.solo)] if BACKEND == "emulator"
            else [True])


@pytest.mark.parametrize("router", VARIANTS, ids=lambda r: "router" if r else "emulator radio")
def test_the_example_uploads_and_flies_through_one_shared_radio(plan_dir, router):  # noqa: F811
    virtual = not router
    with vehicles(3, homes=HOMES, speedup=SPEEDUP, radio=RadioOptions(), router=router,
                  virtual=virtual) as fleet:
        t0 = clock.monotonic()
        up = CliRunner().invoke(main, ["upload", str(plan_dir), "--sysid", "1..3",
                                       "--connect", fleet.udp_url])
        # in the radio's (the vehicles') time
        upload_s = (clock.monotonic() - t0) * (1.0 if virtual else SPEEDUP)
        assert up.exit_code == 0, up.output
        flown = CliRunner().invoke(main, ["fly", str(plan_dir), "--sysid", "1..3",
                                          *([] if virtual else LOOSE),
                                          "--control-port", "0", "--no-keeper", "--link", "sik-64",
                                          "--connect", fleet.udp_url])
        counts = fleet.radio.counts
    print(f"upload {upload_s:.1f} s (radio time); fly exit {flown.exit_code}:\n{flown.output}")
    print(f"radio: {counts}")
    assert flown.exit_code == 0, flown.output
    assert "link: 3 copter(s) at 10 Hz positions" in flown.output
    summary = json.loads((plan_dir / "flight" / "summary.json").read_text())
    link = summary["link"]
    assert link["told"] == {"name": "sik-64", "bytes_per_s": 6000.0}
    assert link["asked"]["position_hz"] == 10.0
    # what went over the radio is what the flight asked for, within the radio's losses
    assert 0.2 < link["measured"]["share_of_link"] < 0.7
    assert link["radio"]["txbuf"] > 50  # the ground radio's RADIO_STATUS was read
    assert counts.lost["down"] > 0 and counts.full["down"] == 0
    assert not summary["departures"]  # 3 % of frames lost: no link taken for lost


@pytest.mark.skipif(BACKEND != "emulator", reason="the emulator's own radio, virtual clock")
def test_a_radio_that_cannot_carry_the_keeper_is_said_before_take_off(plan_dir):  # noqa: F811
    """Through the rough day's radio (120 +- 80 ms, 10 % lost, a 1 s outage every 15 s)
    ``fly`` says before it arms that the keeper cannot pause anyone through it, naming
    the copter and the figure, and flies the formation on its synchronized start."""
    with vehicles(3, homes=HOMES, speedup=1.0, radio=ROUGH_DAY, virtual=True) as fleet:
        up = CliRunner().invoke(main, ["upload", str(plan_dir), "--sysid", "1..3",
                                       "--connect", fleet.udp_url])
        assert up.exit_code == 0, up.output
        flown = CliRunner().invoke(main, ["fly", str(plan_dir), "--sysid", "1..3",
                                          "--control-port", "0", "--link", "sik-64",
                                          "--connect", fleet.udp_url])
    print(flown.output)
    said = flown.output.index("warning: the formation keeper cannot act through this link: ")
    assert said < flown.output.index("arming and taking off")
    assert re.search(r"uav\d's reports (stopped for \d\.\d s|' delays vary by \d+ ms)",
                     flown.output[said:].splitlines()[0])
    assert flown.exit_code == 0, flown.output
    assert "formation keeper: no vehicle needed to wait" in flown.output
