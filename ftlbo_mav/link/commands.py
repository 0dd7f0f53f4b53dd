"""``ftlbo-mav upload`` and ``download``: parse options, call the library, print.

Registered on the main group in :mod:`ftlbo_mav.cli` (the emulator's ``sim`` command is
:mod:`ftlbo_mav.sim.commands`).
"""

from __future__ import annotations

import os
import re
import sys
import threading
from dataclasses import replace
from pathlib import Path

import click

from ..ardupilot.copters import FLIGHT_PARAMS
from ..cli_errors import user_errors
from ..cli_types import LINK_URL, SYSIDS, FiniteFloat
from ..errors import BadInput, MissionFileError
from ..mission.fence_files import read_fence_set, write_fence_set
from ..mission.params_file import write_params
from ..mission.plan_reader import check_plan_folder, read_plan_json
from ..mission.waypoints import read_waypoints, write_waypoints
from .addresses import default_urls_for, parse_sysids
from .codec import storage_warnings
from .discovery import describe_missing, discover
from .endpoints import LinkError, open_links
from .geofence import download_fence_set
from .mission_protocol import Timing, download_mission
from .params import read_params
from .signing import load_key
from .swarm import Assignment, ProgressEvent, upload_swarm


def _urls(values: tuple[str, ...]) -> list[str]:
    """``--connect`` values; one value may also hold several, separated by spaces."""
    return [u for v in values for u in v.split()]


def _check_output_file(path: Path) -> None:
    """:class:`BadInput` when ``path`` cannot be a file written here: it is a folder, a
    device or a FIFO, or its folder is missing or a file."""
    if path.exists() and not path.is_file():
        raise BadInput(f"{path}: not a regular file (a folder, a device or a FIFO); give a "
                       ".waypoints file to write; no vehicle was contacted")
    parent = path.parent
    if not parent.is_dir():
        raise BadInput(f"{path}: its folder {parent} does not exist; no vehicle was contacted")
    if not os.access(parent, os.W_OK):
        raise BadInput(f"{path}: its folder {parent} is not writable; no vehicle was "
                       "contacted")


def _timing(timeout: float, retries: int, ready_timeout: float) -> Timing:
    return Timing(timeout_s=timeout, retries=retries, not_ready_s=ready_timeout)


def mission_files(folder: Path) -> list[Path]:
    """``uav1.waypoints``, ``uav2.waypoints``, ... in UAV order; gaps are an error, and so
    is a ``uav0.waypoints`` (or ``uav01``): the numbers start at 1, one per ``--sysid``.

    A folder with a ``plan.json`` must hold exactly the mission files it was written with
    (:func:`~ftlbo_mav.mission.plan_reader.check_plan_folder`): never a mix of two plans."""
    if (folder / "plan.json").exists():
        doc, source = read_plan_json(folder)
        return check_plan_folder(folder, doc, source=source)
    found = {}
    for p in sorted(folder.glob("uav*.waypoints")):
        m = re.fullmatch(r"uav(\d+)\.waypoints", p.name)
        if not m:
            continue
        if m.group(1).startswith("0"):  # uav0, and uav01 that would stand in for uav1
            raise BadInput(f"{p}: not a mission file name: UAV numbers start at 1 and have "
                           "no leading zeros (uav1.waypoints goes to the first --sysid); "
                           "rename or remove it; no vehicle was contacted")
        found[int(m.group(1))] = p
    if not found:
        raise BadInput(f"{folder}: no uavN.waypoints files (write them with `ftlbo-mav plan`)")
    numbers = sorted(found)
    if numbers != list(range(1, len(numbers) + 1)):
        missing = min(set(range(1, numbers[-1] + 1)) - set(numbers))
        raise BadInput(f"{folder}: uav{missing}.waypoints is missing (found "
                       f"{', '.join(found[n].name for n in numbers)})")
    return [found[n] for n in numbers]


