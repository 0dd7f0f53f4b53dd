"""``ftlbo-mav plan``: its options, a survey cut into sorties, and what it prints.

The command parses its options, calls :func:`~ftlbo_mav.planning.planner.plan` (or
:func:`~ftlbo_mav.planning.sorties.plan_sorties`) and writes the folder through
:mod:`ftlbo_mav.mission.export`; ``format_*`` turn a plan into the lines it prints (each
leg, the summary, the survey, the battery). Registered on the group in :mod:`ftlbo_mav.cli`,
which also takes the option types here (``SEED``, ``ITERATIONS``, ...) for ``compare``.
"""

from __future__ import annotations

import sys
from dataclasses import replace

import click
import numpy as np

from .cli_errors import user_errors
from .cli_types import LINK_URL, SYSIDS
from .energy import BATTERY_VIOLATION
from .errors import BadInput
from .gnss import classes_within
from .mission.export import FORMATS, PLAN_OUTPUTS, plan_files
from .mission.files import OutputFolder
from .planning.optimizers import OPTIMIZERS
from .planning.planner import AUTO_TARGET
from .planning.planner import plan as plan_scenario
from .planning.repair import fleet_lags
from .scenario import AUTO, load_scenario
from .scenario.model import MAX_ITERATIONS, MAX_SEED, MAX_STUDENTS, MAX_WAYPOINTS, MIN_STUDENTS
from .scenario.reader import scenario_inputs


def _parse_formats(_ctx, _param, value: str | None) -> tuple[str, ...]:
    """``--formats geojson,kml,plan`` or ``all`` -> a tuple of FORMATS names. ``all``
    among other names (``all,kml``) is still every format: a name it already holds is
    redundant, not wrong (an unknown name beside it is still refused)."""
    if value is None:
        return ()
    names = [v.strip().lower() for v in value.split(",") if v.strip()]
    if not names:
        raise click.BadParameter(f"names no format; give a comma-separated list of "
                                 f"{', '.join(FORMATS)}, or all (or leave --formats out)")
    if "all" in names:
        names = list(FORMATS) + [n for n in names if n != "all"]  # in FORMATS order
    unknown = [n for n in names if n not in FORMATS]
    if unknown:
        raise click.BadParameter(
            f"unknown format {unknown[0]!r}; give a comma-separated list of "
            f"{', '.join(FORMATS)}, or all")
    return tuple(dict.fromkeys(names))


def _with_fleet(scn, sysids_text: str, connect) -> object:
    """``scn`` with each UAV's copter as read from the vehicles (``plan --fleet``)."""
    from .link.addresses import default_urls_for, parse_sysids
    from .link.commands import _urls
    from .link.fleet_read import read_fleet

    sysids = parse_sysids(sysids_text)
    if len(sysids) != len(scn.offsets):
        raise BadInput(f"--fleet {sysids_text} names {len(sysids)} vehicles but the scenario "
                       f"has {len(scn.offsets)} UAVs")
    copters = read_fleet(scn.fleet(), sysids, _urls(connect) or default_urls_for(sysids))
    for n, c in enumerate(copters):
        click.echo(f"uav{n + 1}: {c.source}", err=True)
    from dataclasses import replace

    return replace(scn, copters=tuple(copters), vehicle=copters[0].nav)


class WaypointCount(click.ParamType):
    """``--waypoints``: an integer within 1..MAX_WAYPOINTS, or ``auto``."""

    name = "M|auto"

    def convert(self, value, param, ctx):
        if value == AUTO:
            return value
        try:
            count = int(value)
        except ValueError:
            count = 0
        if not 1 <= count <= MAX_WAYPOINTS:
            self.fail(f"{value!r} is neither an integer within 1..{MAX_WAYPOINTS} nor {AUTO}",
                      param, ctx)
        return count


WAYPOINTS = WaypointCount()
# The scenario's [planner] ranges (scenario/model.py), for the options that override them.
SEED = click.IntRange(0, MAX_SEED)
ITERATIONS = click.IntRange(1, MAX_ITERATIONS)
STUDENTS = click.IntRange(MIN_STUDENTS, MAX_STUDENTS)


@click.command()
@click.argument("scenario", type=click.Path(dir_okay=False, path_type=str))
@click.option("-o", "--output", "out_dir", required=True, type=click.Path(file_okay=False),
              help="Folder for uavN.waypoints and plan.json (created if needed).")
