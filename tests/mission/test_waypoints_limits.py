"""Issue 12: a ``.waypoints`` file's every field is checked where it is read, against
what MAVLink can carry (uint16 seq and command, uint8 frame, 0/1 flags, float32 params)
and what means something (finite, an altitude within 100 km); ``upload`` refuses such a
folder before any vehicle is contacted."""

from __future__ import annotations

import pytest
from click.testing import CliRunner

from ftlbo_mav.cli import main
from ftlbo_mav.errors import BadInput, MissionFileError
from ftlbo_mav.mission.waypoints import parse_waypoints, render_waypoints
from tests.link.support import make_mission, write_missions

FIELDS = ["seq", "current", "frame", "command", "param1", "param2", "param3", "param4",
          "lat", "lon", "alt", "autocontinue"]
BAD = {
    "seq": ["99999999999", "-1"],
    "current": ["7", "-1"],
    "frame": ["300", "-1"],
    "command": ["70000", "-1"],
    "autocontinue": ["999", "2", "-1"],
    **{p: ["nan", "inf", "-inf", "1e300"] for p in ("param1", "param2", "param3", "param4")},
    "lat": ["nan", "91", "inf"],
    "lon": ["nan", "-181", "inf"],
    "alt": ["nan", "inf", "-inf", "1e30", "1e6"],
}
CASES = [(f, v) for f, values in BAD.items() for v in values]


def _with(field: str, value: str, line: int = 3) -> str:
    lines = render_waypoints(make_mission()).splitlines()
    parts = lines[line].split("\t")
    parts[FIELDS.index(field)] = value
    lines[line] = "\t".join(parts)
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("field, value", CASES, ids=[f"{f}={v}" for f, v in CASES])
def test_a_field_that_does_not_fit_is_refused_naming_the_line(field, value):
    with pytest.raises(MissionFileError, match=r"m.waypoints: line 4: ") as info:
        parse_waypoints(_with(field, value), source="m.waypoints")
    assert isinstance(info.value, BadInput)


@pytest.mark.parametrize("field, value", CASES[::3], ids=[f"{f}={v}" for f, v in CASES[::3]])
def test_upload_refuses_it_before_contacting_any_vehicle(field, value, tmp_path):
    write_missions(tmp_path, 3)
    (tmp_path / "uav2.waypoints").write_text(_with(field, value))
    result = CliRunner().invoke(main, ["upload", str(tmp_path), "--sysid", "1..3",
                                       "--connect", "tcp:127.0.0.1:9"])
    assert result.exit_code == 2, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "uav2.waypoints: line 4" in lines[0]
    assert "no vehicle was contacted" in lines[0]


def test_more_items_than_a_mission_count_holds_is_refused():
    header, *items = render_waypoints(make_mission()).splitlines()
    line = items[3].split("\t", 1)[1]
    text = "\n".join([header] + [f"{i}\t{line}" for i in range(70_000)]) + "\n"
    with pytest.raises(MissionFileError, match="at most 65535"):
        parse_waypoints(text)

