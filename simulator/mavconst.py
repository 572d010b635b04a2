"""The MAVLink, ArduCopter, ArduRover and PX4 numbers the simulator uses, as typed enums.

pymavlink's constants are untyped module attributes; these mirror the ones we need so
the pure logic stays typed. A unit test checks every value against pymavlink's dialect.
"""

from __future__ import annotations

from enum import IntEnum, IntFlag


class CopterMode(IntEnum):
    """ArduCopter flight-mode numbers (HEARTBEAT.custom_mode)."""

    STABILIZE = 0
    ACRO = 1
    ALT_HOLD = 2
    AUTO = 3
    GUIDED = 4
    LOITER = 5
    RTL = 6
    CIRCLE = 7
    LAND = 9
    DRIFT = 11
    SPORT = 13
    FLIP = 14
    AUTOTUNE = 15
    POSHOLD = 16
    BRAKE = 17
    THROW = 18
    AVOID_ADSB = 19
    GUIDED_NOGPS = 20
    SMART_RTL = 21
    FLOWHOLD = 22
    FOLLOW = 23
    ZIGZAG = 24
    SYSTEMID = 25
    AUTOROTATE = 26
    AUTO_RTL = 27
    TURTLE = 28


# The modes this simulator flies; the others exist in ArduCopter but are not modelled.
SUPPORTED_MODES = frozenset(
    {
        CopterMode.STABILIZE,
        CopterMode.AUTO,
        CopterMode.GUIDED,
        CopterMode.LOITER,
        CopterMode.RTL,
        CopterMode.LAND,
        CopterMode.BRAKE,
    }
)


class RoverMode(IntEnum):
    """ArduRover mode numbers (Rover/mode.h; pymavlink's mode_mapping_rover)."""

    MANUAL = 0
    ACRO = 1
    STEERING = 3
    HOLD = 4
    LOITER = 5
    FOLLOW = 6
    SIMPLE = 7
    DOCK = 8
    CIRCLE = 9
    AUTO = 10
    RTL = 11
    SMART_RTL = 12
    GUIDED = 15
    INITIALISING = 16


# The Rover modes this simulator drives; the others exist but are not modelled.
SUPPORTED_ROVER_MODES = frozenset(
    {RoverMode.MANUAL, RoverMode.HOLD, RoverMode.AUTO, RoverMode.GUIDED, RoverMode.RTL}
)


class Px4MainMode(IntEnum):
    """PX4_CUSTOM_MAIN_MODE (commander/px4_custom_mode.h)."""

    MANUAL = 1
    ALTCTL = 2
    POSCTL = 3
    AUTO = 4
    ACRO = 5
    OFFBOARD = 6
    STABILIZED = 7
    RATTITUDE = 8


class Px4AutoMode(IntEnum):
    """PX4_CUSTOM_SUB_MODE_AUTO: the sub mode of main mode AUTO."""

    READY = 1
    TAKEOFF = 2
    LOITER = 3
    MISSION = 4
    RTL = 5
    LAND = 6
    FOLLOW_TARGET = 8
    PRECLAND = 9


class MavType(IntEnum):
    """HEARTBEAT.type values of the simulated frames."""

    QUADROTOR = 2
    GROUND_ROVER = 10


class MavAutopilot(IntEnum):
    ARDUPILOTMEGA = 3
    PX4 = 12


class MavResult(IntEnum):
    ACCEPTED = 0
    TEMPORARILY_REJECTED = 1
    DENIED = 2
    UNSUPPORTED = 3
    FAILED = 4
    IN_PROGRESS = 5
    # PX4: a position command in a frame it does not take (newer than pymavlink's dialect)
    COMMAND_UNSUPPORTED_MAV_FRAME = 9


class Severity(IntEnum):
    EMERGENCY = 0
    ALERT = 1
    CRITICAL = 2
    ERROR = 3
    WARNING = 4
    NOTICE = 5
    INFO = 6
    DEBUG = 7


class MavState(IntEnum):
    UNINIT = 0
    BOOT = 1
    CALIBRATING = 2
    STANDBY = 3
    ACTIVE = 4
    CRITICAL = 5
    EMERGENCY = 6


class LandedState(IntEnum):
    UNDEFINED = 0
    ON_GROUND = 1
    IN_AIR = 2
    TAKEOFF = 3
    LANDING = 4


class ModeFlag(IntFlag):
    CUSTOM_MODE_ENABLED = 1
    TEST_ENABLED = 2
    AUTO_ENABLED = 4
    GUIDED_ENABLED = 8
    STABILIZE_ENABLED = 16
    HIL_ENABLED = 32
    MANUAL_INPUT_ENABLED = 64
    SAFETY_ARMED = 128


