"""Issue 4's acceptance tests: `ftlbo-mav upload` and `download` against real links.

Run against the emulator, or ArduPilot SITL when ARDUPILOT_SITL is set (tests that need
fault injection are skipped there). All addresses are loopback.
"""

from __future__ import annotations

import hashlib

import pytest
from click.testing import CliRunner

from ftlbo_mav.cli import main
from ftlbo_mav.link.codec import mission_differences
from ftlbo_mav.mission.waypoints import read_waypoints
from ftlbo_mav.sim.faults import Faults
from ftlbo_mav.sim.mission_server import MissionServerOptions
from ftlbo_mav.sim.vehicle import VehicleOptions
from tests.integration.fleet import FAST, vehicles
from tests.link.support import make_mission, write_missions

pytestmark = pytest.mark.sitl


def run(*args):
    result = CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)
    return result.exit_code, result.output


def connect(urls):
    return [x for u in urls for x in ("--connect", u)]


ITEMS = len(make_mission(0))  # every mission write_missions writes has as many


def verified_lines(output):
    return [line for line in output.splitlines()
            if line.endswith(f"verified ({ITEMS} items)")]


def test_three_vehicles_three_missions_one_command(tmp_path):
    missions = write_missions(tmp_path, 3)
    with vehicles(3) as fleet:
        code, out = run("upload", tmp_path, "--sysid", "1..3", *connect(fleet.urls))
        assert code == 0, out
        assert len(verified_lines(out)) == 3 and "3/3 vehicles verified" in out
        for k, url in enumerate(fleet.urls):
            dest = tmp_path / f"back{k + 1}.waypoints"
            code, out = run("download", "--sysid", k + 1, "--connect", url, "-o", dest)
            assert code == 0, out
            assert mission_differences(missions[k], read_waypoints(dest)) == []


def test_the_same_over_one_shared_link(tmp_path):
    write_missions(tmp_path, 3)
    with vehicles(3, shared_link=True) as fleet:
        code, out = run("upload", tmp_path, "--sysid", "1..3", "--connect", fleet.udp_url)
        assert code == 0, out
        assert len(verified_lines(out)) == 3


def test_thirty_percent_loss_each_way_duplicates_and_reordering(tmp_path):
    write_missions(tmp_path, 3)
    faults = Faults(loss_up=0.3, loss_down=0.3, duplicate=0.05, reorder=0.05)
    with vehicles(3, faults=faults, seed=11) as fleet:
        code, out = run("upload", tmp_path, "--sysid", "1..3", *connect(fleet.urls))
        assert code == 0, out
        assert len(verified_lines(out)) == 3


def test_a_vehicle_that_never_answers_is_named_and_the_others_verified(tmp_path):
    write_missions(tmp_path, 3)
    faults = [Faults(), Faults(silent=True), Faults()]
    with vehicles(3, faults=faults) as fleet:
        code, out = run("upload", tmp_path, "--sysid", "1..3", "--discover-timeout", "1",
                        *connect(fleet.urls))
    assert code == 1
    assert "uav2 -> sysid 2: FAILED: system id 2: no HEARTBEAT within 1 s" in out
    assert len(verified_lines(out)) == 2 and "2/3 vehicles verified" in out


def test_a_vehicle_that_stops_answering_the_mission_protocol(tmp_path):
    write_missions(tmp_path, 3)
    faults = [Faults(), Faults(), Faults(mute=True)]
    with vehicles(3, faults=faults) as fleet:
        code, out = run("upload", tmp_path, "--sysid", "1..3", "--timeout", "0.3",
                        "--retries", "2", *connect(fleet.urls))
    assert code == 1
    assert ("uav3 -> sysid 3: FAILED: upload failed: no answer to MISSION_COUNT within 0.9 s"
            in out)
    assert len(verified_lines(out)) == 2


def test_a_mission_longer_than_the_vehicle_holds_is_refused_at_once_with_the_count(tmp_path):
    """ArduPilot answers NO_SPACE and says "Only N items are supported": final at once,
    nothing is sent, and nothing is cleared on the vehicle."""
    write_missions(tmp_path, 2)
    small = VehicleOptions(heartbeat_s=FAST.heartbeat_s,
                           mission=MissionServerOptions(capacity=10))
    with vehicles(2, options=[FAST, small]) as fleet:
        code, out = run("upload", tmp_path, "--sysid", "1,2", *connect(fleet.urls))
        assert fleet.missions()[1] == []
    assert code == 1
    assert ("uav2 -> sysid 2: FAILED: upload failed: the vehicle holds at most 10 mission "
            f"items and this mission has {ITEMS}") in out
    assert "its mission is unchanged" in out and len(verified_lines(out)) == 1


def test_capacity_given_by_the_user_is_checked_before_any_vehicle(tmp_path):
    write_missions(tmp_path, 2)
    code, out = run("upload", tmp_path, "--sysid", "1,2", "--capacity", "12",
                    "--connect", "tcp:127.0.0.1:9")
    assert code == 2
    assert f"uav1.waypoints has {ITEMS} items, more than --capacity 12" in out
    assert "no vehicle was contacted" in out


def test_no_space_while_booting_is_waited_out(tmp_path):
    write_missions(tmp_path, 2)
    booting = VehicleOptions(heartbeat_s=FAST.heartbeat_s,
                             mission=MissionServerOptions(boot_no_space_s=1.0))
    with vehicles(2, options=booting) as fleet:
        code, out = run("upload", tmp_path, "--sysid", "1..2", *connect(fleet.urls))
    assert code == 0, out


