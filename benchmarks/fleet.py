"""The fleet as it is: a plan made for ArduCopter's defaults, flown by other copters.

For each scenario (default: the shipped example and the orchard survey, their shipped plan
folders, made for default ArduCopter 4.5 copters) and each fleet, on freshly started
copters: ``ftlbo-mav upload`` (which reads every copter's values and release, predicts
again and writes none of its tuning) and ``ftlbo-mav fly``, then a row: the exit codes,
how many of the copters' tuning parameters changed (read before the upload and after the
flight: must be 0), the clearance upload predicted with the copters' own values and the
one flown, and the formation error on the legs (RMS / worst). Where the upload refuses (a
promise the plan made for default copters loses with these), the scenario is planned for
the fleet as the refusal says (``plan --fleet``, each copter's values read from it) and
that plan uploaded and flown.

Fleets: ``4.5.6`` and ``4.6.3`` (three copters of that release, copter.parm only),
``solo-4.5.6`` and ``solo-4.6.3`` (three 3DR Solos: CubeSolo's defaults.parm after
copter.parm), ``mixed`` (4.5.6, 4.6.3 and a Solo on 4.5.6), ``solo-among-4.5.6`` (two
4.5.6 copters and a Solo).

On ArduPilot SITL when ``ARDUPILOT_SITL`` names a 4.5.x build (``ARDUPILOT_SITL_DEFAULTS``
ArduPilot's copter.parm) and ``ARDUPILOT_SITL_4_6`` a 4.6.x one; on the emulator
otherwise. SITL listens on every interface: run it in a network namespace of its own.

    python benchmarks/fleet.py [--fleet NAME ...] [--scenario FILE ...] [--speedup 4]
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import re
import shutil
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from click.testing import CliRunner  # noqa: E402

from ftlbo_mav.ardupilot.copters import PROFILES  # noqa: E402
from ftlbo_mav.cli import main as cli  # noqa: E402
from ftlbo_mav.flight.planned import load_planned_flight  # noqa: E402
from ftlbo_mav.link.discovery import discover  # noqa: E402
from ftlbo_mav.link.endpoints import open_links  # noqa: E402
from ftlbo_mav.link.params import read_params  # noqa: E402
from ftlbo_mav.link.transfer import Timing  # noqa: E402
from ftlbo_mav.scenario import load_scenario  # noqa: E402
from ftlbo_mav.sim.homes import scenario_homes  # noqa: E402

SOLO = dict(PROFILES["3dr-solo"].params)
FLEETS = {
    "4.5.6": [("4.5.6", {})] * 3,
    "4.6.3": [("4.6.3", {})] * 3,
    "solo-4.5.6": [("4.5.6", SOLO)] * 3,
    "solo-4.6.3": [("4.6.3", SOLO)] * 3,
    "mixed": [("4.5.6", {}), ("4.6.3", {}), ("4.5.6", SOLO)],
    "solo-among-4.5.6": [("4.5.6", {}), ("4.5.6", {}), ("4.5.6", SOLO)],
}
SCENARIOS = [ROOT / "missions" / "nha-trang-orchard.toml",
             ROOT / "missions" / "orchard-survey.toml"]
TUNING = ("PSC_VELXY_P", "PSC_VELXY_I", "PSC_VELXY_D", "PSC_POSXY_P", "ANGLE_MAX",
          "ATC_INPUT_TC", "ATC_ACCEL_R_MAX", "ATC_ACCEL_P_MAX")


@contextlib.contextmanager
def copters(homes, fleet, speedup: float, workdir: Path | None = None):
    """Started copters, one per ``(release, boot parameters)``; yields their URLs.
    ``workdir``: SITL's instance folders (their DataFlash logs) there, kept."""
    sitl = os.environ.get("ARDUPILOT_SITL")
    if sitl:
        from sitl import SitlSwarm

        later = os.environ.get("ARDUPILOT_SITL_4_6")
        if any(r.startswith("4.6") for r, _v in fleet) and not later:
            raise SystemExit("a 4.6 copter on SITL needs ARDUPILOT_SITL_4_6")
        with SitlSwarm(homes=homes, speedup=speedup, workdir=workdir,
                       instance_params=[values for _r, values in fleet],
                       binaries=[later if r.startswith("4.6") else None
                                 for r, _v in fleet]) as swarm:
            yield swarm.urls, "SITL"
        return
    from ftlbo_mav.sim.commands import fleet_options
    from ftlbo_mav.sim.server import Simulator
    from ftlbo_mav.sim.vehicle import VehicleOptions

    base = VehicleOptions(heartbeat_s=0.2)
    options = [fleet_options(base, 1, firmware=[r])[0] for r, _v in fleet]
    with Simulator(homes=homes, base_port=0, time_scale=speedup, options=options) as sim:
        for v, (_r, values) in zip(sim.vehicles, fleet):
            sim.call(lambda v=v, values=values: v.autopilot.params.update(values))
        yield sim.urls, "emulator"


