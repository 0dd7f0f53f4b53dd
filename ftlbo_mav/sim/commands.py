"""``ftlbo-mav sim``: run emulated ArduCopters; parse options, build the emulator, print.

Registered on the main group in :mod:`ftlbo_mav.cli`. The emulator's modules are imported
when the command runs, so the CLI starts as fast as before.
"""

from __future__ import annotations

import socket

import click

from ..ardupilot.storage import SITL_MISSION_CAPACITY
from ..cli_errors import user_errors
from ..cli_types import HOST_PORT, PORT, FiniteFloat
from ..errors import BadInput, FtlboError
from ..link.signing import load_key
from .server import MAX_TIME_SCALE


def resolve_udp_out(host: str, port: int) -> tuple[str, int]:
    """``--udp-out HOST:PORT`` -> the IPv4 address it is sent to, looked up once, before
    anything starts (the shared socket is bound on 127.0.0.1, so IPv4 only). A host that
    does not resolve is a :class:`click.BadParameter` naming it: the emulator would
    otherwise run on and send nothing anywhere."""
    try:
        found = socket.getaddrinfo(host, port, socket.AF_INET, socket.SOCK_DGRAM)
    except (socket.gaierror, UnicodeError) as exc:
        why = getattr(exc, "strerror", None) or str(exc)
        raise click.BadParameter(f"{host}:{port}: the host {host!r} does not resolve to an "
                                 f"IPv4 address ({why}); give an IPv4 address or a name "
                                 "this machine resolves", param_hint="'--udp-out'") from None
    return found[0][4][0], port


def _per_vehicle(texts, n: int, option: str) -> list[str | None]:
    """``[SYSID=]VALUE`` options: one value per vehicle (None: not given); one without a
    SYSID is every vehicle's, one with it that vehicle's."""
    out: list[str | None] = [None] * n
    for text in texts:
        sysid, sep, value = text.partition("=")
        if sep and sysid.strip().isdigit():
            i = int(sysid)
            if not 1 <= i <= n:
                raise BadInput(f"{option} {text}: the vehicles are system ids 1..{n}")
            out[i - 1] = value
        else:
            out = [text if o is None or not sep else o for o in out]
    return out


def fleet_options(base, n: int, *, firmware=(), profile=(), params=()) -> list:
    """``base`` (:class:`~.vehicle.VehicleOptions`) for each of ``n`` vehicles with its
    ``--firmware``, ``--profile`` and ``--params``; :class:`BadInput` names a bad one."""
    from dataclasses import replace

    from ..ardupilot.copters import PROFILES, flight_values, read_param_text
    from ..ardupilot.firmware import Firmware
    from ..ardupilot.navigation import Navigation
    from ..inputs import read_user_text

    out = []
    for fw, prof, path in zip(_per_vehicle(firmware, n, "--firmware"),
                              _per_vehicle(profile, n, "--profile"),
                              _per_vehicle(params, n, "--params")):
        o = base
        if fw is not None:
            parts = fw.split(".")
            if len(parts) != 3 or not all(p.isdigit() for p in parts):
                raise BadInput(f"--firmware {fw}: give a version such as 4.6.3")
            o = replace(o, firmware=Firmware(*map(int, parts), 255))
        values: dict[str, float] = {}
        if prof is not None:
            if prof not in PROFILES:
                raise BadInput(f"--profile {prof}: not one of {', '.join(PROFILES)}")
            values |= dict(PROFILES[prof].params)
        if path is not None:
            text = read_user_text(path, error=lambda problem, p=path: BadInput(
                f"--params {p}: {problem}"))
            try:
                values |= flight_values(read_param_text(text, source=path), source=path)
            except ValueError as exc:
                raise BadInput(f"--params {exc}") from None
        if values:
            nav = Navigation().with_params(o.limits.nav.to_params() | values)
            o = replace(o, limits=replace(o.limits, nav=nav))
        out.append(o)
    return out


@click.command()
@click.option("--count", type=click.IntRange(1, 254), default=None,
              help="Number of vehicles (default: the scenario's UAVs, else 3).")
@click.option("--scenario", type=click.Path(dir_okay=False),
              help="Put the homes at each UAV's start position.")
@click.option("--base-port", type=PORT, default=5760, show_default=True,
              help="Vehicle i listens on TCP base-port + 10*i (0: any free ports).")
