"""Issue 12: a flight log folder that cannot be written is refused before any vehicle is
contacted, not found out when the flight's record is written at its end."""

from __future__ import annotations

from pathlib import Path

import pytest
from click.testing import CliRunner

from ftlbo_mav.cli import main

PLANNED = Path(__file__).resolve().parents[2] / "missions" / "nha-trang-orchard"


@pytest.mark.parametrize("command", ["fly", "monitor"])
@pytest.mark.parametrize("kind", ["a file", "under /proc", "a name too long"])
def test_an_unwritable_log_dir_is_bad_input_before_any_link(command, kind, tmp_path):
    target = {"a file": tmp_path / "afile", "under /proc": Path("/proc/ftlbo-log"),
              "a name too long": tmp_path / ("x" * 300)}[kind]
    if kind == "a file":
        target.write_text("keep me\n")
    result = CliRunner().invoke(main, [command, str(PLANNED), "--sysid", "1..3", "--log-dir",
                                       str(target), "--connect", "tcp:127.0.0.1:9"])
    assert result.exit_code == 2, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "cannot connect" not in lines[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == (["afile"] if kind == "a file" else [])
