"""One copter of a fleet as ArduCopter defines it: its release and its parameters.

A fleet is not one copter: a 3DR Solo flies with the values ArduPilot ships for its board,
another copter with its own autotuned gains, and each runs the release it was last
updated to. The flown path is predicted with each copter's own values, taken from (last
wins): ArduCopter's defaults for its release (:mod:`.navigation`), a named profile (the
values ArduPilot ships for a board, ``hwdef/<board>/defaults.parm``), a parameter file
saved from the copter, and the values a scenario names. What upload may write is
decided here too: a *navigation* value the scenario names (speeds, accelerations,
WPNAV_RADIUS, ...) is the plan's to set, as Mission Planner's "Write Params" would after
the user typed it; a *tuning* value (PSC_*, ATC_*, ANGLE_MAX, INS_*, MOT_*) is the
copter's own, chosen for its frame, and is never written.

Pure values: reading a parameter file's text is parsing, not I/O (the caller reads it).
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, field

from .navigation import (
    NAV_PARAMS,
    RELEASE_DEFAULTS,
    VEHICLE_PARAMS,
    Navigation,
    param_matches,
)

# -- which parameters the plan depends on, and their ranges -----------------------------

FLIGHT_PARAM_RANGES: Mapping[str, tuple[float, float]] = VEHICLE_PARAMS
"""Every parameter the flown path, the landing and RTL depend on (:data:`.navigation.NAV_PARAMS`),
with the range ArduCopter documents for it (its ``@Range``; ArduPilot itself does not
enforce it, a ground station warns)."""

FLIGHT_PARAMS: tuple[str, ...] = NAV_PARAMS
"""The parameters read from a copter, a file or a scenario and predicted with."""

assert set(FLIGHT_PARAM_RANGES) == set(FLIGHT_PARAMS)

TUNING_PREFIXES = ("PSC_", "ATC_", "INS_", "MOT_")
TUNING_NAMES = frozenset({"ANGLE_MAX"})


def is_tuning(name: str) -> bool:
    """Whether ``name`` is part of a copter's tuning (its controllers' gains and limits:
    PSC_*, ATC_*, ANGLE_MAX, INS_*, MOT_*), which nothing here writes: Mission Planner and
    QGroundControl never touch it when they send a mission, and neither does ``upload``."""
    return name in TUNING_NAMES or name.startswith(TUNING_PREFIXES)


# -- releases -----------------------------------------------------------------------------

RELEASES = ("4.5", "4.6")
"""The ArduCopter release series whose waypoint navigation the model follows, each held
to recordings of its SITL (``tests/data/ardupilot-<release>/``)."""
DEFAULT_RELEASE = "4.5"
SITL_CLOCK_BEHIND_S = {"4.5": 0.0, "4.6": 0.17}
"""How far each release's SITL clock of the day is behind 4.5.6 SITL's on the same machine:
its GPS time, and AP_RTC, which ArduPilot sets once from its first GPS fix
(libraries/AP_RTC/AP_RTC.cpp ``set_utc_usec``). Measured, not read from the code (what in
libraries/SITL changed is not found): three flights of a 4.5.6, a 4.6.3 and a 4.5.6 copter
with the Solo's values (``benchmarks/fleet.py --fleet mixed --speedup 1 --keep``,
2026-12-07): their boot clocks within 11 ms of each other on the ground's clock, the
4.6.3 copter's GPS time 166-170 ms behind the others' at the same boot time
(``python -m sitl.truth``), and its start gate opening 163-170 ms after theirs. Copters of
one release agree within 5 ms (fifteen flights). A start gate opens by that clock: the
emulator's copters carry it, and ``fly`` trims the start for it (flight/start.py)."""


def release_of(major: int, minor: int) -> str:
    """The series of a version (``4.6`` for 4.6.3)."""
    return f"{major}.{minor}"


def nearest_release(major: int, minor: int) -> str:
    """The modelled series nearest a version: the same one, else the closest by minor
    number within major 4 (4.7 -> 4.6, 4.4 -> 4.5)."""
    if major == 4:
        return min(RELEASES, key=lambda r: (abs(int(r.split(".")[1]) - minor), r))
    return RELEASES[-1] if major > 4 else RELEASES[0]


def release_for(flight_sw_version: int | None, default: str = DEFAULT_RELEASE) -> str:
    """The modelled series a copter's AUTOPILOT_VERSION ``flight_sw_version`` flies as
    (``major<<24 | minor<<16 | ...``, :mod:`.firmware`): its own, else the nearest;
    ``default`` when it did not say."""
    if flight_sw_version is None:
        return default
    raw = int(flight_sw_version) & 0xFFFFFFFF
    major, minor = raw >> 24, (raw >> 16) & 0xFF
    own = release_of(major, minor)
    return own if own in RELEASES else nearest_release(major, minor)


