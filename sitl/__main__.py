"""``python -m sitl --count 3 [--scenario FILE] [--binary PATH]``: run SITL copters until Ctrl-C."""

from __future__ import annotations

import argparse
import math
import signal
import sys

from ftlbo_mav.errors import FtlboError, ScenarioError

from .launcher import SitlSwarm


def _count(text: str) -> int:
    value = int(text)
    if not 1 <= value <= 254:
        raise argparse.ArgumentTypeError(f"{text}: copters are system ids 1..254")
    return value


def _speedup(text: str) -> float:
    value = float(text)
    if not (math.isfinite(value) and 0 < value <= 1000):
        raise argparse.ArgumentTypeError(f"{text}: a speed-up within (0, 1000]")
    return value


def main(argv: list[str] | None = None) -> int:
    """Exit codes: 0 stopped by Ctrl-C/SIGTERM, 2 bad input, 1 SITL failed (died, not ready)."""
    parser = argparse.ArgumentParser(prog="python -m sitl", description=__doc__)
    parser.add_argument("--count", type=_count, default=None,
                        help="copters (default: the scenario's UAVs, else 3)")
    parser.add_argument("--scenario", help="put each home at its UAV's start position")
    parser.add_argument("--binary", help="arducopter binary (default: $ARDUPILOT_SITL)")
    parser.add_argument("--defaults", action="append", default=[],
                        help="extra defaults .parm file (e.g. ArduPilot's copter.parm)")
    parser.add_argument("--speedup", type=_speedup, default=1.0)
    parser.add_argument("--workdir", help="keep the instances' files here")
    args = parser.parse_args(argv)

    from ftlbo_mav.scenario import load_scenario
    from ftlbo_mav.sim.homes import default_homes, scenario_homes

    try:
        homes = (scenario_homes(load_scenario(args.scenario)) if args.scenario
                 else default_homes(args.count or 3))
        if args.count is not None and args.count != len(homes):
            parser.error(f"--count {args.count}, but the scenario has {len(homes)} UAVs")
        with SitlSwarm(binary=args.binary, homes=homes, defaults=args.defaults,
                       speedup=args.speedup, workdir=args.workdir) as swarm:
            for i, url in enumerate(swarm.urls):
                print(f"SITL sysid {i + 1}: {url}  home {homes[i][0]:.7f}, {homes[i][1]:.7f}")
            print("ready (GPS fix, pre-arm checks pass); Ctrl-C to stop", flush=True)
            signal.pause()
    except KeyboardInterrupt:
        pass
    except (FtlboError, ValueError, OSError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        bad = isinstance(exc, ScenarioError) or getattr(exc, "bad_input", False)
        return 2 if bad else 1
    return 0


def _interrupt(_signum, _frame):
    raise KeyboardInterrupt


if __name__ == "__main__":
    signal.signal(signal.SIGTERM, _interrupt)  # stop the copters on `kill` too
    sys.exit(main())
