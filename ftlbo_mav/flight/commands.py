"""``ftlbo-mav fly``, ``monitor`` and ``abort``: parse options, call the library, print.

Kept whole: one concept, the flight's three commands and the options they share; most of
its lines are click option declarations. The report they leave is :mod:`.report`.

Registered on the main group at the end of :mod:`ftlbo_mav.cli`.
"""

from __future__ import annotations

import contextlib
import sys
from dataclasses import replace
from pathlib import Path

import click

from .. import clock
from ..cli_errors import user_errors
from ..cli_types import LINK_URL, PORT, SYSIDS, FiniteFloat
from ..errors import BadInput, FtlboError
from ..link.addresses import default_urls_for, parse_sysids
from ..link.commands import _timing, _urls, timing_options
from ..link.signing import load_key
from ..mission.files import check_writable
from .control import DEFAULT_CONTROL_PORT, ControlServer, request_abort
from .departures import DepartureWatch
from .fleet import concurrently
from .fly import Fleet, FlightLeftPlan, FlyOptions, abort, fly, make_keeper
from .keeper import KeeperOptions
from .monitor import LiveView, Monitor
from .planned import PlannedFlight, load_planned_flight
from .policy import FaultPolicy
from .report import summary_lines, write_flight_report
from .resume import PROGRESS_FILE, plan_rest
from .vehicle import FlightAborted, FlightError
from .watch import battery_watch, describe, landing_points, observe, watch_from_outside

_link_options = [
    click.option("--sysid", "sysid_text", required=True, type=SYSIDS,
                 help="Vehicle system ids: a range 1..3 or a list 1,2,5; uav1 is the first."),
    click.option("--connect", "connect", multiple=True, type=LINK_URL,
                 help="pymavlink connection string(s); default: system id s on "
                      "tcp:127.0.0.1:5760 + 10*(s-1), as SITL and `ftlbo-mav sim` listen."),
]


def link_options(func):
    for option in reversed(_link_options):
        func = option(func)
    return func


def _fleet_args(planned: PlannedFlight | None, sysid_text: str, connect) -> tuple:
    sysids = parse_sysids(sysid_text)
    if planned is not None and planned.count != len(sysids):
        raise BadInput(f"{planned.folder} plans {planned.count} UAVs but --sysid {sysid_text} "
                       f"names {len(sysids)} vehicles")
    names = list(planned.names) if planned else [f"uav{i + 1}" for i in range(len(sysids))]
    return names, sysids, _urls(connect) or default_urls_for(sysids)


def _control(port: int, fleet: Fleet):
    """The control endpoint of a flight (flight/control.py); ``port`` 0 turns it off."""
    if not port:
        return contextlib.nullcontext()

    def on_abort(mode: str, sysids) -> tuple[dict, list]:
        wanted = [v for v in fleet.vehicles if sysids is None or v.sysid in sysids]
        held = {v.sysid for v in fleet.vehicles}
        late = set(abort(wanted, mode=mode))
        results = {v.sysid: mode if v.name not in late else "NOT CONFIRMED" if v.link_up
                   else "NOT REACHED (link down)" for v in wanted}
        return results, [s for s in (sysids or []) if s not in held]

    return ControlServer(on_abort, port=port)


def _forwarding(url: str | None, fleet: Fleet):
    if not url:
        return contextlib.nullcontext()
    from .forward import Forwarder

    return Forwarder(url, fleet.links, {v.sysid: v.link for v in fleet.vehicles})


def _rtcm(source: str | None, fleet: Fleet):
    """RTK corrections from ``--rtcm`` to every link of the flight (link/rtcm.py)."""
    if not source:
        return contextlib.nullcontext()
    from ..link.rtcm import RtcmForwarder, frames_from, parse_source

    return RtcmForwarder(frames_from(parse_source(source)), fleet.links)


