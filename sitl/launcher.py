"""Start N ArduCopter SITL instances, wait until each is ready, stop them all on exit.

Instance i runs in its own working directory (its eeprom.bin, logs), with ``--instance i``
so it listens on TCP 5760 + 10*i, ``--home`` at its UAV's start, and the defaults a user
gives it (ArduPilot's ``Tools/autotest/default_params/copter.parm``, with ``defaults=`` or
``ARDUPILOT_SITL_DEFAULTS``) plus one line of ours: SYSID_THISMAV = i + 1. Nothing else:
no stream rates (the ground side asks for what it reads, as it must on a real vehicle).
The binary is ``ARDUPILOT_SITL`` (a built ``arducopter``, e.g. ``build/sitl/bin/arducopter``).
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import tempfile
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Self

from ftlbo_mav.errors import BadInput
from ftlbo_mav.link.addresses import default_urls
from ftlbo_mav.link.discovery import wait_ready
from ftlbo_mav.link.endpoints import LinkError, open_links

IDENTITY_PARAMS = "SYSID_THISMAV {sysid}\n"


def sitl_command(binary: str | Path, *, instance: int, home: tuple[float, float, float],
                 defaults: Sequence[Path], model: str = "quad", speedup: float = 1.0) -> list[str]:
    """The command line of one SITL instance (libraries/AP_HAL_SITL/SITL_cmdline.cpp)."""
    lat, lon, alt = home
    return [
        str(binary), "--model", model, "--speedup", f"{speedup:g}",
        "--instance", str(instance), f"--home={lat:.7f},{lon:.7f},{alt:.2f},0",
        "--defaults", ",".join(str(p) for p in defaults),
        "--wipe",  # start from the defaults, with no mission left from an earlier run
    ]


def _check_workdir(workdir: Path) -> None:
    """:class:`BadInput` when ``workdir`` (or the nearest part of it that exists) is not a
    directory: the instances' folders could not be made in it. Checked before any process
    is started."""
    existing = next((p for p in (workdir, *workdir.parents) if p.exists()), None)
    if existing is not None and not existing.is_dir():
        inside = "" if existing == workdir else f" (in --workdir {workdir})"
        raise BadInput(f"{existing}: is a file, not a directory{inside}: give --workdir a "
                       "directory (it is made if missing) for the instances' files")


class SitlSwarm:
    """N ArduCopter SITL processes; ``urls[i]`` reaches system id i+1.

    ``with SitlSwarm(binary=..., homes=[...]) as swarm:`` starts every instance, waits up to
    ``ready_timeout_s`` until each has a 3D GPS fix and passes its pre-arm checks, and on
    exit stops every process (SIGTERM, then SIGKILL) and removes the working directories
    it created.
    """

    def __init__(self, *, binary: str | Path | None = None,
                 homes: Sequence[tuple[float, float, float]], workdir: str | Path | None = None,
                 defaults: Sequence[str | Path] = (), model: str = "quad", speedup: float = 1.0,
                 ready_timeout_s: float = 180.0,
                 binaries: Sequence[str | Path | None] | None = None,
                 instance_defaults: Sequence[Sequence[str | Path]] | None = None,
                 instance_params: Sequence[Mapping[str, float]] | None = None):
        """``binaries``: one per copter (None: ``binary``), for a fleet of two releases;
        ``instance_defaults``: parameter files of each copter's own, after every other
        (a 3DR Solo's values for one of them); ``instance_params``: values of each
        copter's own, written as a defaults file in its folder after those."""
        binary = binary or os.environ.get("ARDUPILOT_SITL")
        if not binary:
            raise BadInput("no SITL binary: pass binary= (--binary) or set ARDUPILOT_SITL")
        self.binary = Path(binary)
        if not 1 <= len(homes) <= 254:
            raise BadInput(f"{len(homes)} copters: SITL instances are system ids 1..254")
        self.homes = list(homes)
        self.binaries = [Path(b) if b else self.binary for b in (binaries or [None] * len(homes))]
        for b in set(self.binaries):
            if not b.is_file() or not os.access(b, os.X_OK):
                raise BadInput(f"{b}: not an executable file (the arducopter SITL binary)")
        if len(self.binaries) != len(self.homes):
            raise BadInput(f"{len(self.binaries)} binaries for {len(self.homes)} copters")
        self.own_defaults = [[Path(p) for p in d]
                             for d in (instance_defaults or [()] * len(homes))]
        self.own_params = [dict(p) for p in (instance_params or [{}] * len(homes))]
        env_defaults = os.environ.get("ARDUPILOT_SITL_DEFAULTS", "")
        # ArduPilot's own copter.parm first, then the user's files (--defaults a,b: later wins)
        self.defaults = [Path(p) for p in env_defaults.split(",") if p] + [
            Path(p) for p in defaults]
        for path in self.defaults + [p for d in self.own_defaults for p in d]:
            # SITL would wait, not say, on a defaults file it lacks
            if not path.is_file():
                where = "--defaults" if path in [Path(p) for p in defaults] else \
                    "ARDUPILOT_SITL_DEFAULTS"
                raise BadInput(f"{path}: no such defaults file ({where})")
        self.model, self.speedup = model, speedup
        self.ready_timeout_s = ready_timeout_s
        self._workdir = Path(workdir) if workdir else None
        if self._workdir is not None:
            _check_workdir(self._workdir)
        self._own_workdir = workdir is None
        self.processes: list[subprocess.Popen] = []
        self.urls = default_urls(len(self.homes))

    def __enter__(self) -> Self:
        if self._workdir is None:
            self._workdir = Path(tempfile.mkdtemp(prefix="ftlbo-sitl-"))
        try:
            for i, home in enumerate(self.homes):
                run_dir = self._workdir / f"instance{i}"
                run_dir.mkdir(parents=True, exist_ok=True)
                identity = run_dir / "identity.parm"
                identity.write_text(IDENTITY_PARAMS.format(sysid=i + 1))
                own = []
                if self.own_params[i]:
                    own = [run_dir / "own.parm"]
                    own[0].write_text("".join(f"{k} {v:g}\n"
                                              for k, v in self.own_params[i].items()))
                cmd = sitl_command(self.binaries[i], instance=i, home=home,
                                   defaults=[*self.defaults, *self.own_defaults[i], *own,
                                             identity],
                                   model=self.model, speedup=self.speedup)
                log = open(run_dir / "sitl.log", "wb")
                try:
                    self.processes.append(subprocess.Popen(
                        cmd, cwd=run_dir, stdout=log, stderr=subprocess.STDOUT,
                        stdin=subprocess.DEVNULL, start_new_session=True))
                finally:
                    log.close()
            links = self._connect(timeout_s=30.0)
            try:
                wait_ready(links, list(range(1, len(self.homes) + 1)),
                           timeout_s=self.ready_timeout_s)
            finally:
                for link in links:
                    link.close()  # SITL takes the next client once this one has left
            self.check_running()  # ready means every process is still there
        except BaseException:
            self.__exit__(None, None, None)
            raise
        return self

    def _connect(self, *, timeout_s: float) -> list:
        """Links to every instance, tried for ``timeout_s``; an instance that has exited
        meanwhile is named at once (a binary that fails to start), not after the wait."""
        grace = time.monotonic() + 0.3  # a binary that cannot start exits within this
        for p in self.processes:
            try:
                p.wait(timeout=max(0.0, grace - time.monotonic()))
            except subprocess.TimeoutExpired:
                pass
        deadline = time.monotonic() + timeout_s
        while True:
            self.check_running()
            try:
                return open_links(self.urls, connect_timeout_s=1.0)
            except LinkError:
                if time.monotonic() >= deadline:
                    self.check_running()  # a SITL that died says so, not "cannot connect"
                    raise

    def check_running(self) -> None:
        """:class:`LinkError` naming every instance whose process has exited."""
        dead = [(i, p.returncode) for i, p in enumerate(self.processes) if p.poll() is not None]
        if dead:
            logs = self._workdir / f"instance{dead[0][0]}" / "sitl.log"
            raise LinkError("SITL " + ", ".join(f"instance {i} (sysid {i + 1}) exited with code "
                                                f"{code}" for i, code in dead)
                            + f"; see {logs}" + (" (kept with --workdir)" if self._own_workdir
                                                 else ""))

    def __exit__(self, *exc) -> None:
        for p in self.processes:
            if p.poll() is None:
                p.send_signal(signal.SIGTERM)
        for p in self.processes:
            try:
                p.wait(timeout=5.0)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()
        self.processes.clear()
        if self._own_workdir and self._workdir is not None:
            shutil.rmtree(self._workdir, ignore_errors=True)
            self._workdir = None
