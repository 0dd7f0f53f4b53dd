"""The ``ftlbo-mav`` command line: each command parses options, calls the library, prints.

Errors a user can cause (:class:`~ftlbo_mav.errors.FtlboError`) end in one line on
stderr and a non-zero exit code; a traceback is a bug.
"""

from __future__ import annotations

import functools
import sys

import click

from . import __version__
from .errors import FtlboError, ScenarioError


def user_errors(func):
    """Turn a user error into one line on stderr: exit 2 for bad input, else 1."""

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        try:
            return func(*args, **kwargs)
        except FtlboError as exc:
            click.echo(f"error: {exc}", err=True)
            sys.exit(2 if isinstance(exc, ScenarioError) or getattr(exc, "bad_input", False) else 1)

    return wrapper


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="ftlbo-mav")
def main() -> None:
    """Plan formation flights for a small UAV swarm and get them onto ArduPilot vehicles."""


# Commands are registered below, one module per concern.
