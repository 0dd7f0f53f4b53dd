"""Bad input, the rest (issue 21): every case ends in one line ``error: ...``, exit code 2,
nothing written and nothing contacted; a case that is not bad input plans."""

from __future__ import annotations

import json
import os
import shutil
import xml.dom.minidom
from pathlib import Path

import pytest
from click.testing import CliRunner

from ftlbo_mav.cli import main

from .conftest import ROOT, SMALL

EXAMPLE_DIR = ROOT / "missions" / "nha-trang-orchard"
TREES = json.loads((ROOT / "missions" / "nha-trang-orchard-trees.geojson").read_text())


def run(*args: str):
    return CliRunner().invoke(main, list(args))


def refused(result, *words: str) -> str:
    """The result is one line ``error: ...`` holding ``words``, exit 2; returns it."""
    assert result.exit_code == 2, result.output
    assert result.exception is None or isinstance(result.exception, SystemExit), result.exception
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    for word in words:
        assert word in lines[0], lines[0]
    return lines[0]


def with_layer(tmp_path: Path, layer, name: str = "trees.geojson") -> Path:
    """SMALL with ``obstacles_file`` naming ``layer`` (a dict written as JSON, or a path)."""
    if isinstance(layer, dict):
        (tmp_path / name).write_text(json.dumps(layer))
    else:
        name = str(layer)
    path = tmp_path / "s.toml"
    path.write_text(f'obstacles_file = "{name}"\n' + SMALL)
    return path


@pytest.mark.parametrize("crs, words", [
    ({"type": "name", "properties": [1, 2]}, ("crs.properties", "[1, 2]")),
    ("EPSG:3405", ("crs", "the string 'EPSG:3405'")),
    (7, ("crs", "must be an object")),
])
def test_a_geojson_crs_that_is_not_an_object_naming_wgs84(tmp_path, crs, words):
    scenario = with_layer(tmp_path, {**TREES, "crs": crs})
    refused(run("plan", str(scenario), "-o", str(tmp_path / "out")), *words)
    assert not (tmp_path / "out").exists()


def test_a_layer_of_thousands_of_features_all_outside_the_area_plans(tmp_path):
    far = [{"type": "Feature", "properties": {"radius": 2.0},
            "geometry": {"type": "Point", "coordinates": [-170 + i * 1e-3, -60.0]}}
           for i in range(3000)]
    scenario = with_layer(tmp_path, {"type": "FeatureCollection", "features": far})
    result = run("plan", str(scenario), "-o", str(tmp_path / "out"), "-q")
    assert result.exit_code == 0, result.output
    assert "3000 obstacles left out" in result.stderr
    assert (tmp_path / "out" / "uav1.rally").is_file()  # the fence without obstacles


@pytest.mark.parametrize("device", ["/dev/zero", "/dev/urandom"])
def test_an_endless_device_as_scenario_or_layer(tmp_path, device):
    refused(run("plan", device, "-o", str(tmp_path / "out")), device, "not a regular file")
    refused(run("plan", str(with_layer(tmp_path, device)), "-o", str(tmp_path / "out")),
            device, "not a regular file")
    refused(run("sim", "--scenario", device), "not a regular file")
    assert not (tmp_path / "out").exists()


def test_a_fifo_as_the_scenario_is_refused_not_waited_on(tmp_path):
    fifo = tmp_path / "scenario.toml"
    os.mkfifo(fifo)
    refused(run("plan", str(fifo), "-o", str(tmp_path / "out")), "FIFO")
    refused(run("compare", str(fifo), "-o", str(tmp_path / "out"), "--runs", "1"), "FIFO")


def test_a_scenario_with_a_byte_order_mark_reads(tmp_path):
    path = tmp_path / "bom.toml"
    path.write_bytes(b"\xef\xbb\xbf" + SMALL.encode())
    result = run("plan", str(path), "-o", str(tmp_path / "out"), "-q", "--no-fence")
    assert result.exit_code == 0, result.output


def test_a_file_that_is_not_utf8_says_so(tmp_path):
    path = tmp_path / "latin1.toml"
    path.write_bytes(SMALL.replace("test field", "caf\xe9").encode("latin-1"))
    refused(run("plan", str(path), "-o", str(tmp_path / "out")), "not UTF-8")


def _edited_plan(tmp_path: Path, edit) -> Path:
    folder = tmp_path / "plan"
    shutil.copytree(EXAMPLE_DIR, folder)
    doc = json.loads((folder / "plan.json").read_text())
    edit(doc)
    (folder / "plan.json").write_text(json.dumps(doc))
    return folder


def _set(path: str, value):
    def edit(doc):
        *keys, last = path.split(".")
        target = doc
        for k in keys:
            target = target[int(k)] if k.isdigit() else target[k]
        target[int(last) if last.isdigit() else last] = value
    return edit