def _check_rtcm(source: str | None) -> None:
    """A bad ``--rtcm`` string is a BadInput (exit 2) before any link is opened."""
    if source:
        from ..link.rtcm import parse_source

        parse_source(source)


def _rtcm_line(rtcm) -> str | None:
    if rtcm is None:
        return None
    line = (f"RTCM corrections: {rtcm.frames} frames, {rtcm.bytes} bytes, "
            f"{rtcm.bytes_per_s():.0f} bytes/s to every copter")
    if rtcm.dropped:
        line += f"; {rtcm.dropped} frames longer than 720 bytes dropped"
    if rtcm.error:
        line += f"; the source stopped: {rtcm.error}"
    return line


_rtcm_option = click.option(
    "--rtcm", "rtcm_source", default=None,
    help="RTK corrections for every copter (GPS_RTCM_DATA): a serial port, "
         "tcp://host:port or ntrip://user:pass@host:port/MOUNTPOINT.")


def _print_summary(summary: dict, out_dir: Path) -> None:
    for line in summary_lines(summary, out_dir):
        click.echo(line)


@click.command(name="fly")
@click.argument("plan_dir", type=click.Path(exists=True, file_okay=False, path_type=Path))
@link_options
@click.option("--forward", type=LINK_URL,
              help="Relay everything to a ground station, e.g. udpout:127.0.0.1:14550.")
@click.option("--log-dir", type=click.Path(file_okay=False, path_type=Path),
              help="Where the flight log and report go (default PLAN_DIR/flight).")
@click.option("--abort-mode", type=click.Choice(["RTL", "LAND"]), default="RTL",
              show_default=True, help="Where Ctrl-C sends every vehicle.")
@click.option("--control-port", type=PORT, default=DEFAULT_CONTROL_PORT,
              show_default=True,
              help="127.0.0.1 port where `ftlbo-mav abort` reaches this flight (0: none).")
@click.option("--on-departure", "on_departure",
              type=click.Choice([p.value for p in FaultPolicy]), default="rally",
              show_default=True,
              help="When one vehicle leaves the plan (link lost, a mode or failsafe it was "
                   "not asked for, no progress): the others stop, then fly home together on "
                   "routes planned then and land there, or RTL to their rally points where "
                   "no route exists (rally), or land where they are (land), or carry on "
                   "(continue). The one that left is never commanded against its choice.")
@click.option("--lost-wait", type=FiniteFloat(0, 50), default=15.0, show_default=True,
              help="Seconds a vehicle whose link is lost is waited for (it may fly on and "
                   "come back) before it is reported gone and the flight ends.")
@click.option("--keeper/--no-keeper", "use_keeper", default=True, show_default=True,
              help="Hold the formation in flight: leaders wait (short pauses), laggards "
                   "catch up (a faster next leg); see docs/flight.md.")
@click.option("--arm-budget", type=FiniteFloat(0, 86_400), default=60.0, show_default=True,
              help="Seconds to keep retrying a refused arm (EKF still converging).")
@click.option("--formation-bound", type=FiniteFloat(0.01, 1000), default=None,
              help="Metres a copter may be from its slot before the flight counts it a "
                   "departure, for this flight (default: the plan's formation_bound; more "
                   "than the plan's gives up what that bound keeps: separation).")
@click.option("--preflight-timeout", type=FiniteFloat(0, 86_400),
              default=60.0, show_default=True,
              help="Seconds to wait for a 3D GPS fix and passing pre-arm checks.")
@click.option("--flight-timeout", type=FiniteFloat(1, 86_400), default=900.0,
              show_default=True, help="Abort if the missions have not ended by then.")
@click.option("--any-firmware", "any_firmware", is_flag=True,
              help="Fly a vehicle whose AUTOPILOT_VERSION is not ArduCopter 4.5.x or 4.6.x (the "
                   "firmware the planner's flight model follows), saying what is then not "
                   "promised. Without it pre-flight refuses it.")
