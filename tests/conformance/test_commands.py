"""Arming, mode and mission commands against ArduCopter 4.5.6 SITL (commands.json, boot.json).

Every recorded step is sent to the emulator at its recorded time, after the recorded
uploads, with the recorded boot timeline: the COMMAND_ACK result must be the recorded
one, and the texts that follow from the command (not SITL's sensor chatter) must appear.
"""

from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as R

from .replay import Bench, load

COMMANDS = load("commands.json")
BOOT = load("boot.json")
# texts that follow from the command itself (the rest is SITL's sensors and EKF talking)
_OWN = ("Arm: AUTO", "Auto: ", "Mode change", "Arming motors", "Disarming motors", "Mission: ")
# the uploads, as the vehicle's "Flight plan received" dates them
UPLOADS = [(7.3, "mission_M1"), (61.6, "mission_no_takeoff"), (66.45, "mission_M1")]


def test_every_recorded_command_gets_the_recorded_result_and_texts():
    bench = Bench()
    uploads = list(UPLOADS)
    checked = 0
    for step in COMMANDS["steps"]:
        t = step.get("t_send") or step["state_after"]["t"] - 1.0
        while uploads and uploads[0][0] < t:
            at, name = uploads.pop(0)
            assert bench.upload(at, COMMANDS[name]["rows"]) == R.MAV_MISSION_ACCEPTED
        if not step.get("command_name"):  # MISSION_SET_CURRENT (a message, no ack)
            seq = int(step["sent"].split()[-1])
            bench.send(t, R.MAVLink_mission_set_current_message(1, 1, seq))
            continue
        ack = bench.command(t, step["command"], step["params"])
        assert R.enums["MAV_RESULT"][ack.result].name == step["result_name"], step["step"]
        bench.run(t + 1.0)
        texts = bench.texts(t, t + 1.0)
        for rec in step["statustext"]:
            if rec["text"].startswith(_OWN):
                assert rec["text"] in texts, (step["step"], rec["text"], texts)
        arming = step["command_name"].endswith("ARM_DISARM") and step["params"][0] == 1
        if step["result_name"] == "MAV_RESULT_FAILED" and arming:
            assert any(x.startswith("Arm: ") for x in texts), step["step"]
        after = step["state_after"]
        state = bench.vehicle.state
        assert state.mode.name == after["mode"], step["step"]
        assert state.armed == after["armed"], step["step"]
        checked += 1
    assert checked >= 25


def test_arming_becomes_possible_when_recorded_and_an_idle_copter_disarms_after_10_s():
    rec = BOOT["time_to_armable"]
    bench = Bench()
    for a in rec["attempts"]:
        ack = bench.command(a["t_send"], {"MAV_CMD_DO_SET_MODE": R.MAV_CMD_DO_SET_MODE,
                                          "MAV_CMD_COMPONENT_ARM_DISARM":
                                          R.MAV_CMD_COMPONENT_ARM_DISARM}[a["command_name"]],
                            a["params"])
        assert R.enums["MAV_RESULT"][ack.result].name == a["result_name"], a["t_send"]
    # GUIDED set at boot was reset to STABILIZE at "ArduPilot Ready"
    modes = [c["value"] for c in rec["mode_changes"]]
    assert modes[:2] == ["GUIDED", "STABILIZE"]
    assert "ArduPilot Ready" in bench.texts(2.0, 2.5)
    assert bench.vehicle.state.armed
    t_arm = rec["t_arm_accepted"]
    bench.run(t_arm + 9.5)
    assert bench.vehicle.state.armed
    bench.run(t_arm + 10.5)
    assert not bench.vehicle.state.armed and "Disarming motors" in bench.texts(t_arm + 9.5,
                                                                               t_arm + 10.5)