@click.option("--udp-out", type=HOST_PORT,
              help="Also send every vehicle's traffic to one UDP address (a shared link: "
                   "connect with udpin:HOST:PORT).")
@click.option("--loss", type=FiniteFloat(0, 1), default=0.0, help="Packet loss each way.")
@click.option("--loss-up", type=FiniteFloat(0, 1), default=None,
              help="Loss of packets to the vehicles (overrides --loss).")
@click.option("--loss-down", type=FiniteFloat(0, 1), default=None,
              help="Loss of packets from the vehicles (overrides --loss).")
@click.option("--duplicate", type=FiniteFloat(0, 1), default=0.0,
              help="Fraction of packets duplicated.")
@click.option("--reorder", type=FiniteFloat(0, 1), default=0.0,
              help="Fraction of packets held back behind later ones.")
@click.option("--latency-ms", type=FiniteFloat(0, 60_000), default=0.0, help="One-way delay.")
@click.option("--boot-delay", type=FiniteFloat(0, 86_400), default=0.0,
              help="Seconds after start during which uploads get NO_SPACE (like ArduPilot).")
@click.option("--capacity", type=click.IntRange(0, 65535), default=SITL_MISSION_CAPACITY,
              show_default=True,
              help="Mission items a vehicle can hold.")
@click.option("--silent", "silent", multiple=True, type=click.IntRange(1, 254), metavar="SYSID",
              help="This vehicle says nothing at all (repeatable).")
@click.option("--mute", "mute", multiple=True, type=click.IntRange(1, 254), metavar="SYSID",
              help="This vehicle sends HEARTBEATs but ignores the mission protocol.")
@click.option("--mavlink1", "mavlink1", multiple=True, type=click.IntRange(1, 254),
              metavar="SYSID",
              help="This vehicle's port speaks MAVLink 1 only (SERIALn_PROTOCOL 1).")
@click.option("--signing-key", type=click.Path(dir_okay=False),
              help="Vehicles require MAVLink 2 signing with this key.")
@click.option("--seed", type=click.IntRange(0, 2**63 - 1), default=0,
              help="Seed of the fault decisions.")
@click.option("--arm-delay", type=FiniteFloat(0, 86_400), default=None,
              help="Seconds after start before arming is allowed (the EKF's position "
                   "estimate; ArduCopter SITL: about 42 s). Default: --boot-delay.")
@click.option("--speed", type=FiniteFloat(0.2, 100), default=10.0, show_default=True,
              help="WPNAV_SPEED, m/s: the horizontal speed limit between waypoints "
                   "(ArduCopter's default; short legs stay slower, as on ArduCopter).")
@click.option("--boot-scale", type=FiniteFloat(0, 1000), default=None,
              help="Boot as ArduCopter 4.5.6 SITL was recorded to (ready 2.2 s, home 19.8 s, "
                   "armable 42.1 s), every time multiplied by this (e.g. 0.1). Overrides "
                   "--boot-delay and --arm-delay.")
@click.option("--vary", is_flag=True,
              help="Make each vehicle differ a little, as a real fleet does (a start "
                   "latency of up to 0.3 s, WPNAV_JERK within 5%), seeded by --seed.")
@click.option("--time-scale", type=FiniteFloat(0.01, MAX_TIME_SCALE), default=1.0,
              show_default=True,
              help="Run the vehicles' clock this many times faster than real time (at most "
                   f"{MAX_TIME_SCALE:g}: the emulator steps every 20 ms of its time).")
@click.option("--radio", "radio_text", default=None, metavar="SPEC",
              help="The --udp-out link is one telemetry radio for every vehicle: good (6000 "
                   "B/s both ways, 60+-40 ms, 3 %% lost, 2 KiB buffers), rough (120+-80 ms, "
                   "10 %% lost in bursts, 1 s outage every 15 s), and/or key=value pairs: "
                   "bytes, latency, jitter, loss, burst, buffer, overhead, outage, every.")
@click.option("--firmware", "firmware_text", multiple=True, metavar="[SYSID=]VERSION",
              help="The ArduCopter release the vehicles report and fly as (4.5.6, the "
                   "default, or 4.6.3; another version is reported and flown as the nearest "
                   "modelled one); SYSID= for one vehicle (repeatable).")
@click.option("--profile", "profile_text", multiple=True, metavar="[SYSID=]NAME",
              help="Boot with a board's default parameters (3dr-solo: CubeSolo's "
                   "defaults.parm), as SITL's --defaults does; SYSID= for one vehicle.")