@pytest.fixture
def keys(tmp_path):
    right, wrong = tmp_path / "right.key", tmp_path / "wrong.key"
    right.write_text("orchard survey key\n")
    wrong.write_text("not the key\n")
    return right, wrong, hashlib.sha256(b"orchard survey key").digest()


def test_signing_required_accepts_the_signed_upload(tmp_path, keys):
    right, _wrong, secret = keys
    write_missions(tmp_path, 2)
    with vehicles(2, signing_key=secret) as fleet:
        code, out = run("upload", tmp_path, "--sysid", "1..2", "--signing-key", right,
                        *connect(fleet.urls))
    assert code == 0, out


@pytest.mark.parametrize("which", ["wrong", "unsigned"])
def test_signing_required_ignores_wrong_or_missing_signatures(tmp_path, keys, which):
    _right, wrong, secret = keys
    write_missions(tmp_path, 2)
    key_args = ["--signing-key", wrong] if which == "wrong" else []
    with vehicles(2, signing_key=secret) as fleet:
        code, out = run("upload", tmp_path, "--sysid", "1..2", "--timeout", "0.3",
                        "--retries", "2", *key_args, *connect(fleet.urls))
        assert fleet.missions() == [[], []]
    assert code == 1
    for sysid in (1, 2):
        assert (f"uav{sysid} -> sysid {sysid}: FAILED: upload failed: no answer to "
                f"MISSION_COUNT within 0.9 s") in out
    assert "signing key" in out


def test_a_mission_file_that_does_not_parse_stops_before_any_vehicle(tmp_path):
    write_missions(tmp_path, 3)
    (tmp_path / "uav2.waypoints").write_text("QGC WPL 110\n0\t1\t0\t16\tnot a number\n")
    # nothing listens on the given port: any attempt to connect would be a different error
    code, out = run("upload", tmp_path, "--sysid", "1..3", "--connect", "tcp:127.0.0.1:9")
    assert code == 2
    assert out.strip().startswith("error:") and "uav2.waypoints: line 2" in out


def test_file_count_must_match_the_ids(tmp_path):
    write_missions(tmp_path, 3)
    code, out = run("upload", tmp_path, "--sysid", "1,2", "--connect", "tcp:127.0.0.1:9")
    assert code == 2 and "holds 3 missions" in out and "names 2 vehicles" in out


def test_nothing_goes_to_ids_not_asked_for(tmp_path):
    write_missions(tmp_path, 2)
    with vehicles(3, shared_link=True) as fleet:
        code, out = run("upload", tmp_path, "--sysid", "1,3", "--connect", fleet.udp_url)
        stored = fleet.missions()
    assert code == 0, out
    assert len(stored[0]) == ITEMS and stored[1] == [] and len(stored[2]) == ITEMS


@pytest.mark.parametrize("after", [0, 5])
def test_a_link_that_closes_mid_upload_fails_that_vehicle_and_the_others_go_on(tmp_path,
                                                                                after):
    """Issue 12: the vehicle whose link drops gets a FAILED line with the cause and what it
    now holds; the others are verified; the summary is printed; exit 1; no traceback."""
    write_missions(tmp_path, 3)
    faults = [Faults(), Faults(close_after_items=after), Faults()]
    with vehicles(3, faults=faults) as fleet:
        code, out = run("upload", tmp_path, "--sysid", "1..3", "--timeout", "0.3",
                        "--retries", "2", *connect(fleet.urls))
    assert code == 1, out
    failed = [line for line in out.splitlines() if line.startswith("uav2 -> sysid 2: FAILED:")]
    assert len(failed) == 1, out
    assert "closed by the other end" in failed[0] or "the link failed" in failed[0]
    assert "hold" in failed[0]  # what the vehicle may now hold, and how to check it
    assert len(verified_lines(out)) == 2 and "2/3 vehicles verified" in out


def _on_firmware(firmware):
    from dataclasses import replace

    from ftlbo_mav.ardupilot.firmware import Firmware

    return [FAST, replace(FAST, firmware=Firmware.decode(firmware)), FAST]


def test_a_vehicle_on_another_firmware_refuses_the_whole_upload_before_anything_is_sent(
        tmp_path):
    write_missions(tmp_path, 3)
    with vehicles(3, options=_on_firmware(0x04040400 | 255)) as fleet:  # ArduCopter 4.4.4
        code, out = run("upload", tmp_path, "--sysid", "1..3", *connect(fleet.urls))
        assert code == 1, out
        assert "sysid 2: FAILED: firmware: it runs 4.4.4 official" in out
        assert "--any-firmware" in out
        assert out.count("not uploaded: sysid 2 runs another firmware") == 2
        assert fleet.missions() == [[], [], []]  # nothing sent to any


def test_any_firmware_uploads_and_says_what_is_not_promised(tmp_path):
    write_missions(tmp_path, 3)
    with vehicles(3, options=_on_firmware(0x04060000 | 64)) as fleet:  # 4.6.0 alpha
        code, out = run("upload", tmp_path, "--sysid", "1..3", "--any-firmware",
                        *connect(fleet.urls))
        assert code == 0, out
        assert ("warning: uav2 (sysid 2): firmware: it runs 4.6.0 alpha: the predicted flown "
                "path, the clearance kept on it and its timing are not promised") in out
        assert len(verified_lines(out)) == 3