@pytest.mark.parametrize("edit, words", [
    (_set("obstacles.0.radius", -3.0), ("obstacles[0].radius", "-3")),
    (_set("area.corner_a.0", 1000.0), ("area.corner_a", "latitude 1000")),
    (lambda d: d["area"].__setitem__("corner_b", [d["area"]["corner_a"][0],
                                                   d["area"]["corner_b"][1]]),
     ("area", "no extent")),
    (_set("waypoints", 7), ("legs[0].waypoints", "waypoints = 7")),
    (_set("uavs.1.waypoints.2.lon", 400.0), ("uavs[1].waypoints[2]", "longitude 400")),
    (_set("clearance", -1.0), ("clearance",)),
])
def test_plot_refuses_a_plan_json_no_scenario_could_have_written(tmp_path, edit, words):
    folder = _edited_plan(tmp_path, edit)
    refused(run("plot", str(folder), "-o", str(tmp_path / "figures")), *words)
    assert not (tmp_path / "figures").exists()


def test_upload_of_a_folder_with_an_extra_mission_contacts_nobody(tmp_path):
    folder = tmp_path / "plan"
    shutil.copytree(EXAMPLE_DIR, folder)
    shutil.copy(folder / "uav1.waypoints", folder / "uav0.waypoints")
    # udpout to the discard port: a contact would be a send, and a wait for an answer
    refused(run("upload", str(folder), "--sysid", "1..3", "--connect",
                "udpout:127.0.0.1:9"), "uav0.waypoints", "not a mission of the plan")


@pytest.mark.parametrize("url, words", [
    ("foo:bar", ("'foo' is not a kind of link", "'bar' not a port")),
    ("127.0.0.1:70000", ("port 70000",)),
    ("nothing", ("not a connection string",)),
    (str(ROOT / "pyproject.toml"), ("is a file, not a link",)),
])
def test_a_connection_string_pymavlink_would_misread(tmp_path, url, words):
    refused(run("upload", str(EXAMPLE_DIR), "--sysid", "1..3", "--connect", url), *words)
    refused(run("monitor", "--sysid", "1", "--connect", url), *words)


def test_sim_refuses_ports_past_65535_and_a_scenario_that_does_not_parse(tmp_path):
    refused(run("sim", "--count", "3", "--base-port", "65530"), "65550", "beyond 65535")
    broken = tmp_path / "broken.toml"
    broken.write_text("x = [\n")
    refused(run("sim", "--scenario", str(broken)), "malformed TOML")


def test_kml_stays_well_formed_with_control_characters_in_a_name(tmp_path):
    layer = json.loads(json.dumps(TREES))
    layer["features"][0]["properties"]["name"] = "tree\x02\x1b one"
    scenario = with_layer(tmp_path, layer)
    result = run("plan", str(scenario), "-o", str(tmp_path / "out"), "-q", "--formats", "kml",
                 "--no-fence")
    assert result.exit_code == 0, result.output
    xml.dom.minidom.parse(str(tmp_path / "out" / "plan.kml"))  # raises when not well-formed
    bad = tmp_path / "named.toml"
    bad.write_text(SMALL.replace('"test field"', '"test\\u0007field"'))
    refused(run("plan", str(bad), "-o", str(tmp_path / "out2")), "name", "U+0007")


def test_the_output_folder_never_overwrites_an_input(tmp_path):
    folder = tmp_path / "here"
    folder.mkdir()
    scenario = folder / "plan.json"
    scenario.write_text(SMALL)
    refused(run("plan", str(scenario), "-o", str(folder)), "an input of this command")
    assert scenario.read_text() == SMALL and sorted(os.listdir(folder)) == ["plan.json"]
    layer = with_layer(folder, TREES, name="plan.geojson")
    refused(run("plan", str(layer), "-o", str(folder), "--formats", "geojson"),
            "plan.geojson", "an input of this command")
    assert json.loads((folder / "plan.geojson").read_text()) == TREES


def test_compare_refuses_an_algorithm_named_twice(tmp_path):
    refused(run("compare", str(ROOT / "missions" / "nha-trang-orchard.toml"), "-o",
                str(tmp_path / "out"), "--algorithms", "ftlbo,ga,ftlbo", "--runs", "1"),
            "'ftlbo' is given twice")
    assert not (tmp_path / "out").exists()


def test_fly_reads_the_plan_json_values_before_any_vehicle(tmp_path):
    folder = _edited_plan(tmp_path, _set("obstacles.0.radius", -3.0))
    refused(run("fly", str(folder), "--sysid", "1..3", "--connect", "udpout:127.0.0.1:9"),
            "obstacles[0].radius")


@pytest.mark.parametrize("output, words", [("/dev/zero", "not a regular file"),
                                           ("missing/x.waypoints", "does not exist")])
def test_download_checks_where_it_writes_before_the_vehicle(tmp_path, output, words):
    target = output if output.startswith("/") else str(tmp_path / output)
    refused(run("download", "--sysid", "1", "--connect", "udpout:127.0.0.1:9", "-o", target),
            words, "no vehicle was contacted")


def test_formats_that_name_nothing(tmp_path):
    example = str(ROOT / "missions" / "nha-trang-orchard.toml")
    refused(run("plan", example, "-o", str(tmp_path / "out"), "--formats", ",,"),
            "names no format")