@click.option("--seed", type=SEED, help="Random seed (default: the scenario's).")
@click.option("--iterations", type=ITERATIONS, help="Iterations L.")
@click.option("--students", type=STUDENTS, help="Class size (population).")
@click.option("--waypoints", type=WAYPOINTS,
              help="Free waypoints m per leg, or auto: per leg the fewest within 0.5% of "
                   "its lower bound.")
@click.option("--algorithm", type=click.Choice(sorted(OPTIMIZERS)),
              help="Optimizer (default: the scenario's [planner] algorithm, else "
                   "ftlbo-seeded; ftlbo is the paper's).")
@click.option("--allow-infeasible", is_flag=True,
              help="Write mission files even when the best plan violates a constraint.")
@click.option("--formats", callback=_parse_formats, metavar="LIST",
              help="Also write these next to the .waypoints: geojson, kml, plan "
                   "(QGroundControl), comma-separated, or all.")
@click.option("--plot", "make_plots", is_flag=True,
              help="Also draw the plan: PNG figures in the output folder.")
@click.option("--no-fence", "no_fence", is_flag=True,
              help="Write no geofence and rally point (uavN.fence, uavN.rally, fence.parm).")
@click.option("-q", "--quiet", is_flag=True, help="No progress bar.")
@click.option("--fleet", "fleet_sysids", type=SYSIDS, default=None, metavar="SYSIDS",
              help="Read each copter's firmware and flight parameters from the vehicles "
                   "with these system ids (uav1 the first) and plan for them, over "
                   "[vehicle]'s profile and files (the values it names stay).")
@click.option("--connect", "connect", multiple=True, type=LINK_URL,
              help="With --fleet: the vehicles' connection strings (default: system id s "
                   "on tcp:127.0.0.1:5760 + 10*(s-1)).")
@user_errors
def plan(scenario, out_dir, seed, iterations, students, waypoints, algorithm, allow_infeasible,
         formats, make_plots, no_fence, quiet, fleet_sysids, connect):
    """Plan SCENARIO (TOML) and write one Mission Planner mission per UAV."""
    scn = load_scenario(scenario)
    if connect and fleet_sysids is None:
        raise BadInput("--connect is for --fleet: give the vehicles' system ids with --fleet")
    if fleet_sysids is not None:
        scn = _with_fleet(scn, fleet_sysids, connect)
    if scn.dropped_obstacles:
        click.echo(f"note: {scn.dropped_obstacles} obstacles left out: they cannot reach any "
                   "UAV's path inside the area", err=True)
    # the output folder is checked (a temporary one made beside it) before any planning;
    # everything is moved into it at the end, or nothing (a failure, Ctrl-C)
    with OutputFolder(out_dir, replaces=(*PLAN_OUTPUTS, SORTIES_JSON), last="plan.json",
                      inputs=scenario_inputs(scenario)) as out:
        result = _plan_with_progress(scn, seed=seed, iterations=iterations, students=students,
                                     waypoints=waypoints, algorithm=algorithm, quiet=quiet)
        in_sorties = _in_sorties(result)
        # in sorties: nothing here but the sorties' folders (an earlier plan's files go)
        files = {} if in_sorties else plan_files(result, allow_infeasible=allow_infeasible,
                                                 formats=formats, fence=not no_fence)
        if make_plots and not in_sorties:
            from .plots import figure_files  # matplotlib only when asked: a faster start

            files = {**files, **figure_files(result)}
        paths = out.write_all(files)
    if in_sorties:
        return _plan_sorties(scn, result, out_dir, seed=seed, iterations=iterations,
                             students=students, waypoints=waypoints, algorithm=algorithm,
                             allow_infeasible=allow_infeasible, formats=formats,
                             no_fence=no_fence)
    _remove_sorties(out_dir, 1)  # an earlier plan's, in sorties
    click.echo(format_summary(result))
    for line in format_survey(result) + format_battery(result):
        click.echo(line)
    for line in fleet_lags(result):
        click.echo(f"note: {line}", err=True)
    _say_rally_stopped(files.get("plan.json"))
    _say_written(paths)
    if not result.feasible:
        for line in result.violations:
            click.echo(f"  violation: {line}", err=True)
        hint = None if all(v.startswith(BATTERY_VIOLATION) for v in result.violations) else \
            _navigation_hint(scn, seed=seed, iterations=iterations, students=students,
                                waypoints=waypoints, algorithm=algorithm)
        if hint:
            click.echo(hint, err=True)
        if not allow_infeasible:
            click.echo("no mission files written: the best plan is infeasible "
                       "(see plan.json; --allow-infeasible writes them anyway)", err=True)
        sys.exit(1)


