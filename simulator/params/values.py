"""ArduCopter parameters the simulator honours, in SI units, with ArduCopter's defaults.

The parameter each field mirrors is named in its comment. Where the brief for this
simulator fixes a value (horizontal speed 5 m/s) it wins over the firmware default.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class CopterParams:
    # Navigation (AC_WPNav / AC_PosControl)
    wpnav_speed: float = 5.0  # WPNAV_SPEED (cm/s in the firmware)
    wpnav_speed_up: float = 2.5  # WPNAV_SPEED_UP
    wpnav_speed_dn: float = 1.5  # WPNAV_SPEED_DN
    wpnav_accel: float = 2.5  # WPNAV_ACCEL
    wpnav_accel_z: float = 1.0  # WPNAV_ACCEL_Z
    wpnav_radius: float = 2.0  # WPNAV_RADIUS: a waypoint counts as reached inside this
    psc_posxy_p: float = 1.0  # PSC_POSXY_P
    psc_posz_p: float = 1.0  # PSC_POSZ_P
    angle_max: float = math.radians(30.0)  # ANGLE_MAX
    yaw_rate_max: float = math.radians(60.0)  # ATC_SLEW_YAW
    # GUID_TIMEOUT: a GUIDED velocity target older than this is dropped (the vehicle stops)
    guid_timeout: float = 3.0
    wp_yaw_behavior: int = 2  # WP_YAW_BEHAVIOR: face next waypoint except during RTL

    # Return to launch (ModeRTL)
    rtl_alt: float = 15.0  # RTL_ALT
    rtl_alt_min: float = 2.0  # RTL_ALT_MIN (compile-time constant)
    rtl_cone_slope: float = 3.0  # RTL_CONE_SLOPE
    rtl_abs_min_climb: float = 2.5  # RTL_ABS_MIN_CLIMB (compile-time constant)
    rtl_climb_min: float = 0.0  # RTL_CLIMB_MIN
    rtl_loit_time: float = 5.0  # RTL_LOIT_TIME (ms in the firmware)

    # Landing (ModeLand, land detector)
    land_speed: float = 0.5  # LAND_SPEED
    land_speed_high: float = 0.0  # LAND_SPEED_HIGH: 0 means use WPNAV_SPEED_DN
    land_alt_low: float = 10.0  # LAND_ALT_LOW
    land_detector_trigger: float = 1.0  # LAND_DETECTOR_TRIGGER_SEC

    # Arming and motors
    disarm_delay: float = 10.0  # DISARM_DELAY
    arming_delay: float = 2.0  # ARMING_DELAY_MS: motors idle this long after arming
    spool_time: float = 0.5  # MOT_SPOOL_TIME
    hover_throttle: float = 0.35  # MOT_THST_HOVER

    # Battery monitor and its failsafe (AP_BattMonitor, Copter::handle_battery_failsafe)
    batt_capacity: float = 5000.0  # BATT_CAPACITY, mAh
    batt_low_volt: float = 14.4  # BATT_LOW_VOLT (3.6 V a cell of the simulated 4S pack)
    batt_low_mah: float = 0.0  # BATT_LOW_MAH: remaining mAh that counts as low; 0 off
    batt_low_timer: float = 10.0  # BATT_LOW_TIMER: seconds below BATT_LOW_VOLT to trigger
    batt_fs_low_act: int = 0  # BATT_FS_LOW_ACT: 0 warn only, 1 land, 2 RTL

    # Simulation knobs (SITL's SIM_* parameters)
    # The GCS whose MANUAL_CONTROL (and RC overrides) ArduPilot takes, and how long an
    # override lasts without a fresh one before the RC sticks rule again.
    sysid_mygcs: int = 255  # SYSID_MYGCS (MAV_GCS_SYSID from 4.7)
    rc_override_time: float = 3.0  # RC_OVERRIDE_TIME, seconds
    loit_speed: float = 12.5  # LOIT_SPEED (cm/s in the firmware): full stick in LOITER
    pilot_speed_up: float = 2.5  # PILOT_SPEED_UP (cm/s in the firmware)
    pilot_speed_dn: float = 1.5  # PILOT_SPEED_DN: 0 in the firmware means PILOT_SPEED_UP
    sim_batt_drain: float = 1.0  # SIM_BATT_DRAIN: multiplies the charge drawn (a test knob)
    sim_gps_noise: float = 0.1  # SIM_GPS_NOISE: metres, 1 sigma, on GPS_RAW_INT
    sim_wind_spd: float = 0.0  # SIM_WIND_SPD, m/s
    sim_wind_dir: float = 0.0  # SIM_WIND_DIR, degrees the wind blows from
