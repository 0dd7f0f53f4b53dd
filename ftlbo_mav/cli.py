"""The ``ftlbo-mav`` command line: each command parses options, calls the library, prints.

Here the group (``main``, the entry point), its error handling and the commands'
registration, and the small ``plot`` and ``compare`` commands; ``plan`` is
:mod:`ftlbo_mav.cli_plan`.

Errors a user can cause (:class:`~ftlbo_mav.errors.FtlboError`) end in one line on
stderr and a non-zero exit code; a traceback is a bug.
"""

from __future__ import annotations

import importlib
import signal
import sys
import threading

import click

from . import __version__
from .cli_errors import user_errors
from .cli_plan import ITERATIONS, STUDENTS, WAYPOINTS, plan
from .mission.files import OutputFolder
from .mission.plan_reader import read_plan
from .scenario import load_scenario
from .scenario.reader import scenario_inputs

LAZY_COMMANDS = {
    "upload": "ftlbo_mav.link.commands:upload",
    "download": "ftlbo_mav.link.commands:download",
    "sim": "ftlbo_mav.sim.commands:sim",
    "fly": "ftlbo_mav.flight.commands:fly_command",
    "monitor": "ftlbo_mav.flight.commands:monitor",
    "abort": "ftlbo_mav.flight.commands:abort_command",
    "risk": "ftlbo_mav.risk.commands:risk",
}
"""The commands that talk MAVLink, imported only when one of them runs (or ``--help``
lists them): ``plan`` starts without pymavlink's links and the emulator (click's
documented lazy loading, "Advanced Patterns")."""


class _Group(click.Group):
    """The command group; a bad option value or usage, like every other bad input, ends in
    one line (``error: ...``) and exit code 2, rather than click's usage block. The
    commands of :data:`LAZY_COMMANDS` are imported when asked for."""

    def list_commands(self, ctx):
        return sorted({*super().list_commands(ctx), *LAZY_COMMANDS})

    def get_command(self, ctx, name):
        if name in LAZY_COMMANDS and name not in self.commands:
            module, attribute = LAZY_COMMANDS[name].split(":")
            self.add_command(getattr(importlib.import_module(module), attribute), name)
        return super().get_command(ctx, name)

    def main(self, args=None, prog_name=None, complete_var=None, standalone_mode=True,
             **extra):
        if not standalone_mode:
            return super().main(args, prog_name, complete_var, standalone_mode, **extra)
        try:
            rv = super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        except click.UsageError as exc:
            where = exc.ctx.command_path if exc.ctx is not None else "ftlbo-mav"
            click.echo(f"error: {exc.format_message()} (see {where} --help)", err=True)
            sys.exit(2)
        except click.ClickException as exc:
            exc.show()
            sys.exit(exc.exit_code)
        except click.Abort:
            click.echo("Aborted!", err=True)
            sys.exit(1)
        sys.exit(rv if isinstance(rv, int) else 0)


@click.group(cls=_Group, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="ftlbo-mav")
def main() -> None:
    """Plan formation flights for a small UAV swarm and get them onto ArduPilot vehicles."""
    if threading.current_thread() is threading.main_thread():
        # `kill` stops every command the way Ctrl-C does: through its clean-up (a
        # half-written output folder removed, vehicles sent home by `fly`)
        signal.signal(signal.SIGTERM, _terminate)


def _terminate(_signum, _frame) -> None:
    raise KeyboardInterrupt


main.add_command(plan)  # the planner's command (cli_plan.py): imported with the group


# Commands are registered here, one module per concern: the planner's (cli_plan.py: plan)
# above, plot and compare below; the MAVLink bridge (link/commands.py: upload, download),
# the emulator (sim/commands.py: sim), the flights (flight/commands.py: fly, monitor,
# abort) and risk (risk/commands.py) through LAZY_COMMANDS.


@main.command("plot")
@click.argument("folder", type=click.Path(file_okay=False, path_type=str))
@click.option("-o", "--output", "out_dir", type=click.Path(file_okay=False),
              help="Folder for the PNG files (default: FOLDER).")
@user_errors
def plot_command(folder, out_dir):
    """Draw the plan in FOLDER (written by `plan`): 3D view, projections, convergence."""
    from .plots import figure_files  # matplotlib only when asked: a faster start

    plan = read_plan(folder)
    with OutputFolder(out_dir or folder) as out:
        paths = out.write_all(figure_files(plan))
    for path in paths:
        click.echo(f"  wrote {path}")


# The comparison of algorithms over seeds (ftlbo_mav/compare.py).
@main.command("compare")
@click.argument("scenario", type=click.Path(dir_okay=False, path_type=str))
@click.option("-o", "--output", "out_dir", required=True, type=click.Path(file_okay=False),
              help="Folder for table.md, table.csv, compare.json, convergence.png.")
@click.option("--runs", type=click.IntRange(1, 100_000), default=30, show_default=True,
              help="Seeds 0..RUNS-1 per algorithm.")
@click.option("--algorithms", default="ftlbo,tlbo,ga,theta-pso,ftlbo-seeded", show_default=True,
              help="Comma-separated algorithm names (ftlbo,tlbo,ga,theta-pso is the paper's set).")
@click.option("--processes", type=click.IntRange(1, 256),
              help="Worker processes (default: the number of cores).")
@click.option("--iterations", type=ITERATIONS, help="Iterations L (default: scenario's).")
@click.option("--students", type=STUDENTS, help="Class size (default: scenario's).")
@click.option("--waypoints", type=WAYPOINTS,
              help="Waypoints m per leg, or auto (default: scenario's).")
@click.option("-q", "--quiet", is_flag=True, help="No progress bar.")
@user_errors
def compare_command(scenario, out_dir, runs, algorithms, processes, iterations, students,
                    waypoints, quiet):
    """Run several algorithms over many seeds on SCENARIO: table, figure and JSON."""
    from .compare import compare, comparison_files, table_markdown
    from .planning.optimizers import OPTIMIZERS as known

    names = [a.strip() for a in algorithms.split(",") if a.strip()]
    bad = [a for a in names if a not in known]
    if bad or not names:
        raise click.BadParameter(
            f"unknown algorithm {bad[0]!r}; known: {', '.join(known)}" if bad
            else "give at least one algorithm", param_hint="--algorithms")
    twice = sorted({a for a in names if names.count(a) > 1})
    if twice:
        raise click.BadParameter(f"{twice[0]!r} is given twice: name each algorithm once",
                                 param_hint="--algorithms")
    scn = load_scenario(scenario)
    # checked before the runs, written after them
    with OutputFolder(out_dir, inputs=scenario_inputs(scenario)) as out:
        with click.progressbar(length=runs * len(names), label="comparing", file=sys.stderr,
                               hidden=quiet) as bar:
            result = compare(scn, algorithms=names, runs=runs, processes=processes,
                             iterations=iterations, students=students, waypoints=waypoints,
                             progress=lambda _run: bar.update(1))
        paths = out.write_all(comparison_files(result))
    click.echo(table_markdown(result), nl=False)
    for path in paths:
        click.echo(f"  wrote {path}")