@click.option("--params", "params_text", multiple=True, metavar="[SYSID=]FILE",
              help="Boot with a parameter file's values (.param or .parm; after --profile), "
                   "as SITL's --defaults a.parm,b.parm does; SYSID= for one vehicle.")
@user_errors
def sim(count, scenario, base_port, udp_out, loss, loss_up, loss_down, duplicate, reorder,
        latency_ms, boot_delay, capacity, silent, mute, signing_key, seed, arm_delay, speed,
        boot_scale, vary, time_scale, radio_text, firmware_text, profile_text, params_text,
        mavlink1):
    """Run emulated ArduCopters (system ids 1..N) until Ctrl-C, listening like SITL."""
    from ..ardupilot.commands import RECORDED_BOOT
    from ..scenario import load_scenario
    from .faults import Faults
    from .homes import default_homes, scenario_homes
    from .mission_server import MissionServerOptions
    from .physics import FlightLimits
    from .server import Simulator
    from .vehicle import VehicleOptions

    if udp_out is not None:
        udp_out = resolve_udp_out(*udp_out)
    radio = None
    if radio_text is not None:
        from .radio import parse_radio

        if udp_out is None:
            raise BadInput("--radio is the shared link's: give --udp-out HOST:PORT too")
        try:
            radio = parse_radio(radio_text)
        except ValueError as exc:
            raise BadInput(f"--radio {radio_text!r}: {exc}") from None
    if scenario:
        homes = scenario_homes(load_scenario(scenario))
        if count is not None and count != len(homes):
            raise BadInput(f"--count {count}, but {scenario} has {len(homes)} UAVs")
    else:
        homes = default_homes(count or 3)
    n = len(homes)
    if base_port and base_port + 10 * (n - 1) > 65535:
        raise BadInput(f"--base-port {base_port}: {n} vehicles listen on base-port + 10*i, up "
                       f"to {base_port + 10 * (n - 1)}, beyond 65535 (at most "
                       f"{65535 - 10 * (n - 1)} for {n}; 0: any free ports)")
    for option, ids in (("--silent", silent), ("--mute", mute), ("--mavlink1", mavlink1)):
        if any(s > n for s in ids):
            raise BadInput(f"{option} {max(ids)}: the vehicles are system ids 1..{n}")
    link = {"loss_up": loss if loss_up is None else loss_up,
            "loss_down": loss if loss_down is None else loss_down,
            "duplicate": duplicate, "reorder": reorder, "latency_s": latency_ms / 1000.0}
    faults = [Faults(**link, silent=(i + 1) in silent, mute=(i + 1) in mute,
                     mavlink1=(i + 1) in mavlink1) for i in range(n)]
    options = VehicleOptions(ready_after_s=boot_delay, position_after_s=arm_delay,
                             boot=None if boot_scale is None else RECORDED_BOOT.scaled(boot_scale),
                             limits=FlightLimits.with_speed(speed),
                             mission=MissionServerOptions(capacity=capacity,
                                                          boot_no_space_s=boot_delay))
    options = fleet_options(options, n, firmware=firmware_text, profile=profile_text,
                            params=params_text)
    key = load_key(signing_key) if signing_key else None
    simulator = Simulator(homes=homes, base_port=base_port,
                          udp_out=udp_out, faults=faults,
                          options=options, signing_key=key, seed=seed, time_scale=time_scale,
                          vary=vary, radio=radio)

    def ready() -> None:
        for i, (url, home) in enumerate(zip(simulator.urls, homes)):
            click.echo(f"vehicle sysid {i + 1}: {url}  home {home[0]:.7f}, {home[1]:.7f}, "
                       f"{home[2]:.1f} m")
        if simulator.udp_url:
            click.echo(f"all vehicles also on UDP: connect with {simulator.udp_url}"
                       + (f" (one radio: {radio.bytes_per_s:,.0f} B/s, {1000 * radio.latency_s:.0f}"
                          f" +- {1000 * radio.jitter_s:.0f} ms, {100 * radio.loss:.0f} % lost)"
                          if radio else ""))
        click.echo("emulating; Ctrl-C to stop")

    try:
        simulator.run(ready)
    except OSError as exc:
        raise FtlboError(f"cannot listen on TCP port {base_port}+: {exc.strerror or exc} "
                         "(is SITL or another `ftlbo-mav sim` running? try --base-port)") from None