SORTIES_JSON = r"sorties\.json"


def _say_rally_stopped(plan_json: str | None) -> None:
    """One line on stderr naming the UAVs left without a rally point because the rally
    search reached its bound (:func:`~.mission.fence.rally_search_stopped`)."""
    import json

    from .mission.fence import rally_search_stopped

    line = rally_search_stopped(json.loads(plan_json)) if plan_json else None
    if line:
        click.echo(f"note: {line}", err=True)


def _remove_sorties(out_dir, first: int) -> None:
    """Remove ``OUT/sortie<first>`` and after: plan folders of sorties an earlier plan
    wrote (only folders that hold a plan.json)."""
    import shutil
    from pathlib import Path

    k = first
    while (Path(out_dir) / f"sortie{k}" / "plan.json").is_file():
        shutil.rmtree(Path(out_dir) / f"sortie{k}")
        k += 1


def _in_sorties(result) -> bool:
    """Whether the plan is a survey that one battery does not fly (:mod:`.planning.sorties`)."""
    if result.charges is None or result.scenario.survey is None:
        return False
    from .planning.sorties import battery_short

    return battery_short(result) and bool(result.scenario.survey.lanes)


def _plan_sorties(scn, whole, out_dir, *, allow_infeasible, formats, no_fence,
                  **planner) -> None:
    """A survey that one battery does not fly, written as sorties: ``OUT/sortie1`` ...
    (each a plan folder: upload and fly it as it is) and ``OUT/sorties.json``
    (:mod:`.planning.sorties`)."""
    import json

    from .mission.export import write_plan
    from .planning.sorties import plan_sorties, sortie_note, sorties_document

    b = whole.scenario.battery
    click.echo(f"the survey does not fit one battery ({b.describe()}; the whole survey in "
               f"one flight needs up to {max(c.total_mah for c in whole.charges):.0f} mAh): "
               "planning it in sorties, each from home to home", err=True)
    sorties = plan_sorties(scn, plan_scenario, whole=whole,
                           **{k: v for k, v in planner.items() if v is not None})
    for line in sortie_note(sorties):
        click.echo(line)
    infeasible = [k for k, p in enumerate(sorties.plans) if not p.feasible]
    if infeasible and not allow_infeasible:
        for k in infeasible:
            for line in sorties.plans[k].violations:
                click.echo(f"  violation (sortie {k + 1}): {line}", err=True)
        click.echo("no mission files written: a sortie is infeasible (--allow-infeasible "
                   "writes them anyway)", err=True)
        sys.exit(1)
    from pathlib import Path

    out = Path(out_dir)
    folders = [f"sortie{k + 1}" for k in range(len(sorties.plans))]
    for folder, p in zip(folders, sorties.plans):
        paths = write_plan(p, out / folder, allow_infeasible=allow_infeasible, formats=formats,
                           fence=not no_fence)
        _say_rally_stopped((out / folder / "plan.json").read_text())
        click.echo(f"  wrote {len(paths)} files in {out / folder}")
    _remove_sorties(out, len(folders) + 1)  # of an earlier, longer split
    with OutputFolder(out, replaces=(*PLAN_OUTPUTS, SORTIES_JSON), last="sorties.json") as top:
        paths = top.write_all({"sorties.json": json.dumps(
            sorties_document(sorties, folders), indent=1) + "\n"})
    _say_written(paths)
    if infeasible:
        sys.exit(1)


