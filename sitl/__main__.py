"""``python -m sitl --count 3 [--scenario FILE] [--binary PATH] [--radio SPEC]
[--instance-binary SYSID=PATH] [--instance-defaults SYSID=FILE]``: run SITL
copters until Ctrl-C; with ``--radio`` (``good``, ``rough`` or ``key=value`` pairs, as
``ftlbo-mav sim --radio``) all of them behind one telemetry radio to ``--udp-out``
(ftlbo_mav/sim/router.py): connect the ground station with ``udpin:HOST:PORT``."""

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


def _radio(text: str):
    from ftlbo_mav.sim.radio import parse_radio

    try:
        return parse_radio(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _udp_out(text: str) -> tuple[str, int]:
    host, _, port = text.rpartition(":")
    if not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise argparse.ArgumentTypeError(f"{text}: HOST:PORT")
    return host, int(port)


def _for_sysid(text: str) -> tuple[int, str]:
    sysid, sep, path = text.partition("=")
    if not sep or not sysid.isdigit() or not path:
        raise argparse.ArgumentTypeError(f"{text}: SYSID=PATH")
    return int(sysid), path


def main(argv: list[str] | None = None) -> int:
    """Exit codes: 0 stopped by Ctrl-C/SIGTERM, 2 bad input, 1 SITL failed (died, not ready)."""
    parser = argparse.ArgumentParser(prog="python -m sitl", description=__doc__)
    parser.add_argument("--count", type=_count, default=None,
                        help="copters (default: the scenario's UAVs, else 3)")
    parser.add_argument("--scenario", help="put each home at its UAV's start position")
    parser.add_argument("--binary", help="arducopter binary (default: $ARDUPILOT_SITL)")
    parser.add_argument("--defaults", action="append", default=[],
                        help="extra defaults .parm file (e.g. ArduPilot's copter.parm)")
    parser.add_argument("--instance-binary", action="append", default=[], type=_for_sysid,
                        metavar="SYSID=PATH",
                        help="this copter's arducopter binary (a fleet of two releases)")
    parser.add_argument("--instance-defaults", action="append", default=[], type=_for_sysid,
                        metavar="SYSID=FILE",
                        help="this copter's own defaults file, after the others (a 3DR "
                             "Solo's values for one)")
    parser.add_argument("--speedup", type=_speedup, default=1.0)
    parser.add_argument("--workdir", help="keep the instances' files here")
    parser.add_argument("--radio", type=_radio, default=None,
                        help="one shared radio to --udp-out: good, rough, or key=value pairs")
    parser.add_argument("--udp-out", type=_udp_out, default=("127.0.0.1", 14550),
                        help="the ground station's UDP address for --radio "
                             "(default 127.0.0.1:14550)")
    parser.add_argument("--seed", type=int, default=0, help="the radio's losses and delays")
    args = parser.parse_args(argv)

    from ftlbo_mav.scenario import load_scenario
    from ftlbo_mav.sim.homes import default_homes, scenario_homes

    try:
        homes = (scenario_homes(load_scenario(args.scenario)) if args.scenario
                 else default_homes(args.count or 3))
        if args.count is not None and args.count != len(homes):
            parser.error(f"--count {args.count}, but the scenario has {len(homes)} UAVs")
        n = len(homes)
        binaries: list[str | None] = [None] * n
        own: list[list[str]] = [[] for _ in range(n)]
        for sysid, _path in args.instance_binary + args.instance_defaults:
            if sysid > n:
                parser.error(f"sysid {sysid}: the copters are 1..{n}")
        for sysid, path in args.instance_binary:
            binaries[sysid - 1] = path
        for sysid, path in args.instance_defaults:
            own[sysid - 1].append(path)
        with SitlSwarm(binary=args.binary, homes=homes, defaults=args.defaults,
                       speedup=args.speedup, workdir=args.workdir, binaries=binaries,
                       instance_defaults=own) as swarm:
            for i, url in enumerate(swarm.urls):
                print(f"SITL sysid {i + 1}: {url}  home {homes[i][0]:.7f}, {homes[i][1]:.7f}")
            if args.radio is None:
                print("ready (GPS fix, pre-arm checks pass); Ctrl-C to stop", flush=True)
                signal.pause()
            else:
                from ftlbo_mav.sim.router import RadioRouter

                with RadioRouter(swarm.urls, args.udp_out, args.radio, seed=args.seed,
                                 time_scale=args.speedup) as router:
                    print(f"one radio for all: connect with {router.udp_url}; ready; "
                          "Ctrl-C to stop", flush=True)
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