# -- profiles: the values ArduPilot ships for a board ---------------------------------

@dataclass(frozen=True)
class Profile:
    name: str
    description: str
    params: Mapping[str, float]  # FLIGHT_PARAMS only, ArduPilot units
    source: str


PROFILES: Mapping[str, Profile] = {
    "arducopter": Profile("arducopter", "ArduCopter's own defaults", {},
                          "ArduCopter's var_info defaults (ftlbo_mav/ardupilot/navigation.py)"),
    # The flight-path parameters of libraries/AP_HAL_ChibiOS/hwdef/CubeSolo/defaults.parm,
    # the same at Copter-4.5.6 (bbf0b066) and Copter-4.6.3: the 3DR Solo with a stock or
    # green/black cube on Copter 4. The rest of that file (RC, serial, notch filters,
    # battery, gimbal) does not shape the flown path.
    "3dr-solo": Profile(
        "3dr-solo", "3DR Solo (CubeSolo defaults.parm)",
        {"WPNAV_SPEED": 300.0, "WPNAV_SPEED_UP": 320.0, "WPNAV_SPEED_DN": 240.0,
         "PSC_VELXY_P": 1.41, "PSC_VELXY_I": 0.51, "ANGLE_MAX": 2000.0,
         "ATC_INPUT_TC": 0.25, "ATC_ACCEL_R_MAX": 36000.0, "ATC_ACCEL_P_MAX": 36000.0,
         "LAND_SPEED": 45.0, "LAND_SPEED_HIGH": 220.0, "LAND_ALT_LOW": 600.0,
         "RTL_ALT": 4500.0, "RTL_SPEED": 800.0},
        "libraries/AP_HAL_ChibiOS/hwdef/CubeSolo/defaults.parm (ArduPilot Copter-4.5.6, 4.6.3)"),
}


# -- parameter files --------------------------------------------------------------------

class ParamFileError(ValueError):
    """A parameter file that cannot be read: names the file and the line."""


_LINE = re.compile(r"^\s*([A-Za-z0-9_]{1,16})\s*[,\s]\s*([^\s,#]+)")