def _navigation_hint(scn, **planner) -> str | None:
    """For a plan infeasible with its navigation budget: the loosest tighter class
    (:data:`~ftlbo_mav.gnss.CLASSES`) with which the same scenario plans feasibly, each
    planned in turn, loosest first; None without a budget."""
    nav = scn.navigation
    if not nav.horizontal_m:
        return None
    tighter = [c for c in classes_within(nav.horizontal_m) if c.horizontal_m < nav.horizontal_m]
    for c in [*tighter, replace(nav, name="none", horizontal_m=0.0)]:
        click.echo(f"planning again with [navigation] {c.describe()}, to see what budget "
                   "would do", err=True)
        if plan_scenario(replace(scn, navigation=c), **planner).feasible:
            if c.horizontal_m == 0:
                return ("  navigation: feasible only with no navigation error at all: with "
                        f"[navigation] {nav.describe()} kept beyond the predicted path, and "
                        "with every class of receiver, it is not (a larger clearance cannot "
                        "help; fewer obstacles in the way, or a smaller formation, can)")
            return (f"  navigation: the clearance and separation are kept where the copters "
                    f"truly are, [navigation] {nav.describe()} beyond the predicted path; "
                    f"with [navigation] class = \"{c.name}\" ({c.horizontal_m:g} m) the plan "
                    "is feasible")
    return (f"  navigation: infeasible even with no navigation error: [navigation] "
            f"{nav.describe()} is not what stops it")


def _say_written(paths, *, listed: int = 24) -> None:
    """A line per file written; past ``listed`` (a large swarm), one line per kind."""
    if len(paths) <= listed:
        for path in paths:
            click.echo(f"  wrote {path}")
        return
    kinds: dict[str, list] = {}
    for path in paths:
        kind = path.suffix if path.name.startswith("uav") else path.name
        kinds.setdefault(kind, []).append(path)
    folder = paths[0].parent
    for group in kinds.values():
        # the first and last names: not every UAV has every kind (a .rally)
        what = (f"{len(group)} files {group[0].name} .. {group[-1].name}" if len(group) > 1
                else group[0].name)
        click.echo(f"  wrote {what} in {folder}")


def _plan_with_progress(scn, *, seed, iterations, students, waypoints, algorithm, quiet):
    """:func:`plan_scenario` with a progress bar on stderr and one line per leg."""
    settings = scn.planner
    per_leg = iterations or settings.iterations
    legs = len(scn.via) + 1
    said: list[str] = []  # one line per leg, after the bar (at once with -q)

    def tell(line: str) -> None:
        click.echo(line, err=True)

    with click.progressbar(length=legs * per_leg, label="planning", file=sys.stderr,
                           hidden=quiet) as bar:
        done = [0]  # legs finished

        def progress(it: int, _iterations: int, _best: float) -> None:
            bar.update(max(done[0] * per_leg + it - bar.pos, 0))

        def on_leg(k: int, count: int, leg) -> None:
            done[0] = k + 1
            bar.update(max(done[0] * per_leg - bar.pos, 0))
            if count > 1 or leg.tried:
                line = format_leg(k, count, leg)
                tell(line) if quiet else said.append(line)

        result = plan_scenario(scn, seed=seed, iterations=iterations, students=students,
                               waypoints=waypoints, algorithm=algorithm, progress=progress,
                               notice=tell, on_leg=on_leg)
    for line in said:
        click.echo(line, err=True)
    return result


def format_summary(result) -> str:
    c = result.cost
    s = result.settings
    status = "feasible" if result.feasible else f"INFEASIBLE ({len(result.violations)} violations)"
    legs = result.legs
    shape = ""
    if len(legs) > 1 or s.waypoints == AUTO:
        counts = ", ".join(str(leg.waypoints) for leg in legs)
        shape = (f"; {len(legs)} leg{'s' if len(legs) > 1 else ''}, "
                 f"{result.waypoint_count} points between start and goal"
                 + (f" (auto waypoints per leg: {counts})" if s.waypoints == AUTO else ""))
    return (
        f"{s.algorithm} seed {s.seed}: {status}; cost {c.total:.2f} = length {c.length:.2f} m"
        f" + safety {c.safety:.3f} + task {c.task:.3f}; {result.evaluations} evaluations"
        f" in {result.seconds:.2f} s"
        + (
            f"; lower bound {result.lower_bound_length:.2f} m (length x{result.length_ratio:.4f})"
            if result.lower_bound_length is not None
            else "; no route: no lower bound"
        )
        + shape
        + _flown(result)
    )