def plan_fleet(folder: Path):
    """The plan of ``folder`` as the flight side reads it
    (:class:`~ftlbo_mav.flight.planned.PlannedFlight`: each UAV's copter, its paths and
    promises), or None without a plan.json."""
    if not (folder / "plan.json").exists():
        return None
    from ..flight.planned import PlanFolderError, load_planned_flight

    try:
        return load_planned_flight(folder)
    except PlanFolderError as exc:
        raise BadInput(f"{exc}; no vehicle was contacted") from None


class ProgressBoard:
    """One line per vehicle on stderr: redrawn in place on a terminal, else a line per step."""

    def __init__(self, names: list[tuple[str, int]], *, stream=None):
        self.stream = stream or sys.stderr
        self.tty = self.stream.isatty()
        self.order = [sysid for _, sysid in names]
        self.lines = {sysid: f"{name} -> sysid {sysid}: waiting" for name, sysid in names}
        self.names = {sysid: name for name, sysid in names}
        self.last_step: dict[int, str] = {}
        self.lock = threading.Lock()
        if self.tty:
            self.stream.write("\n".join(self.lines[s] for s in self.order) + "\n")

    def __call__(self, e: ProgressEvent) -> None:
        if e.step.split()[-1] in ("upload", "read-back") and e.total:
            bar = "#" * int(20 * e.done / e.total)
            text = f"{e.step:9s} [{bar:20s}] {e.done}/{e.total}"
        elif e.step in ("verified", "failed"):
            text = "verified" if e.step == "verified" else "FAILED"
        else:
            text = {"discover": "waiting for HEARTBEAT", "clear": "clearing"}.get(e.step, e.step)
        with self.lock:
            self.lines[e.sysid] = f"{self.names[e.sysid]} -> sysid {e.sysid}: {text}"
            if self.tty:
                up = len(self.order)
                body = "".join(f"\x1b[2K{self.lines[s]}\n" for s in self.order)
                self.stream.write(f"\x1b[{up}F{body}")
                self.stream.flush()
            elif self.last_step.get(e.sysid) != e.step:
                self.last_step[e.sysid] = e.step
                self.stream.write(self.lines[e.sysid] + "\n")
                self.stream.flush()


_timing_options = [
    click.option("--timeout", type=FiniteFloat(0.05, 3600), default=1.5, show_default=True,
                 help="Seconds without an answer before a message is resent."),
    click.option("--retries", type=click.IntRange(0, 1000), default=5, show_default=True,
                 help="Resends of one step before it fails."),
    click.option("--ready-timeout", type=FiniteFloat(0, 86_400), default=15.0,
                 show_default=True,
                 help="Seconds a booting (NO_SPACE) or busy (DENIED) vehicle is waited for."),
    click.option("--discover-timeout", type=FiniteFloat(0.1, 86_400), default=5.0,
                 show_default=True, help="Seconds to wait for each vehicle's HEARTBEAT."),
    click.option("--signing-key", type=click.Path(dir_okay=False),
                 help="MAVLink 2 signing key file (64 hex digits, or a passphrase)."),
]


def timing_options(func):
    for option in reversed(_timing_options):
        func = option(func)
    return func


@click.command()
@click.argument("mission_dir", type=click.Path(exists=True, file_okay=False, path_type=Path))
@click.option("--sysid", "sysid_text", required=True, type=SYSIDS,
              help="Vehicle system ids: a range 1..3 or a list 1,2,5; uav1 goes to the first.")
@click.option("--connect", "connect", multiple=True, type=LINK_URL,
              help="pymavlink connection string; repeat it (or give several separated by "
                   "spaces) for one link per vehicle. Default: system id s on "
                   "tcp:127.0.0.1:5760 + 10*(s-1), where SITL and `ftlbo-mav sim` listen.")
@click.option("--capacity", type=click.IntRange(1, 65535), default=None,
              help="Mission items the vehicles hold (ArduCopter SITL: 650): longer missions "
                   "are refused before anything is sent. Without it the vehicle's own "
                   "NO_SPACE answer refuses them, also before any item is sent.")
@click.option("--no-fence", "no_fence", is_flag=True,
              help="Send only the missions: no fence, rally points or fence parameters.")