@click.option("--any-params", "any_params", is_flag=True,
              help="Fly copters whose own values (read before arming) lose a promise of the "
                   "plan, saying which: that promise is then not kept. Without it pre-flight "
                   "refuses them.")
@click.option("--link", "link_text", default=None,
              help="The link every copter shares: bytes a second for both ways together "
                   "(6000) or a radio (sik-64, sik-128, sik-250, wifi). Says what the flight "
                   "asks of it, chooses the stream rates that fit, refuses a swarm that "
                   "cannot (docs/link.md).")
@click.option("--resume", is_flag=True,
              help="Carry on after a flight of PLAN_DIR that ended early: plan the rest from "
                   "the first point not yet flown (lanes and photos neither skipped nor "
                   "taken twice) into PLAN_DIR/resume, upload it, verified, and fly it "
                   "(log in PLAN_DIR/resume/flight).")
@click.option("--progress", "progress_file", type=click.Path(dir_okay=False, path_type=Path),
              help="With --resume: the progress.json of the flight to carry on from "
                   "(default PLAN_DIR/flight/progress.json, the last flight's).")
@click.option("--report-png/--no-report-png", "report_png", default=True, show_default=True,
              help="Draw report.png at the end (flight.csv and summary.json are always "
                   "written).")
@timing_options
@_rtcm_option
@user_errors
def fly_command(plan_dir, sysid_text, connect, forward, log_dir, abort_mode, control_port,
                on_departure, lost_wait, use_keeper, arm_budget, formation_bound,
                preflight_timeout, flight_timeout,
                any_firmware, any_params, link_text, resume, progress_file, report_png,
                timeout, retries, ready_timeout, discover_timeout, signing_key, rtcm_source):
    """Fly PLAN_DIR's missions: check, take off, start together, watch, report.

    The vehicles must hold the plan's missions (`ftlbo-mav upload` first); nothing is
    armed unless every vehicle passes the pre-flight checks. Ctrl-C sends every vehicle
    to RTL (or --abort-mode LAND); so does `ftlbo-mav abort` from another terminal,
    through the control endpoint on 127.0.0.1:--control-port.

    Every flight writes how far each UAV got along its plan (progress.json beside the
    log); after an early end (a vehicle lost, a battery, an abort), --resume carries on
    from there with a fresh battery.
    """
    planned = load_planned_flight(plan_dir)
    names, sysids, urls = _fleet_args(planned, sysid_text, connect)
    _check_rtcm(rtcm_source)
    key = load_key(signing_key) if signing_key else None
    if progress_file is not None and not resume:
        raise BadInput("--progress names the flight to resume: give it with --resume")
    told, budget = _link_budget(link_text, len(sysids), signed=key is not None)
    if resume:
        planned = _resume(planned, progress_file or plan_dir / "flight" / PROGRESS_FILE,
                          sysids, urls, any_firmware=any_firmware, any_params=any_params,
                          signing_key=key,
                          timing=_timing(timeout, retries, ready_timeout),
                          discover_timeout_s=discover_timeout)
        plan_dir = planned.folder
    if formation_bound is not None:
        planned = replace(planned, formation_bound_m=formation_bound)
    monitor = Monitor(planned)
    options = FlyOptions(ready_timeout_s=preflight_timeout, arm_budget_s=arm_budget,
                         flight_timeout_s=flight_timeout, abort_mode=abort_mode,
                         keeper=KeeperOptions(enabled=use_keeper),
                         policy=FaultPolicy(on_departure), lost_wait_s=lost_wait,
                         any_firmware=any_firmware, any_params=any_params)
    keeper = make_keeper(planned, options.keeper)
    out_dir = log_dir or plan_dir / "flight"
    check_writable(out_dir)  # before any vehicle: a flight's record is not lost at its end
    monitor.link_bytes_per_s = told[0] if told else None
    click.echo(f"link: {budget.describe(told[0] if told else None)}"
               + (f" ({told[1]})" if told else ""), err=True)
    with Fleet(names, sysids, urls, signing_key=key, discover_timeout_s=discover_timeout,
               on_position=monitor, on_photo=monitor.photo, position_hz=budget.position_hz,
               status_hz=budget.status_hz) as fleet, \
            _forwarding(forward, fleet), \
            _control(control_port, fleet), _rtcm(rtcm_source, fleet) as rtcm:
        monitor.vehicles = fleet.vehicles
        if rtcm is not None:
            click.echo(f"RTCM corrections from {rtcm_source} to {len(fleet.links)} link(s)")
        view = LiveView(monitor, sys.stderr)
        events: list[str] = []

        def report(**extra) -> dict:
            return write_flight_report(planned, monitor, out_dir, sysids, keeper=keeper,
                                       events=events, rtcm=rtcm, progress=True,
                                       budget=budget, told=told, png=report_png, **extra)

        try:
            fly(planned, fleet.vehicles, options=options,
                timing=_timing(timeout, retries, ready_timeout), say=view.message,
                tick=view.update, keeper=keeper, on_event=events.append)
            view.update(force=True)
        except KeyboardInterrupt:
            _print_summary(report(), out_dir)
            sys.exit(130)
        except FlightAborted as exc:
            summary = report()
            click.echo(f"flight aborted: every vehicle sent to {exc.mode}")
            _print_summary(summary, out_dir)
            sys.exit(1)
        except FlightLeftPlan as exc:
            summary = report(outcome=exc.lines)
            click.echo("the flight left its plan:")
            for line in exc.lines:
                click.echo(f"  {line}")
            _print_summary(summary, out_dir)
            sys.exit(1)
        except FlightError as exc:
            summary = report(outcome=[str(exc)])
            click.echo(f"error: {exc}")
            _print_summary(summary, out_dir)
            sys.exit(1)
    summary = report()
    click.echo("all vehicles finished their missions")
    _print_summary(summary, out_dir)


