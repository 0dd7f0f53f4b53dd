"""The start gate's arithmetic: ModeAuto::do_nav_delay and AP_RTC::get_time_utc
(libraries/AP_RTC/AP_RTC.cpp), field by field."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from ftlbo_mav.ardupilot.commands import delaying, nav_delay_ms, time_until_utc_ms

NOW = ((13 * 60 + 5) * 60 + 7) * 1000 + 250  # 13:05:07.250 UTC, on 1 January 1970


@pytest.mark.parametrize(("fields", "ms"), [
    ((-1, -1, -1, 0), 750),            # ms only (NAV_DELAY with no time): the next second
    ((-1, -1, 9, 0), 1750),            # the second of the minute
    ((-1, -1, 7, 0), 59_750),          # this second: a minute on (total < 0 -> +60 s)
    ((-1, -1, 3, 0), 55_750),          # past in this minute: the next minute's
    ((-1, 6, 0, 0), 52_750),           # minute and second: within the hour
    ((13, 5, 8, 0), 750),              # a time of day
    ((13, 5, 7, 0), 86_399_750),       # now, to the second: the next day's
    ((-1, -1, -1, -1), 0),             # nothing given
])
def test_time_until_a_time_of_day(fields, ms):
    assert time_until_utc_ms(*fields, NOW) == ms


def test_a_nav_delay_is_relative_when_param1_is_positive_else_absolute():
    item = SimpleNamespace(param1=2.5, param2=-1, param3=-1, param4=9)
    assert nav_delay_ms(item, NOW) == 2500
    gate = SimpleNamespace(param1=-1.0, param2=-1.0, param3=-1.0, param4=9.0)
    assert nav_delay_ms(gate, NOW) == 1750
    assert nav_delay_ms(gate, None) == 0  # no clock yet: AP_RTC::get_time_utc returns 0
    assert delaying(1750) == (6, "Delaying 1 sec")