def _flown(result) -> str:
    """The predicted flown path: the clearance it keeps, what the planner did for it."""
    p = result.prediction
    if p is None or not len(p.obstacle_clearance):
        return ""
    did = [f"{n} {what}{'s' if n > 1 else ''}"
           for n, what in ((result.corners_moved, "corner move"),
                           (result.corner_stops, "corner stop"),
                           (result.replans, "re-plan")) if n]
    nav = result.scenario.navigation
    true_sep = p.separation if p.true_separation is None else p.true_separation
    truly = (f"; where the copters truly are, at 95 % with [navigation] {nav.describe()}: "
             f"clearance {p.clearance.min() - nav.horizontal_m:.2f} m"
             + (f", separation {true_sep.min():.2f} m" if np.isfinite(true_sep.min()) else ""))
    return (f"; flown path (predicted): clearance {p.clearance.min():.2f} m"
            + (f" ({', '.join(did)})" if did else "") + truly)


def format_battery(result) -> list[str]:
    """With a ``[battery]``: each UAV's predicted charge and what it lands with."""
    b, charges = result.scenario.battery, result.charges
    if b is None or charges is None:
        return []
    worst = max(range(len(charges)), key=lambda n: charges[n].total_mah)
    c = charges[worst]
    left = b.capacity_mah - c.total_mah
    return [f"battery ({b.describe()}): the missions use "
            f"{min(x.total_mah for x in charges):.0f}-{c.total_mah:.0f} mAh in "
            f"{c.seconds / 60.0:.1f} min at most; uav{worst + 1} lands with {left:.0f} mAh "
            f"({100.0 * left / b.capacity_mah:.0f} %)"]


def format_survey(result) -> list[str]:
    """The survey in a line or three: how many lanes at what spacing; with a camera, each
    UAV's footprint and ground sample distance, the trigger distance and the photos."""
    survey = result.scenario.survey
    if survey is None:
        return []
    from .mission.export import plan_missions
    from .mission.photos import camera_document, plan_photos

    spacing = survey.lane_spacing_m if survey.lane_spacing_m is not None else survey.spacing_m
    lines = [f"survey: {len(survey.lanes)} lane{'s' if len(survey.lanes) != 1 else ''} "
             f"{spacing:.2f} m apart (at most {survey.spacing_m:.2f} m), heading "
             f"{survey.heading_deg:g} deg, margin {survey.margin_m:.2f} m, at {survey.alt_m:.2f} m"
             + (f"; laid {result.lanes_inset_m:.2f} m further in, where the copters were "
                "predicted to swing out of the area turning into or out of a lane"
                if result.lanes_inset_m > 0 else "")]
    if survey.camera is None:
        return lines
    doc = camera_document(result, plan_photos(result, plan_missions(result)))
    for u in doc["uavs"]:
        lines.append(f"camera {u['name']}: at {u['alt']:.2f} m a footprint "
                     f"{u['footprint'][0]:.2f} x {u['footprint'][1]:.2f} m (across x along), "
                     f"GSD {u['gsd_cm']:.2f} cm/px, {u['photos']} photos")
    lines.append(f"camera: a photo every {doc['trigger_distance']:.2f} m along each lane "
                 f"(front overlap {survey.camera.front_overlap:g}, side overlap "
                 f"{survey.camera.side_overlap:g}); "
                 f"{sum(u['photos'] for u in doc['uavs'])} photos in all")
    return lines


def format_leg(index: int, count: int, leg) -> str:
    """One line per planned leg: its ends, waypoints (what auto chose), length and bound."""
    head = f"leg {index + 1}/{count} {leg.start_name} -> {leg.goal_name}: "
    noun = "waypoint" if leg.waypoints == 1 else "waypoints"
    if leg.tried:
        target = leg.target if leg.target is not None else AUTO_TARGET
        within = leg.feasible and leg.length_ratio is not None and (
            leg.length_ratio <= 1 + target)
        if leg.lower_bound_length is None:
            count_text = f"{leg.waypoints} {noun} (auto: no route to measure against)"
        elif within:
            count_text = f"{leg.waypoints} {noun} (auto)"
        else:
            count_text = (f"{leg.waypoints} {noun} (auto: no plan within "
                          f"{target:.1%} of the bound with "
                          f"{', '.join(map(str, leg.tried))} waypoints; kept the nearest)")
    else:
        count_text = f"{leg.waypoints} {noun}"
    status = "" if leg.feasible else f", INFEASIBLE ({len(leg.violations)} violations)"
    bound = ("no route" if leg.lower_bound_length is None else
             f"bound {leg.lower_bound_length:.2f} m (x{leg.length_ratio:.4f})")
    return f"{head}{count_text}, {leg.cost.length:.2f} m, {bound}{status}"
