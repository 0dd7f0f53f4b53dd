"""The mission, fence, rally and parameter files load with MAVProxy's own loaders: the
classes its ``wp``, ``fence`` and ``rally`` modules read files with
(``MAVProxy.modules.mavproxy_fence.FenceModule.loader_class()`` is
``pymavlink.mavwp.MissionItemProtocol_Fence``, the rally module's
``MissionItemProtocol_Rally``, the wp module's ``MAVWPLoader``) and ``param load``'s
``pymavlink.mavparm.MAVParmDict.load``. They run in a child process: the fence and rally
loaders need MAVLink 2 (``MAVLINK20`` in the environment), a process-wide pymavlink
setting the other tests should not inherit.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from ftlbo_mav.mission.export import write_plan
from ftlbo_mav.mission.fence_files import read_fence_set
from ftlbo_mav.mission.plan_reader import read_plan
from ftlbo_mav.mission.waypoints import read_waypoints

STORED = Path(__file__).resolve().parents[1] / "data" / "orchard-plan"

LOAD = r"""
import json, sys
from pymavlink import mavparm
from MAVProxy.modules.mavproxy_fence import FenceModule
from MAVProxy.modules.mavproxy_rally import RallyModule
from MAVProxy.modules.mavproxy_wp import WPModule

folder = sys.argv[1]
out = {}
for name, loader in (("waypoints", WPModule.loader_class(None)),
                     ("fence", FenceModule.loader_class()), ("rally", RallyModule.loader_class())):
    wp = loader(target_system=1, target_component=1)
    wp.load(f"{folder}/uav1.{name}")
    out[name] = [[w.seq, w.frame, w.command, w.param1, w.x, w.y, w.z, w.mission_type]
                 for w in (wp.wp(i) for i in range(wp.count()))]
params = mavparm.MAVParmDict()
params.load(f"{folder}/fence.parm", mav=None)
out["params"] = dict(params)
print(json.dumps(out))
"""


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("gcs")
    write_plan(read_plan(STORED), out)
    return out


@pytest.fixture(scope="module")
def loaded(folder) -> dict:
    env = {**os.environ, "MAVLINK20": "1"}
    done = subprocess.run([sys.executable, "-c", LOAD, str(folder)], env=env, text=True,
                          capture_output=True, timeout=120, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def _same(ours, theirs, mission_type):
    assert len(theirs) == len(ours)
    for it, (seq, frame, command, p1, lat, lon, alt, kind) in zip(ours, theirs):
        assert (seq, frame, command, kind) == (it.seq, it.frame, it.command, mission_type)
        assert p1 == pytest.approx(it.param1, abs=1e-6)
        assert (lat, lon) == (pytest.approx(it.lat_deg, abs=1e-8),
                              pytest.approx(it.lon_deg, abs=1e-8))
        assert alt == pytest.approx(it.alt_m, abs=1e-6)


def test_mavproxy_reads_the_mission_as_written(folder, loaded):
    _same(read_waypoints(folder / "uav1.waypoints"), loaded["waypoints"], 0)


def test_mavproxy_reads_the_fence_as_fence_items(folder, loaded):
    fence = read_fence_set(folder, "uav1")
    _same(fence.fence, loaded["fence"], 1)  # mission_type FENCE
    assert {row[2] for row in loaded["fence"]} == {5001, 5004}


def test_mavproxy_reads_the_rally_point(folder, loaded):
    _same(read_fence_set(folder, "uav1").rally, loaded["rally"], 2)  # mission_type RALLY
    assert [row[2] for row in loaded["rally"]] == [5100]


def test_mavproxy_param_load_reads_the_fence_parameters(folder, loaded):
    assert loaded["params"] == read_fence_set(folder, "uav1").params
    assert set(loaded["params"]) == {"FENCE_ENABLE", "FENCE_TYPE", "FENCE_ACTION",
                                     "FENCE_ALT_MAX", "FENCE_MARGIN"}