def read_param_text(text: str, *, source: str) -> dict[str, float]:
    """Every ``NAME,VALUE`` (Mission Planner's ``.param``) or ``NAME VALUE`` (MAVProxy's
    and ``ftlbo-mav download``'s ``.parm``; also QGroundControl's tab-separated
    ``sysid compid NAME VALUE type``) line of a parameter file; ``#`` starts a comment.
    :class:`ParamFileError` names ``source`` and the line of one that is neither, or a
    value that is not a finite number."""
    out: dict[str, float] = {}
    for number, raw in enumerate(text.splitlines(), 1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        parts = line.split("\t")
        if len(parts) >= 4 and parts[0].strip().isdigit() and parts[1].strip().isdigit():
            line = f"{parts[2].strip()} {parts[3].strip()}"  # QGC: sysid compid name value type
        m = _LINE.match(line)
        if m is None:
            raise ParamFileError(f"{source}, line {number}: {raw.strip()!r} is not a "
                                 "parameter line (NAME,VALUE or NAME VALUE)")
        name, value = m.group(1), m.group(2)
        try:
            out[name] = float(value)
        except ValueError:
            raise ParamFileError(f"{source}, line {number}: {name}: {value!r} is not a "
                                 "number") from None
        if not math.isfinite(out[name]):
            raise ParamFileError(f"{source}, line {number}: {name}: {value} is not finite")
    return out


def flight_values(values: Mapping[str, float], *, source: str,
                  only_known: bool = False) -> dict[str, float]:
    """The :data:`FLIGHT_PARAMS` among ``values``, each within ArduCopter's range
    (ValueError naming ``source`` and the parameter). With ``only_known``, a name that
    is not one of them is an error too (a scenario's table); a file's other parameters
    are left out."""
    out = {}
    for name, value in values.items():
        if name not in FLIGHT_PARAM_RANGES:
            if only_known:
                raise ValueError(f"{source}: {name} is not a parameter the flown path "
                                 f"depends on (known: {', '.join(FLIGHT_PARAMS)})")
            continue
        lo, hi = FLIGHT_PARAM_RANGES[name]
        if not (math.isfinite(value) and lo <= value <= hi):
            raise ValueError(f"{source}: {name} = {value:g} is outside ArduCopter's range "
                             f"[{lo:g}, {hi:g}]")
        out[name] = float(value)
    return out


# -- one copter --------------------------------------------------------------------------

@dataclass(frozen=True)
class Copter:
    """One copter as its flight is predicted: ``release`` (the series whose navigation
    is modelled, :data:`RELEASES`), ``params``: every :data:`FLIGHT_PARAMS` value it flies
    with (ArduPilot's names and units), ``named``: the names a scenario gave a value of
    (upload sets the navigation ones among them, never the tuning), ``source``: where the
    values came from, for a person."""

    release: str = DEFAULT_RELEASE
    params: Mapping[str, float] = field(default_factory=lambda: defaults())
    named: tuple[str, ...] = ()
    source: str = "ArduCopter defaults"

    @property
    def nav(self) -> Navigation:
        return Navigation(release=self.release).with_params(self.params)

    def to_set(self) -> dict[str, float]:
        """What ``upload`` writes: the navigation values the scenario named."""
        return {n: self.params[n] for n in self.named if not is_tuning(n)}

    def document(self) -> dict:
        return {"release": self.release, "source": self.source,
                "params": {n: round(float(v), 6) for n, v in self.params.items()},
                "set": self.to_set()}

    @classmethod
    def from_document(cls, doc: Mapping) -> Copter:
        """plan.json's per-UAV ``vehicle``; ValueError for one that is not."""
        release = str(doc.get("release", DEFAULT_RELEASE))
        if release not in RELEASES:
            raise ValueError(f"release {release!r} is not one of {', '.join(RELEASES)}")
        params = defaults(release) | {str(k): float(v) for k, v in dict(doc["params"]).items()}
        named = tuple(str(k) for k in dict(doc.get("set") or {}))
        return cls(release, params, named, str(doc.get("source", "plan.json")))

    def with_onboard(self, onboard: Mapping[str, float], *, release: str, source: str
                     ) -> Copter:
        """This copter as it truly is: the values read from it (the ones this plan will
        set stay as planned: upload writes them) and the release it runs."""
        planned = self.to_set()
        params = dict(self.params) | {n: float(v) for n, v in onboard.items()
                                      if n in FLIGHT_PARAM_RANGES} | planned
        return Copter(release, params, self.named, source)


def defaults(release: str = DEFAULT_RELEASE) -> dict[str, float]:
    """ArduCopter's defaults of every :data:`FLIGHT_PARAMS` value in ``release``
    (:data:`.navigation.RELEASE_DEFAULTS`: 4.6 differs in PSC_VELXY_D)."""
    every = Navigation().to_params() | dict(RELEASE_DEFAULTS[release])
    return {n: round(every[n], 6) for n in FLIGHT_PARAMS}


def copter_of(nav: Navigation, *, source: str = "ArduCopter defaults") -> Copter:
    """The copter that flies as ``nav`` says (nothing named)."""
    every = nav.to_params()
    return Copter(nav.release, {n: round(every[n], 6) for n in FLIGHT_PARAMS}, (), source)


def resolve_copter(*, profile: str = "arducopter", release: str = DEFAULT_RELEASE,
                   file_values: Mapping[str, float] | None = None, file_source: str = "",
                   named: Mapping[str, float] | None = None) -> Copter:
    """One copter's values: ArduCopter's defaults, then ``profile``'s, then a saved
    parameter file's, then the ``named`` ones (checked: ValueError names the one out of
    range)."""
    if profile not in PROFILES:
        raise ValueError(f"profile {profile!r}: not one of {', '.join(PROFILES)}")
    if release not in RELEASES:
        raise ValueError(f"firmware {release!r}: the modelled releases are "
                         f"{', '.join(RELEASES)}")
    params = defaults(release) | dict(PROFILES[profile].params)
    parts = [f"ArduCopter {release}"]
    if profile != "arducopter":
        parts.append(PROFILES[profile].description)
    if file_values:
        params |= dict(file_values)
        parts.append(file_source)
    named = dict(named or {})
    params |= named
    if named:
        parts.append("scenario: " + ", ".join(named))
    return Copter(release, params, tuple(named), " + ".join(parts))


def differences(planned: Copter, actual: Copter) -> list[tuple[str, float, float]]:
    """``(name, planned value, actual value)`` of every flight parameter that differs as
    a copter keeps it (:func:`.navigation.param_matches`)."""
    out = []
    for name in FLIGHT_PARAMS:
        a, b = float(planned.params[name]), float(actual.params[name])
        if not param_matches(name, a, b):
            out.append((name, a, b))
    return out
