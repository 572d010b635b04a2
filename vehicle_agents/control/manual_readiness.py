"""Whether the autopilot will take MANUAL_CONTROL from the agent, checked before browser
control opens, so that the agent refuses with the reason (and the parameter change that
would lift it) instead of streaming frames the autopilot would drop:

- ArduPilot takes MANUAL_CONTROL (an RC override) only from its GCS's system id,
  ``MAV_GCS_SYSID`` (4.7 on, up to ``MAV_GCS_SYSID_HI`` when that is greater;
  ``SYSID_MYGCS`` before, default 255), and times overrides out after
  ``RC_OVERRIDE_TIME`` seconds (0 turns them off; -1 never times out).
- PX4 takes it only when ``COM_RC_IN_MODE`` allows MAVLink input: 1 (MAVLink only),
  2 (RC and MAVLink with fallback) or 3 (RC or MAVLink, keep first); 0 is RC only and
  4 disables manual input. PX4 checks only the target system, not the sender's id.
  And when the input stops (the deadman's case) PX4's manual-control-loss failsafe
  flies ``NAV_RCL_ACT`` (Return by default) ``COM_RC_LOSS_T`` + ``COM_FAIL_ACT_T`` later,
  unless ``COM_RCL_EXCEPT`` exempts the mode flown: the deadman's Hold must be (bit 1),
  or the hold the lease promises turns into a flight home.
"""

from __future__ import annotations

from protocol.messages import ParamFix
from vehicle_agents.fcu.link import FcuLink
from vehicle_agents.fcu.params import ParamClient

# PX4 COM_RC_IN_MODE values that let MAVLink manual input through.
PX4_MAVLINK_INPUT = {1: "MAVLink only", 2: "RC and MAVLink", 3: "RC or MAVLink, keep first"}
# What a refusal offers to set instead: each autopilot's own default, which lets our input
# in and keeps the RC transmitter's (ArduPilot RC_OVERRIDE_TIME 3 s, PX4 COM_RC_IN_MODE 3).
RC_OVERRIDE_TIME_DEFAULT = 3.0
PX4_RC_IN_MODE_DEFAULT = 3
# PX4 COM_RCL_EXCEPT's bit that exempts Hold from the manual-control-loss failsafe, and
# the NAV_RCL_ACT values whose action leaves a hold a hold (0 none, 1 Hold).
PX4_RCL_EXCEPT_HOLD = 1 << 1
PX4_RCL_ACT_HOLDS = {0: "none", 1: "Hold"}
PX4_RCL_ACT_NAMES = {2: "Return", 3: "Land", 5: "Terminate", 6: "Disarm"}

Refusal = tuple[str, ParamFix | None]  # why, and the parameter change that would lift it


async def manual_refusal(link: FcuLink, params: ParamClient, source_system: int) -> Refusal | None:
    """Why the autopilot would drop MANUAL_CONTROL from ``source_system`` (the agent's
    id), and the parameter change that would lift it if one would; None if it will take it."""
    modes = link.modes
    if modes is None or link.target_system is None:
        return "the flight controller is not identified yet", None
    if modes.autopilot == "ardupilot":
        return await _ardupilot_refusal(params, source_system)
    if modes.autopilot == "px4":
        return await _px4_refusal(params)
    return None


async def _ardupilot_refusal(params: ParamClient, source_system: int) -> Refusal | None:
    low = await _param(params, "MAV_GCS_SYSID")
    high = await _param(params, "MAV_GCS_SYSID_HI") if low is not None else None
    gcs_id = low or await _param(params, "SYSID_MYGCS")
    if gcs_id is None:
        return "could not read MAV_GCS_SYSID or SYSID_MYGCS", None
    name, value = gcs_id
    # 4.7 accepts the range MAV_GCS_SYSID..MAV_GCS_SYSID_HI when HI is greater.
    top = high[1] if high is not None and high[1] > value else value
    if not round(value) <= source_system <= round(top):
        accepted = f"{value:g}" if top == value else f"{value:g}..{top:g}"
        return (
            f"ArduPilot takes MANUAL_CONTROL only from its GCS ({name} = "
            f"{accepted}); set {name} to {source_system}, the agent's id",
            ParamFix(param=name, value=source_system),
        )
    override = await _param(params, "RC_OVERRIDE_TIME")
    if override is not None and override[1] == 0:
        return (
            "RC_OVERRIDE_TIME is 0, which turns RC overrides off",
            ParamFix(param="RC_OVERRIDE_TIME", value=RC_OVERRIDE_TIME_DEFAULT),
        )
    return None


async def _px4_refusal(params: ParamClient) -> Refusal | None:
    rc_in = await _param(params, "COM_RC_IN_MODE")
    if rc_in is None:
        return "could not read COM_RC_IN_MODE", None
    if round(rc_in[1]) not in PX4_MAVLINK_INPUT:
        return (
            f"COM_RC_IN_MODE = {rc_in[1]:g} lets no MAVLink manual input in; "
            f"set it to 1, 2 or 3 ({PX4_RC_IN_MODE_DEFAULT}, PX4's default, keeps RC too)",
            ParamFix(param="COM_RC_IN_MODE", value=PX4_RC_IN_MODE_DEFAULT),
        )
    return await _px4_loss_refusal(params)


async def _px4_loss_refusal(params: ParamClient) -> Refusal | None:
    """Refused unless the deadman's Hold stays a hold when the input stops: PX4's
    manual-control-loss failsafe flies NAV_RCL_ACT unless COM_RCL_EXCEPT exempts
    Hold (bit 1) or that action is itself a hold (or none)."""
    exempt = await _param(params, "COM_RCL_EXCEPT")
    action = await _param(params, "NAV_RCL_ACT")
    if exempt is None or action is None:
        return "could not read COM_RCL_EXCEPT or NAV_RCL_ACT", None
    bits, act = round(exempt[1]), round(action[1])
    if bits & PX4_RCL_EXCEPT_HOLD or act in PX4_RCL_ACT_HOLDS:
        return None
    needed = bits | PX4_RCL_EXCEPT_HOLD
    act_name = PX4_RCL_ACT_NAMES.get(act, "its action")
    return (
        f"COM_RCL_EXCEPT = {bits} does not exempt Hold from PX4's manual-control-loss "
        f"failsafe (NAV_RCL_ACT = {act}, {act_name}): the hold after the stream stops "
        f"would turn into it; set COM_RCL_EXCEPT to {needed} (bit 1, Hold)",
        ParamFix(param="COM_RCL_EXCEPT", value=needed),
    )


async def _param(params: ParamClient, name: str) -> tuple[str, float] | None:
    outcome = await params.read(name)
    if outcome.status != "accepted" or not outcome.values:
        return None
    return name, outcome.values[name]