def _link_budget(text: str | None, copters: int, *, signed: bool, wanted_hz: float = 10.0):
    """``(told, budget)`` of ``--link``: the link (bytes a second, name) or None, and the
    flight's budget at the rates that fit it (:func:`~ftlbo_mav.link.budget.choose`;
    without ``--link``, the default rates); :class:`BadInput` when the swarm cannot fit."""
    from ..link.budget import choose, flight_budget, parse_link

    if text is None:
        return None, flight_budget(copters, wanted_hz, signed=signed)
    told = parse_link(text)
    return told, choose(copters, told[0], wanted_hz=wanted_hz, signed=signed)


def _resume(planned: PlannedFlight, progress_file: Path, sysids: list[int], urls, *,
            any_firmware: bool, signing_key, timing, discover_timeout_s: float,
            any_params: bool = False
            ) -> PlannedFlight:
    """``fly --resume`` before the flight: the rest planned and written
    (:func:`~ftlbo_mav.flight.resume.plan_rest`), uploaded to every vehicle and verified;
    the rest's plan folder as the flight to fly. Exits 0 when nothing is left to fly, 1
    when a vehicle did not take its mission."""
    from ..link.commands import upload_folder
    from ..planning.resume import NothingToResume

    click.echo(f"resuming from {progress_file}: planning the rest", err=True)
    try:
        rest = plan_rest(planned, progress_file)
    except NothingToResume as exc:
        click.echo(str(exc))
        sys.exit(0)
    flown_to = ", ".join(f"{n} {p:.2f}" for n, p in zip(planned.names, rest.progress))
    click.echo(f"the flight before got to path points {flown_to} of "
               f"{planned.paths.shape[1] - 1}; resuming at {rest.at.describe(rest.plan)}")
    click.echo(f"the rest planned in {rest.folder} ({rest.plan.waypoint_count} points, "
               f"{rest.plan.seconds:.2f} s); uploading it")
    results = upload_folder(rest.folder, sysids, urls, any_firmware=any_firmware,
                            any_params=any_params,
                            timing=timing, discover_timeout_s=discover_timeout_s,
                            signing_key=signing_key)
    for r in results:
        click.echo(f"{r.name} -> sysid {r.sysid}: "
                   + (r.message if r.verified else f"FAILED: {r.message}"))
    if not all(r.verified for r in results):
        click.echo("not flown: every vehicle must hold the rest of the plan", err=True)
        sys.exit(1)
    return load_planned_flight(rest.folder)


