"""A stand-in for ArduPilot's ``arducopter`` binary, to test the SITL launcher here.

Takes the command line SITL takes (``--instance``, ``--home``, ``--defaults``) and runs
one emulated copter on TCP 5760 + 10*instance with SYSID_THISMAV from the defaults files.
"""

from __future__ import annotations

import argparse
import signal
import sys

from ftlbo_mav.sim.server import Simulator
from ftlbo_mav.sim.vehicle import VehicleOptions


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--instance", type=int, default=0)
    p.add_argument("--home", required=True)
    p.add_argument("--defaults", default="")
    p.add_argument("--model")
    p.add_argument("--speedup")
    p.add_argument("--wipe", action="store_true")
    args = p.parse_args()
    sysid = 1
    for path in filter(None, args.defaults.split(",")):
        with open(path) as f:
            lines = f.read().splitlines()
        for line in lines:
            parts = line.split()
            if len(parts) == 2 and parts[0] == "SYSID_THISMAV":
                sysid = int(float(parts[1]))
    lat, lon, alt, _hdg = (float(x) for x in args.home.split(","))
    sim = Simulator(homes=[(lat, lon, alt)], base_port=5760 + 10 * args.instance,
                    first_sysid=sysid, options=VehicleOptions(heartbeat_s=0.2, ready_after_s=0.5))
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(0))
    sim.run()


if __name__ == "__main__":
    main()
