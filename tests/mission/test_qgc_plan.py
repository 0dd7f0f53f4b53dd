"""QGroundControl .plan: schema, round trip, and MAVSDK's own importer reading our files."""

from __future__ import annotations

import json
import re
import time
from functools import lru_cache

import pytest

from ftlbo_mav.errors import MissionFileError
from ftlbo_mav.mission.export import plan_missions
from ftlbo_mav.mission.items import CMD_DO_CHANGE_SPEED, build_mission
from ftlbo_mav.mission.qgc_plan import parse_plan, render_plan, write_plan_file
from ftlbo_mav.mission.waypoints import parse_waypoints, render_waypoints
from ftlbo_mav.planning.planner import plan
from ftlbo_mav.scenario import parse_scenario

from ..conftest import SMALL


@lru_cache(maxsize=1)
def missions():
    return plan_missions(plan(parse_scenario(SMALL), seed=3, students=12, iterations=5))


def test_plan_file_follows_the_documented_schema_and_matches_the_waypoints():
    for m in missions():
        doc = json.loads(render_plan(m.items))
        assert doc["fileType"] == "Plan" and doc["version"] == 1
        mission = doc["mission"]
        assert mission["version"] == 2
        assert mission["firmwareType"] == 3 and mission["vehicleType"] == 2  # ArduPilot copter
        assert isinstance(doc["geoFence"], dict) and isinstance(doc["rallyPoints"], dict)
        # Home is item 0 of the .waypoints and plannedHomePosition of the .plan.
        wp = parse_waypoints(render_waypoints(m.items))
        home = mission["plannedHomePosition"]
        assert home[0] == pytest.approx(wp[0].lat_deg, abs=1e-7)
        assert home[1] == pytest.approx(wp[0].lon_deg, abs=1e-7)
        assert len(mission["items"]) == len(wp) - 1
        for item, ref in zip(mission["items"], wp[1:]):
            assert item["type"] == "SimpleItem"
            assert item["doJumpId"] == ref.seq
            assert (item["frame"], item["command"]) == (ref.frame, ref.command)
            assert item["autoContinue"] is True
            assert len(item["params"]) == 7
            lat, lon, alt = item["params"][4:]
            assert lat == pytest.approx(ref.lat_deg, abs=1e-7)
            assert lon == pytest.approx(ref.lon_deg, abs=1e-7)
            assert alt == pytest.approx(ref.alt_m, abs=1e-6)


def test_render_parse_round_trip_is_exact_with_a_speed_item():
    items = build_mission(home=(12.2332, 109.1145), takeoff_alt_m=5.0,
                          path=[(12.2332, 109.1145, 5.0), (12.2334, 109.11517, 4.5)],
                          end_action="loiter", speed_m_s=3.5)
    assert any(it.command == CMD_DO_CHANGE_SPEED for it in items)
    assert parse_plan(render_plan(items, hover_speed_m_s=3.5)) == items
    for m in missions():
        assert parse_plan(render_plan(m.items)) == list(m.items)


@pytest.mark.parametrize("text, problem", [
    ("{", "not JSON"),
    ('{"fileType": "Mission"}', "fileType"),
    ('{"fileType": "Plan"}', "mission: missing"),
    ('{"fileType": "Plan", "mission": {"plannedHomePosition": [1, 2]}}', "plannedHomePosition"),
    ('{"fileType": "Plan", "mission": {"plannedHomePosition": [1, 2, 0], "items": '
     '[{"type": "ComplexItem"}]}}', "items[0]: only SimpleItem"),
    ('{"fileType": "Plan", "mission": {"plannedHomePosition": [1, 2, 0], "items": '
     '[{"type": "SimpleItem", "frame": 3, "command": 16, "params": [0, 0]}]}}', "items[0]: params"),
])
def test_parse_errors_name_the_file_and_item(text, problem):
    with pytest.raises(MissionFileError, match=re.escape(problem)) as err:
        parse_plan(text, source="x.plan")
    assert str(err.value).startswith("x.plan: ")


# --------------------------------------------------------------------------- MAVSDK

mavsdk = pytest.importorskip("mavsdk")


@pytest.fixture(scope="module")
def mission_raw():
    """MAVSDK's MissionRaw plugin on an in-process ``raw://`` link: no server, no network.

    ``import_qgroundcontrol_mission`` only parses a file, but the plugin needs a System,
    and MAVSDK makes one when it hears an autopilot's heartbeat: we hand it one
    (an ArduPilot quadrotor, so the importer applies ArduPilot's home-as-item-0 rule).
    """
    from mavsdk import ComponentType, Configuration, Mavsdk
    from mavsdk.plugins.mission_raw.mission_raw import MissionRaw
    from pymavlink.dialects.v20 import common as mavlink2

    sdk = Mavsdk(Configuration.create_with_component_type(ComponentType.GROUND_STATION))
    try:
        sdk.add_any_connection("raw://")
        packer = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
        heartbeat = mavlink2.MAVLink_heartbeat_message(
            mavlink2.MAV_TYPE_QUADROTOR, mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA, 0, 0,
            mavlink2.MAV_STATE_STANDBY, 3).pack(packer)
        system = None
        for _ in range(20):  # a bounded wait: the heartbeat is handled on MAVSDK's thread
            sdk.pass_received_raw_bytes(heartbeat)
            system = sdk.first_autopilot(0.1)
            if system is not None:
                break
            time.sleep(0.05)
        if system is None:
            pytest.fail("MAVSDK did not register the autopilot from an in-process heartbeat")
        yield MissionRaw(system)
    finally:
        sdk.destroy()


def test_mavsdk_imports_every_uav_plan_with_the_waypoints_items(mission_raw, tmp_path):
    for m in missions():
        path = write_plan_file(tmp_path / f"{m.name}.plan", m.items)
        imported = mission_raw.import_qgroundcontrol_mission(str(path)).mission_items
        assert len(imported) == len(m.items)
        # ArduPilot: item 0 is home, from plannedHomePosition.
        assert imported[0].x == round(m.items[0].lat_deg * 1e7)
        assert imported[0].y == round(m.items[0].lon_deg * 1e7)
        for got, ref in zip(imported[1:], m.items[1:]):
            assert got.seq == ref.seq
            assert (got.frame, got.command) == (ref.frame, ref.command)
            assert abs(got.x / 1e7 - ref.lat_deg) <= 1e-7
            assert abs(got.y / 1e7 - ref.lon_deg) <= 1e-7
            assert got.z == pytest.approx(ref.alt_m, abs=1e-4)  # float32 in MAVLink
            assert (got.param1, got.param2) == pytest.approx((ref.param1, ref.param2))


def test_mavsdk_import_really_parses_the_file(mission_raw, tmp_path):
    """The check above could pass on an importer that ignores its input: it does not."""
    from mavsdk.plugins.mission_raw.mission_raw import MissionRawError

    text = render_plan(missions()[0].items)
    path = tmp_path / "truncated.plan"
    path.write_text(text[: len(text) // 2])
    with pytest.raises(MissionRawError):
        mission_raw.import_qgroundcontrol_mission(str(path))
