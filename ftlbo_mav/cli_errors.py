"""How every command ends on a user error: one line on stderr and an exit code.

Exit 2 for bad input (a scenario, a file, an option value), 1 for anything else a user
can cause (an unreachable vehicle, a refused step). A traceback is a bug.
"""

from __future__ import annotations

import functools
import sys

import click

from .errors import FtlboError, ScenarioError


def user_errors(func):
    """Turn a :class:`FtlboError` into one line on stderr and exit 2 (bad input) or 1."""

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        try:
            return func(*args, **kwargs)
        except FtlboError as exc:
            click.echo(f"error: {exc}", err=True)
            sys.exit(2 if isinstance(exc, ScenarioError) or getattr(exc, "bad_input", False) else 1)

    return wrapper