@click.option("--no-vehicle-params", "no_vehicle_params", is_flag=True,
              help="Set no parameter at all, not even the navigation values the scenario "
                   "names (a copter's tuning is never written). The plan is still "
                   "predicted again with each copter's own values.")
@click.option("--any-firmware", "any_firmware", is_flag=True,
              help="Upload to a vehicle whose AUTOPILOT_VERSION is not ArduCopter 4.5.x or "
                   "4.6.x (the firmware the planner's flight model follows), saying what is not "
                   "then promised. Without it such a swarm is refused before anything is sent.")
@click.option("--any-params", "any_params", is_flag=True,
              help="Upload to copters whose own values lose a promise of the plan, saying "
                   "which: that promise is then not kept. Without it nothing is sent.")
@timing_options
@user_errors
def upload(mission_dir, sysid_text, connect, capacity, no_fence, no_vehicle_params,
           any_firmware, any_params, timeout, retries, ready_timeout, discover_timeout,
           signing_key):
    """Upload MISSION_DIR/uavN.waypoints to the vehicles, read each back and verify it.

    With uavN.fence (and uavN.rally, fence.parm) beside it, each vehicle also gets its
    fence, rally points and fence parameters, each read back and verified. With a
    plan.json, each vehicle's firmware and flight parameters are read first: where they
    are not those the plan was predicted with, the flight is predicted again with the
    copters' own values and the upload goes on only when every promise still holds
    (saying so), else nothing is sent. A copter's tuning (PSC_*, ATC_*, ANGLE_MAX, ...) is
    never written; the navigation values the scenario names ([vehicle] WPNAV_SPEED, ...)
    are, and the upload says which before it sends anything. Exits 0 only when every
    vehicle holds exactly what its files say.
    """
    sysids = parse_sysids(sysid_text)
    key = load_key(signing_key) if signing_key else None
    results = upload_folder(mission_dir, sysids, _urls(connect) or default_urls_for(sysids),
                            capacity=capacity, no_fence=no_fence,
                            no_vehicle_params=no_vehicle_params, any_firmware=any_firmware,
                            any_params=any_params,
                            timing=_timing(timeout, retries, ready_timeout),
                            discover_timeout_s=discover_timeout, signing_key=key,
                            sysid_text=sysid_text)
    for r in results:
        status = r.message if r.verified else f"FAILED: {r.message}"
        click.echo(f"{r.name} -> sysid {r.sysid}: {status}")
    ok = sum(r.verified for r in results)
    click.echo(f"{ok}/{len(results)} vehicles verified")
    if ok != len(results):
        sys.exit(1)