@click.command()
@click.argument("plan_dir", required=False,
                type=click.Path(exists=True, file_okay=False, path_type=Path))
@link_options
@click.option("--forward", type=LINK_URL,
              help="Relay everything to a ground station, e.g. udpout:127.0.0.1:14550.")
@click.option("--duration", type=FiniteFloat(0.1, 86_400), default=None,
              help="Stop after this many seconds (default: until Ctrl-C, or until every "
                   "vehicle has landed after flying).")
@click.option("--log-dir", type=click.Path(file_okay=False, path_type=Path),
              help="Where the flight log and report go (default PLAN_DIR/monitor).")
@click.option("--rate", type=FiniteFloat(1, 1000), default=10.0, show_default=True,
              help="Position reports per second requested from each vehicle.")
@click.option("--discover-timeout", type=FiniteFloat(0.1, 86_400), default=5.0,
              show_default=True, help="Seconds to wait for each vehicle's HEARTBEAT.")
@click.option("--signing-key", type=click.Path(dir_okay=False),
              help="MAVLink 2 signing key file (64 hex digits, or a passphrase).")
@click.option("--link", "link_text", default=None,
              help="The link every copter shares (bytes a second, or sik-64, sik-128, "
                   "sik-250, wifi): says what watching asks of it and lowers --rate to fit.")
@_rtcm_option
@user_errors
def monitor(plan_dir, sysid_text, connect, forward, duration, log_dir, rate, discover_timeout,
            signing_key, link_text, rtcm_source):
    """Live view of the vehicles; with PLAN_DIR also formation error, separation and
    clearance, and a flight log and report at the end."""
    planned = load_planned_flight(plan_dir) if plan_dir else None
    names, sysids, urls = _fleet_args(planned, sysid_text, connect)
    _check_rtcm(rtcm_source)
    key = load_key(signing_key) if signing_key else None
    watch = Monitor(planned)
    told, budget = _link_budget(link_text, len(sysids), signed=key is not None,
                                wanted_hz=rate)
    if told is not None:
        watch.link_bytes_per_s = told[0]
        click.echo(f"link: {budget.describe(told[0])} ({told[1]})", err=True)
    if planned is not None:
        check_writable(log_dir or plan_dir / "monitor")
    with Fleet(names, sysids, urls, signing_key=key, discover_timeout_s=discover_timeout,
               on_position=watch, on_photo=watch.photo,
               position_hz=budget.position_hz if told else rate,
               status_hz=budget.status_hz) as fleet, _forwarding(forward, fleet), \
            _rtcm(rtcm_source, fleet) as rtcm:
        watch.vehicles = fleet.vehicles
        if rtcm is not None:
            click.echo(f"RTCM corrections from {rtcm_source} to {len(fleet.links)} link(s)")
        view = LiveView(watch, sys.stderr)
        departures = DepartureWatch(len(sysids),
                                    landing=landing_points(planned) if planned else None,
                                    navigation=planned.navigation if planned else None,
                                    battery=battery_watch(planned))
        events: list[str] = []
        end = clock.monotonic() + duration if duration else float("inf")
        flew = set()
        try:
            while clock.monotonic() < end:
                flew |= {v.sysid for v in fleet.vehicles if v.status.armed}
                if flew and len(flew) == len(sysids) and not any(
                        v.status.armed for v in fleet.vehicles):
                    break  # every vehicle flew and has landed
                watch_from_outside(departures, fleet.vehicles, planned)
                seen = [observe(v, planned) for v in fleet.vehicles]
                for e in departures.check(seen, clock.monotonic()):
                    events.append(describe(e, fleet.vehicles))
                    view.message(events[-1])
                view.update()
                clock.sleep(0.1)
        except KeyboardInterrupt:
            pass
        view.update(force=True)
    if _rtcm_line(rtcm):
        click.echo(_rtcm_line(rtcm))
    departed = [e for e in departures.events if e.departure]
    if departed:
        click.echo(f"{len(departed)} departure(s) from the plan:")
        for line in events:
            click.echo(f"  {line}")
    if planned is not None:
        out_dir = log_dir or plan_dir / "monitor"
        _print_summary(write_flight_report(planned, watch, out_dir, sysids, events=events,
                                           rtcm=rtcm, budget=budget if told else None,
                                           told=told), out_dir)
    if departed:
        sys.exit(1)


