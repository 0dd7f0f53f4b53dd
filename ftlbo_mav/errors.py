"""Typed errors. Every error a user can cause derives from :class:`FtlboError`.

The command line turns an ``FtlboError`` into one line on stderr and a non-zero exit code;
anything else reaching the top level is a bug and keeps its traceback.
"""

from __future__ import annotations


class FtlboError(Exception):
    """Base class of every error a user can cause."""


class ScenarioError(FtlboError):
    """A scenario file is missing, malformed or describes an impossible survey.

    The message always names the file and the field: ``scenario.toml: area.corner_a: ...``.
    """

    def __init__(self, source: str, field: str, problem: str) -> None:
        self.source = source
        self.field = field
        self.problem = problem
        where = f"{source}: {field}" if field else source
        super().__init__(f"{where}: {problem}")


class BadInput(FtlboError):
    """A malformed input (an option value, a file, a size too large to plan): exit code 2.

    ``bad_input`` is what :func:`ftlbo_mav.cli_errors.user_errors` looks at; subclasses
    of other kinds set it too."""

    bad_input = True


class MissionFileError(BadInput):
    """A mission file (``.waypoints``, a plan folder's ``plan.json``) cannot be read, does
    not parse, or holds a value that does not fit where it goes."""


class OutputError(BadInput):
    """An output cannot be written (the path is a file, not writable, a name too long):
    nothing of the command's outputs was written, what was there is untouched."""