class MavFrame(IntEnum):
    GLOBAL = 0
    LOCAL_NED = 1
    MISSION = 2
    GLOBAL_RELATIVE_ALT = 3
    LOCAL_ENU = 4
    GLOBAL_INT = 5
    GLOBAL_RELATIVE_ALT_INT = 6
    LOCAL_OFFSET_NED = 7
    BODY_NED = 8
    BODY_OFFSET_NED = 9
    GLOBAL_TERRAIN_ALT = 10
    GLOBAL_TERRAIN_ALT_INT = 11


class MavCmd(IntEnum):
    NAV_WAYPOINT = 16
    NAV_LOITER_TIME = 19
    NAV_RETURN_TO_LAUNCH = 20
    NAV_LAND = 21
    NAV_TAKEOFF = 22
    NAV_LOITER_UNLIM = 17
    DO_SET_MODE = 176
    DO_CHANGE_SPEED = 178
    DO_SET_HOME = 179
    DO_REPOSITION = 192
    DO_DIGICAM_CONTROL = 203
    DO_SET_CAM_TRIGG_DIST = 206
    PREFLIGHT_REBOOT_SHUTDOWN = 246
    GET_HOME_POSITION = 410
    COMPONENT_ARM_DISARM = 400
    GET_MESSAGE_INTERVAL = 510
    SET_MESSAGE_INTERVAL = 511
    REQUEST_MESSAGE = 512
    REQUEST_AUTOPILOT_CAPABILITIES = 520


class MsgId(IntEnum):
    """Ids of the messages the simulator can send."""

    HEARTBEAT = 0
    SYS_STATUS = 1
    PARAM_VALUE = 22
    GPS_RAW_INT = 24
    ATTITUDE = 30
    MISSION_CURRENT = 42
    MISSION_ITEM_REACHED = 46
    GLOBAL_POSITION_INT = 33
    GPS_GLOBAL_ORIGIN = 49
    VFR_HUD = 74
    COMMAND_ACK = 77
    CAMERA_FEEDBACK = 180
    EKF_STATUS_REPORT = 193
    BATTERY_STATUS = 147
    AUTOPILOT_VERSION = 148
    HOME_POSITION = 242
    MESSAGE_INTERVAL = 244
    EXTENDED_SYS_STATE = 245
    STATUSTEXT = 253


class MavMissionResult(IntEnum):
    """MAV_MISSION_RESULT (names after ``MAV_MISSION_``)."""

    ACCEPTED = 0
    ERROR = 1
    UNSUPPORTED_FRAME = 2
    UNSUPPORTED = 3
    NO_SPACE = 4
    INVALID = 5
    INVALID_SEQUENCE = 13
    DENIED = 14


class MissionState(IntEnum):
    """MISSION_STATE (names after ``MISSION_STATE_``)."""

    UNKNOWN = 0
    NO_MISSION = 1
    NOT_STARTED = 2
    ACTIVE = 3
    PAUSED = 4
    COMPLETE = 5


class SysSensor(IntFlag):
    """MAV_SYS_STATUS_SENSOR bits reported in SYS_STATUS (names after ``MAV_SYS_STATUS_``)."""

    SENSOR_3D_GYRO = 0x01
    SENSOR_3D_ACCEL = 0x02
    SENSOR_3D_MAG = 0x04
    SENSOR_ABSOLUTE_PRESSURE = 0x08
    SENSOR_GPS = 0x20
    SENSOR_ANGULAR_RATE_CONTROL = 0x400
    SENSOR_ATTITUDE_STABILIZATION = 0x800
    SENSOR_YAW_POSITION = 0x1000
    SENSOR_Z_ALTITUDE_CONTROL = 0x2000
    SENSOR_XY_POSITION_CONTROL = 0x4000
    SENSOR_MOTOR_OUTPUTS = 0x8000
    SENSOR_RC_RECEIVER = 0x10000
    AHRS = 0x200000
    LOGGING = 0x1000000
    SENSOR_BATTERY = 0x2000000
    PREARM_CHECK = 0x10000000


# COMPONENT_ARM_DISARM param2 values that skip checks (ArduPilot's GCS.h).
FORCE_ARM_MAGIC = 2989.0
FORCE_DISARM_MAGIC = 21196.0
# PREFLIGHT_REBOOT_SHUTDOWN param6 that reboots even while armed (pymavlink's force=True).
FORCE_REBOOT_MAGIC = 20190226.0

# SET_POSITION_TARGET_* type_mask bits: position x, y, z ignored.
POSITION_TARGET_IGNORE_POSITION = 0b111
DO_REPOSITION_FLAGS_CHANGE_MODE = 1
