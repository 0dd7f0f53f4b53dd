"""How ArduCopter 4.5 answers arming, mode and mission commands, and when it is ready.

The COMMAND_ACK results and STATUSTEXTs that ftlbo-mav meets, each with the ArduPilot
function it follows, and the boot timeline recorded on ArduCopter 4.5.6 SITL with
copter.parm (``tests/data/ardupilot-4.5.6/boot.json``, ``commands.json``). Pure values:
the emulator answers by them; the ground side may use them to explain a refusal.
"""

from __future__ import annotations

from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as R

from .modes import CopterMode, mode_name


@dataclass(frozen=True)
class BootTimeline:
    """Seconds after boot (SITL boots when its first client connects) at which ArduCopter
    4.5.6 SITL became ready, as recorded (boot.json ``time_to_armable``, mission_protocol.json
    ``0_upload_during_boot``):

    - ``ready_s``: "ArduPilot Ready" (AP_Vehicle / Copter::init_ardupilot end); a mode
      set before is reset to STABILIZE (init_ardupilot's ``set_mode(STABILIZE)``).
    - ``storage_s``: MISSION_COUNT is answered NO_SPACE ("Only 0 items are supported":
      AP_Mission not yet initialised, ``num_commands_max`` 0) until about this time.
    - ``gps_fix_s``: GPS_RAW_INT fix_type reaches 3 (SITL reports 6, RTK fixed).
    - ``home_s``: EKF origin and home set; HOME_POSITION and GPS_GLOBAL_ORIGIN are sent.
    - ``prearm_s``: SYS_STATUS's PREARM_CHECK health bit set.
    - ``armable_s``: MAV_CMD_COMPONENT_ARM_DISARM accepted ("EKF3 IMU0 is using GPS":
      AP_Arming ``mandatory_gps_checks`` pass).
    """

    ready_s: float = 2.23
    storage_s: float = 2.49
    gps_fix_s: float = 9.8
    home_s: float = 19.8
    prearm_s: float = 41.4
    armable_s: float = 42.1

    def scaled(self, factor: float) -> BootTimeline:
        """Every time multiplied by ``factor`` (tests run a fast boot in the same order)."""
        return BootTimeline(*(factor * v for v in vars(self).values()))


RECORDED_BOOT = BootTimeline()
INSTANT_BOOT = RECORDED_BOOT.scaled(0.0)

FORCE_DISARM_MAGIC = 21196  # AP_Arming::MAGIC_FORCE_ARM_VALUE / disarm: forced
DISARM_DELAY_S = 10.0       # DISARM_DELAY default (ArduCopter/motors.cpp auto_disarm_check)

# Texts, with the severity ArduPilot sends them at
ARMING_MOTORS = (R.MAV_SEVERITY_INFO, "Arming motors")        # AP_Arming::arm
DISARMING_MOTORS = (R.MAV_SEVERITY_INFO, "Disarming motors")  # AP_Arming::disarm
MISSING_TAKEOFF = (R.MAV_SEVERITY_CRITICAL, "Auto: Missing Takeoff Cmd")  # ModeAuto::init
# ArduCopter/GCS_Mavlink.cpp handle_command_pause_continue, when the mode will not
FAILED_TO_PAUSE = (R.MAV_SEVERITY_INFO, "Failed to pause")
FAILED_TO_RESUME = (R.MAV_SEVERITY_INFO, "Failed to resume")
READY = (R.MAV_SEVERITY_INFO, "ArduPilot Ready")
FLIGHT_PLAN_RECEIVED = (R.MAV_SEVERITY_INFO, "Flight plan received")  # AP_Mission complete
LAND_COMPLETE = (R.MAV_SEVERITY_INFO, "Land complete")


def no_space_text(max_items: int) -> tuple[int, str]:
    """MissionItemProtocol::handle_mission_count on a COUNT beyond ``max_items``."""
    return (R.MAV_SEVERITY_WARNING, f"Only {max_items} items are supported")


def mode_change_failed(mode: int, reason: str) -> tuple[int, str]:
    """Copter::mode_change_failed (ArduCopter/mode.cpp)."""
    return (R.MAV_SEVERITY_WARNING, f"Mode change to {mode_name(mode)} failed: {reason}")


def arm_refusals(since_boot_s: float, boot: BootTimeline) -> list[tuple[int, str]]:
    """What AP_Arming says when arming is refused at this time after boot (severity
    CRITICAL, prefix "Arm: "). SITL's early sensor texts vary from run to run ("Accels
    inconsistent", "Gyros inconsistent"); the ones that follow the boot phases are kept:
    no home yet (AP_Arming::ahrs_checks), then no position (ArduCopter/AP_Arming.cpp
    mandatory_gps_checks)."""
    crit = R.MAV_SEVERITY_CRITICAL
    if since_boot_s < boot.ready_s:
        return [(crit, "Arm: Need Alt Estimate"), (crit, "Arm: AHRS: waiting for home")]
    if since_boot_s < boot.home_s:
        return [(crit, "Arm: AHRS: waiting for home")]
    return [(crit, "Arm: Need Position Estimate")]


def mode_not_armable(mode: int) -> tuple[int, str]:
    """ArduCopter/AP_Arming.cpp arm_checks: ``"%s mode not armable"`` for a mode whose
    ``allows_arming`` is false (AUTO, RTL, LAND, ... from a GCS command)."""
    return (R.MAV_SEVERITY_CRITICAL, f"Arm: {mode_name(mode)} mode not armable")