def tuning(urls) -> list[dict]:
    out = []
    for i, url in enumerate(urls):
        links = open_links([url])
        try:
            found, _missing = discover(links, [i + 1])
            with found[i + 1].channel(i + 1) as channel:
                out.append(read_params(channel, TUNING, timing=Timing()))
        finally:
            for link in links:
                link.close()
    return out


def one(scenario: Path, name: str, speedup: float, keep: Path | None = None,
        fly_args: tuple[str, ...] = ()) -> dict:
    folder = Path(tempfile.mkdtemp(prefix="ftlbo-fleet-")) / "plan"
    shutil.copytree(scenario.with_suffix(""), folder)
    homes = scenario_homes(load_scenario(scenario))
    keep_dir = None if keep is None else keep / f"{scenario.stem}-{name}"
    with copters(homes, FLEETS[name], speedup, keep_dir) as (urls, backend):
        before = tuning(urls)
        args = ["--sysid", f"1..{len(urls)}", "--connect", " ".join(urls)]
        up = CliRunner().invoke(cli, ["upload", str(folder), *args])
        plan_for = "default copters"
        if up.exit_code == 1 and "refused" in up.stdout:  # as the refusal says: plan for them
            again = CliRunner().invoke(cli, ["plan", str(scenario), "-o", str(folder), "-q",
                                             "--fleet", f"1..{len(urls)}",
                                             "--connect", " ".join(urls)])
            plan_for = "the fleet (plan --fleet)" if again.exit_code == 0 else (
                f"plan --fleet exit {again.exit_code}")
            up = CliRunner().invoke(cli, ["upload", str(folder), *args])
        flown = CliRunner().invoke(cli, ["fly", str(folder), *args, "--control-port", "0",
                                         *fly_args])
        after = tuning(urls)
    changed = sum(b[k] != a[k] for b, a in zip(before, after) for k in TUNING)
    kept = re.search(r"own values: clearance (\d+\.\d+) m", up.stderr)
    predicted = (float(kept.group(1)) if kept else  # else as planned: nothing differed
                 float(load_planned_flight(folder).predicted_clearance.min()))
    summary_path = folder / "flight" / "summary.json"
    s = json.loads(summary_path.read_text()) if summary_path.exists() else {}
    if keep_dir is not None:  # the flight's own records, to look at where an error came from
        # (the plan and its flight/ in plan/, SITL's logs in instanceN/: python -m sitl.truth)
        shutil.copytree(folder, keep_dir / "plan", dirs_exist_ok=True)
    shutil.rmtree(folder.parent, ignore_errors=True)
    return {"scenario": scenario.stem, "fleet": name, "backend": backend, "plan": plan_for,
            "upload_exit": up.exit_code, "fly_exit": flown.exit_code,
            "tuning_changed": changed,
            "predicted_clearance_m": predicted,
            "flown_clearance_m": s.get("min_clearance_m"),
            "formation_rms_m": s.get("formation_error_rms_legs_m"),
            "formation_worst_m": s.get("formation_error_max_legs_m"),
            "departures": len(s.get("departures") or [])}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--fleet", action="append", choices=list(FLEETS), default=[])
    ap.add_argument("--scenario", action="append", type=Path, default=[])
    ap.add_argument("--speedup", type=float, default=4.0)
    ap.add_argument("--out", type=Path, default=None, help="also write the rows as JSON")
    ap.add_argument("--no-keeper", action="store_true",
                    help="fly without the formation keeper (fly --no-keeper): how the "
                    "copters drift apart on their own")
    ap.add_argument("--keep", type=Path, default=None,
                    help="keep each flight under this folder: its plan folder (records "
                    "included) in NAME/plan, on SITL its copters' logs in NAME/instanceN "
                    "(python -m sitl.truth NAME)")
    args = ap.parse_args()
    rows = []
    print("| scenario | fleet | back end | plan made for | upload / fly exit | tuning written "
          "| clearance predicted / flown | formation RMS / worst | departures |")
    print("|---|---|---|---|---|---|---|---|---|")
    for scenario in args.scenario or SCENARIOS:
        for name in args.fleet or list(FLEETS):
            r = one(scenario, name, args.speedup, args.keep,
                    ("--no-keeper",) if args.no_keeper else ())
            rows.append(r)

            def f(x):
                return "-" if x is None else f"{x:.2f}"

            print(f"| {r['scenario']} | {r['fleet']} | {r['backend']} | {r['plan']} | "
                  f"{r['upload_exit']} / "
                  f"{r['fly_exit']} | {r['tuning_changed']} | {f(r['predicted_clearance_m'])} /"
                  f" {f(r['flown_clearance_m'])} m | {f(r['formation_rms_m'])} / "
                  f"{f(r['formation_worst_m'])} m | {r['departures']} |", flush=True)
    if args.out:
        args.out.write_text(json.dumps(rows, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