def upload_folder(mission_dir: Path, sysids: list[int], urls: list[str], *,
                  capacity: int | None = None, no_fence: bool = False,
                  no_vehicle_params: bool = False, any_firmware: bool = False,
                  any_params: bool = False,
                  timing: Timing, discover_timeout_s: float, signing_key: bytes | None,
                  sysid_text: str = "") -> list:
    """What ``upload`` does, for ``fly --resume`` too: every file of ``mission_dir`` read
    and checked before any vehicle is contacted (:class:`BadInput`), notes and progress on
    stderr, then every vehicle uploaded and verified at once (:func:`upload_swarm`).
    Returns the results in vehicle order."""
    files = mission_files(mission_dir)
    if len(files) != len(sysids):
        raise BadInput(f"{mission_dir} holds {len(files)} missions (uav1..uav{len(files)}) but "
                       f"--sysid {sysid_text or len(sysids)} names {len(sysids)} vehicles")
    try:  # every file is read before any vehicle is touched
        missions = [tuple(read_waypoints(f)) for f in files]
        fences = [None if no_fence else read_fence_set(mission_dir, f.stem) for f in files]
    except MissionFileError as exc:
        raise BadInput(f"{exc}; no vehicle was contacted") from None
    planned = plan_fleet(mission_dir)
    copters = planned.fleet() if planned is not None else (None,) * len(files)
    if capacity is not None:
        for f, m in zip(files, missions):
            if len(m) > capacity:
                raise BadInput(f"{f}: {f.name} has {len(m)} items, more than --capacity "
                               f"{capacity}; no vehicle was contacted")
    assignments = [Assignment(f.stem, s, m, fence,
                              {} if c is None or no_vehicle_params else c.to_set(), c)
                   for f, s, m, fence, c in zip(files, sysids, missions, fences, copters)]
    fit = None
    if planned is not None:
        from ..flight.fit import fit_fleet

        labels = [f"{a.name} (sysid {a.sysid})" for a in assignments]

        def fit(actual):
            return fit_fleet(planned, actual, labels)
    if not no_fence and all(fence is None for fence in fences):
        click.echo(f"note: {mission_dir} has no uavN.fence files: missions only (plan "
                   "writes them; --no-fence says so on purpose)", err=True)
    for a in assignments:  # what ArduCopter will not keep, said before anything is sent
        for line in storage_warnings(a.items):
            click.echo(f"note: {a.name}: {line} (ArduCopter keeps only this; the "
                       "read-back is verified against it)", err=True)
    board = ProgressBoard([(a.name, a.sysid) for a in assignments])
    return upload_swarm(assignments, urls, signing_key=signing_key, timing=timing,
                        discover_timeout_s=discover_timeout_s, on_progress=board,
                        any_firmware=any_firmware, fit=fit, any_params=any_params,
                        on_note=lambda text: click.echo(f"note: {text}", err=True),
                        on_warning=lambda name, sysid, text: click.echo(
                            f"warning: {name} (sysid {sysid}): {text}", err=True))


@click.command()
@click.option("--sysid", type=click.IntRange(1, 254), required=True,
              help="The vehicle's system id.")
@click.option("--connect", type=LINK_URL,
              help="pymavlink connection string (default: tcp:127.0.0.1:5760 + 10*(sysid-1)).")
@click.option("-o", "--output", required=True, type=click.Path(dir_okay=False, path_type=Path),
              help="The .waypoints file to write.")
@click.option("--no-fence", "no_fence", is_flag=True,
              help="Only the mission: no .fence, .rally and .parm beside it.")
@timing_options
@user_errors
def download(sysid, connect, output, no_fence, timeout, retries, ready_timeout,
             discover_timeout, signing_key):
    """Save the mission a vehicle holds as a Mission Planner .waypoints file, and its
    fence, rally points and fence parameters beside it (.fence, .rally, .parm)."""
    key = load_key(signing_key) if signing_key else None
    _check_output_file(output)  # before the vehicle: a download with nowhere to go is lost
    url = connect or default_urls_for([sysid])[0]
    links = open_links([url], signing_key=key, connect_timeout_s=discover_timeout)
    try:
        found, missing = discover(links, [sysid], timeout_s=discover_timeout)
        if missing:
            raise LinkError(describe_missing(sysid, links, discover_timeout))
        timing = _timing(timeout, retries, ready_timeout)
        with found[sysid].channel(sysid) as channel:
            items = download_mission(channel, timing=timing)
            fence_set = None if no_fence else download_fence_set(channel, timing=timing)
            flight = {} if no_fence else read_params(channel, FLIGHT_PARAMS, timing=timing)
    finally:
        for link in links:
            link.close()
    write_waypoints(output, items)
    click.echo(f"wrote {output} ({len(items)} items; item 0 is the vehicle's home)")
    if fence_set is not None:
        for path in write_fence_set(output, replace(fence_set, params={})):
            click.echo(f"wrote {path}")
        held = {n: v for n, v in flight.items() if v is not None}
        parm = write_params(output.with_suffix(".parm"), dict(fence_set.params) | held,
                            header=f"# ArduCopter parameters of sysid {sysid}, saved by "
                                   "ftlbo-mav download: the fence's and the flight's (a "
                                   "scenario's [vehicle] params_file reads them)")
        click.echo(f"wrote {parm} ({len(fence_set.params)} fence and {len(held)} flight "
                   "parameters)")
        click.echo(f"fence: {fence_set.describe()}; "
                   + ", ".join(f"{k} {v:g}" for k, v in fence_set.params.items()))