# Modes a GCS may arm in (ArduCopter/mode.h allows_arming); AUTO only with AUTO_OPTIONS bit 0
ARMABLE_MODES = frozenset({
    CopterMode.STABILIZE, CopterMode.ACRO, CopterMode.ALT_HOLD, CopterMode.GUIDED,
    CopterMode.LOITER, CopterMode.DRIFT, CopterMode.SPORT, CopterMode.POSHOLD,
    CopterMode.THROW, CopterMode.FLOWHOLD, CopterMode.ZIGZAG, CopterMode.SYSTEMID,
    CopterMode.GUIDED_NOGPS, CopterMode.AUTOTUNE, CopterMode.BRAKE, CopterMode.CIRCLE,
})

# Modes that need a position estimate to be entered while armed (Mode::requires_GPS)
NEEDS_POSITION = frozenset({
    CopterMode.AUTO, CopterMode.GUIDED, CopterMode.LOITER, CopterMode.RTL,
    CopterMode.CIRCLE, CopterMode.DRIFT, CopterMode.POSHOLD, CopterMode.BRAKE,
    CopterMode.AVOID_ADSB, CopterMode.SMART_RTL, CopterMode.FOLLOW, CopterMode.ZIGZAG,
    CopterMode.AUTO_RTL, CopterMode.THROW,
})


def set_mode_base_ok(base_mode: float) -> bool:
    """GCS_MAVLINK::_set_mode_common: only custom modes; DO_SET_MODE with param1 lacking
    MAV_MODE_FLAG_CUSTOM_MODE_ENABLED is answered MAV_RESULT_DENIED."""
    return bool(int(base_mode) & R.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED)


NAV_LAST = R.MAV_CMD_NAV_LAST  # 95: commands below are navigation commands (AP_Mission)

# AP_Mission / ModeAuto::start_command: "Mission: <seq> <name>" (AP_Mission::Mission_Command::type)
MISSION_COMMAND_NAMES = {
    R.MAV_CMD_NAV_TAKEOFF: "Takeoff", R.MAV_CMD_NAV_WAYPOINT: "WP", R.MAV_CMD_NAV_LAND: "Land",
    R.MAV_CMD_NAV_RETURN_TO_LAUNCH: "RTL", R.MAV_CMD_NAV_LOITER_UNLIM: "LoitUnlim",
    R.MAV_CMD_DO_CHANGE_SPEED: "ChangeSpeed", R.MAV_CMD_NAV_DELAY: "Delay",
}


def mission_started(seq: int, command: int) -> tuple[int, str] | None:
    """What ArduCopter says when it starts mission item ``seq`` ("Mission: 3 WP"), or None
    for a command it starts silently (as far as recorded)."""
    name = MISSION_COMMAND_NAMES.get(command)
    return None if name is None else (R.MAV_SEVERITY_INFO, f"Mission: {seq} {name}")


def reached_command(seq: int) -> tuple[int, str]:
    """ModeAuto::verify_nav_wp, once a waypoint is reached: "Reached command #N"."""
    return (R.MAV_SEVERITY_INFO, f"Reached command #{seq}")


DAY_MS = 86_400_000


def time_until_utc_ms(hour: int, minute: int, second: int, ms: int, utc_ms: int) -> int:
    """AP_RTC::get_time_utc (libraries/AP_RTC/AP_RTC.cpp): milliseconds from ``utc_ms``
    (the vehicle's clock, ms since the Unix epoch) until the time of day given by the
    fields that are not -1. The largest field given sets the period it wraps in: a time
    already past is the next one (``second`` alone: within the minute; ``minute``: the
    hour; ``hour``: the day), and the same second as now is a whole period away."""
    if hour != -1:
        largest = 4
    elif minute != -1:
        largest = 3
    elif second != -1:
        largest = 2
    elif ms != -1:
        largest = 1
    else:
        return 0
    day = utc_ms % DAY_MS
    cur_hour, rest = divmod(day, 3_600_000)
    cur_min, rest = divmod(rest, 60_000)
    cur_sec, cur_ms = divmod(rest, 1000)
    total = ms - cur_ms
    for level, value, current, unit, period in (
            (1, None, None, 0, 1000), (2, second, cur_sec, 1000, 60_000),
            (3, minute, cur_min, 60_000, 3_600_000), (4, hour, cur_hour, 3_600_000, DAY_MS)):
        if level > largest:
            break
        if value is not None:
            total += (value - current) * unit
        if level == largest and total < 0:
            return total + period
    return total % 2**32  # static_cast<uint32_t>


def nav_delay_ms(item, utc_ms: int | None) -> int:
    """How long ArduCopter holds at a NAV_DELAY mission item (ModeAuto::do_nav_delay,
    ArduCopter/mode_auto.cpp): ``param1`` > 0 seconds from when the item starts, else
    until the UTC time of day in ``param2``-``param4`` (hour, minute, second; -1: not
    given; stored as int8, :mod:`.storage`), by the vehicle's clock (AP_RTC, set from
    its GPS): :func:`time_until_utc_ms` with 0 ms. Without a clock (``utc_ms`` None: no GPS
    time yet) 0. Every field -1 holds until the next whole second. The item ends on the
    first loop after that many ms (verify_nav_delay: ``millis() - start > max``)."""
    if item.param1 > 0:
        return int(item.param1 * 1000) % 2**32
    if utc_ms is None:
        return 0
    return time_until_utc_ms(int(item.param2), int(item.param3), int(item.param4), 0, utc_ms)


def delaying(ms: int) -> tuple[int, str]:
    """ModeAuto::do_nav_delay's announcement: "Delaying N sec" (whole seconds, rounded
    down)."""
    return (R.MAV_SEVERITY_INFO, f"Delaying {ms // 1000} sec")