def _abort_directly(rest, mode: str, key, discover_timeout: float) -> dict[int, str]:
    """Abort over links of our own, one link at a time for all its vehicles, every link
    at once: a link that cannot be opened, or a vehicle not heard, is its own line."""
    by_url: dict[str, list] = {}
    for n, s, u in rest:
        by_url.setdefault(u, []).append((n, s))

    def one_link(item) -> dict[int, str]:
        url, members = item
        try:
            with Fleet([n for n, _ in members], [s for _, s in members], [url] * len(members),
                       signing_key=key, discover_timeout_s=discover_timeout,
                       position_hz=1.0) as fleet:
                late = set(abort(fleet.vehicles, mode=mode))
        except FtlboError as exc:
            return {s: f"NOT REACHED ({exc})" for _, s in members}
        return {s: "NOT CONFIRMED" if n in late else mode for n, s in members}

    out: dict[int, str] = {}
    for part in concurrently(one_link, list(by_url.items())):
        out.update(part)
    return out


@click.command(name="abort")
@link_options
@click.option("--land", is_flag=True, help="LAND where they are instead of RTL.")
@click.option("--control-port", type=PORT, default=DEFAULT_CONTROL_PORT,
              show_default=True,
              help="Reach a running `ftlbo-mav fly` here first (0: open links directly).")
@click.option("--discover-timeout", type=FiniteFloat(0.1, 86_400), default=1.5,
              show_default=True,
              help="Seconds to wait for each vehicle's link and HEARTBEAT (ArduPilot "
                   "sends one a second); one that does not answer is named, not waited for.")
@click.option("--signing-key", type=click.Path(dir_okay=False),
              help="MAVLink 2 signing key file (64 hex digits, or a passphrase).")
@user_errors
def abort_command(sysid_text, connect, land, control_port, discover_timeout, signing_key):
    """Send every vehicle to RTL (or LAND) at once and confirm the switch.

    While `ftlbo-mav fly` runs it holds the vehicles' links (SITL's TCP ports take one
    client), so the abort goes through its control endpoint; vehicles no flight holds
    are reached on their own links.
    """
    names, sysids, urls = _fleet_args(None, sysid_text, connect)
    mode = "LAND" if land else "RTL"
    results: dict[int, str] = {}
    reply = request_abort(mode, sysids, port=control_port) if control_port else None
    if reply is not None:
        results, _unknown = reply
        click.echo(f"through the running flight (127.0.0.1:{control_port})", err=True)
    rest = [(n, s, u) for n, s, u in zip(names, sysids, urls) if s not in results]
    if rest:
        key = load_key(signing_key) if signing_key else None
        results.update(_abort_directly(rest, mode, key, discover_timeout))
    for s in sysids:
        click.echo(f"sysid {s}: {results[s]}")
    if any(results[s] != mode for s in sysids):
        sys.exit(1)
