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


class MissionFileError(FtlboError):
    """A mission file (``.waypoints``) cannot be read or does not parse."""
