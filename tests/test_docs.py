"""What the README and docs/ quote as a command's output is what the command prints now.

A quote is a fenced block right after a comment naming its command,
``<!-- output of: ftlbo-mav plan missions/X.toml -o out -->``; every line of the block must
be a line the command writes (stdout or stderr), the seconds a run took aside
(``in 1.43 s``). The command runs from the repository's root, its ``-o`` folder in a
temporary one. A quote whose command is not a ``ftlbo-mav plan`` of a shipped scenario is
refused here rather than run (a flight or an upload is quoted from a dated run instead).
A command another test runs already (:data:`CHECKED_ELSEWHERE`) is checked there, on
its output, through :func:`assert_quotes_hold`: one plan, not two.

A figure the pages call *measured* that no such quote holds is either produced by a test
that CI runs (the paragraph names it, ``tests/...py``) or dated with the command that
measured it (a ``YYYY-MM-DD`` and a command in backticks, in the paragraph or earlier in
its section): :func:`test_a_measured_figure_says_when_and_how`.
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
ALL_PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
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


_MEASURED = re.compile(r"\bmeasured\b", re.I)
_FIGURE = re.compile(r"\d(?:[\d,]*\d)?(?:\.\d+)?\s?(?:m|s|ms|%|x|MiB|GiB|min|m/s|kB/s|Hz|cm"
                     r"|deg|degrees|seconds|minutes)\b")
_DATE = re.compile(r"\b20\d\d-\d\d-\d\d\b")
_COMMAND = re.compile(r"`[^`]*(?:python|ftlbo-mav|pytest|benchmarks/|ARDUPILOT_SITL"
                      r"|/usr/bin/time)[^`]*`")
_TEST_FILE = re.compile(r"tests/[\w/]+\.py")


def _undated(pages: dict[str, str]) -> list[str]:
    """The paragraphs of ``pages`` (name: text) that call a figure of their own measured
    without naming a test that produces it or a date and a command (in the paragraph or
    earlier in its section)."""
    undated = []
    for page, text in pages.items():
        for section in re.split(r"\n(?=#)", text):
            paragraphs = re.split(r"\n\s*\n", section)
            for i, paragraph in enumerate(paragraphs):
                if not (_MEASURED.search(paragraph) and _FIGURE.search(paragraph)):
                    continue
                context = "\n".join(paragraphs[:i + 1])
                by_test = any((ROOT / t).is_file() for t in _TEST_FILE.findall(paragraph))
                if not by_test and not (_DATE.search(context) and _COMMAND.search(context)):
                    undated.append(f"{page}: {paragraph[:100]!r}")
    return undated


def test_a_measured_figure_says_when_and_how():
    pages = {p.relative_to(ROOT).as_posix(): p.read_text(encoding="utf-8") for p in ALL_PAGES}
    undated = _undated(pages)
    assert not undated, "measured, but neither dated with its command nor a test's:\n" + (
        "\n".join(undated))


def test_the_measured_check_refuses_an_undated_figure():
    figure = "Measured on SITL: 1.51 m clearance."
    assert _undated({"a.md": figure}) == [f"a.md: {figure!r}"]
    assert _undated({"a.md": "# Flights\n\nOn 2026-12-01, `ftlbo-mav fly out`:\n\n" + figure}) == []
    assert _undated({"a.md": figure + " (tests/test_docs.py)"}) == []
    assert _undated({"a.md": "# Flights\n\nOn 2026-12-01, `ftlbo-mav fly out`.\n\n# Other"
                             "\n\n" + figure}) != []  # a date in another section is not its
