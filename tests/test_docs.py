"""What the README and docs/ quote as a command's output is what the command prints now.

A quote is a fenced block right after a comment naming its command,
``<!-- output of: ftlbo-mav plan missions/X.toml -o out -->``; every line of the block must
be a line the command writes (stdout or stderr), the seconds a run took aside
(``in 1.43 s``). The command runs from the repository's root, its ``-o`` folder in a
temporary one. A quote whose command is not a ``ftlbo-mav plan`` of a shipped scenario is
refused here rather than run (a flight or an upload is quoted from a dated run instead).
A command another test runs already (:data:`CHECKED_ELSEWHERE`) is checked there, on
its output, through :func:`assert_quotes_hold`: one plan, not two.
"""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest
from click.testing import CliRunner

from ftlbo_mav.cli import main

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
QUOTE = re.compile(r"<!-- output of: (?P<command>[^\n]*?) -->\n```[a-z]*\n(?P<body>.*?)```",
                   re.S)
_SECONDS = re.compile(r"\bin \d+(?:\.\d+)? s\b")


def _quotes() -> list[tuple[str, str, str]]:
    found = []
    for page in PAGES:
        for m in QUOTE.finditer(page.read_text(encoding="utf-8")):
            found.append((page.relative_to(ROOT).as_posix(), m["command"], m["body"]))
    return found


QUOTES = _quotes()
CHECKED_ELSEWHERE = {
    "ftlbo-mav plan missions/orchard-survey.toml -o out":
        "tests/test_survey_scenario.py::test_the_shipped_survey_missions_are_what_the_planner_writes",
}


def _plain(text: str) -> str:
    return _SECONDS.sub("in ... s", text)


def test_the_readme_quotes_the_example():
    assert any(page == "README.md" and "nha-trang-orchard.toml" in command
               for page, command, _ in QUOTES)


def assert_quotes_hold(command: str, output: str) -> None:
    """Every quote of ``command`` in the README and docs/ is lines of ``output``."""
    printed = {_plain(line) for line in output.splitlines()}
    quoted = [(page, body) for page, c, body in QUOTES if c == command]
    assert quoted, f"nothing quotes `{command}`"
    for page, body in quoted:
        missing = [line for line in body.splitlines() if line and _plain(line) not in printed]
        assert not missing, f"{page} quotes `{command}` as printing lines it no longer prints"


def test_every_quote_is_checked():
    for page, command, _ in QUOTES:
        args = shlex.split(command)
        assert args[:2] == ["ftlbo-mav", "plan"] and (ROOT / args[2]).is_file(), (
            f"{page}: only `ftlbo-mav plan` of a shipped scenario is checked: {command}")
    for where in CHECKED_ELSEWHERE.values():
        path, _, name = where.partition("::")
        text = (ROOT / path).read_text(encoding="utf-8")
        assert f"def {name}(" in text and "assert_quotes_hold" in text, where


RUN_HERE = [q for q in QUOTES if q[1] not in CHECKED_ELSEWHERE]


@pytest.mark.parametrize("command", sorted({c for _, c, _ in RUN_HERE}),
                         ids=lambda c: c.split()[2])
def test_a_quoted_output_is_what_the_command_prints(command, tmp_path, monkeypatch):
    args = shlex.split(command)
    at = args.index("-o") + 1
    args[at] = str(tmp_path / args[at])
    monkeypatch.chdir(ROOT)
    result = CliRunner().invoke(main, args[1:])
    assert result.exit_code == 0, result.output
    assert_quotes_hold(command, result.output)
