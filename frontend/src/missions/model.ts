// The one mission model in the browser: the hub's REST `MissionItem` (generated from
// protocol/messages/ through the OpenAPI document), plus the few MAV_CMD and MAV_FRAME
// values (pymavlink's, through generated/mavlink.ts) and helpers the map and the editor
// need. No second mission type, and no number typed by hand.
import type { components } from "../generated/api";
import * as mav from "../generated/mavlink";

type Schemas = components["schemas"];
export type MissionItem = Schemas["MissionItem"];
export type Mission = Schemas["Mission"];
export type MissionCheck = Schemas["MissionCheckResponse"];
export type MissionResult = Schemas["MissionResult"];
export type GotoCheck = Schemas["GotoCheckResponse"];
export type Violation = Schemas["ViolationModel"];

/** The MAV_CMD values the editor and the map use, by short names. */
export const CMD = {
  WAYPOINT: mav.MAV_CMD_NAV_WAYPOINT,
  LOITER_TIME: mav.MAV_CMD_NAV_LOITER_TIME,
  RTL: mav.MAV_CMD_NAV_RETURN_TO_LAUNCH,
  LAND: mav.MAV_CMD_NAV_LAND,
  TAKEOFF: mav.MAV_CMD_NAV_TAKEOFF,
  CHANGE_SPEED: mav.MAV_CMD_DO_CHANGE_SPEED,
} as const;

/** MAV_FRAME values: the altitude's reference. */
export const FRAME = {
  GLOBAL: mav.MAV_FRAME_GLOBAL,
  GLOBAL_RELATIVE_ALT: mav.MAV_FRAME_GLOBAL_RELATIVE_ALT,
  GLOBAL_TERRAIN_ALT: mav.MAV_FRAME_GLOBAL_TERRAIN_ALT,
} as const;

const FRAME_NAMES: Record<number, string> = {
  [FRAME.GLOBAL]: "above sea level",
  [FRAME.GLOBAL_RELATIVE_ALT]: "above home",
  [FRAME.GLOBAL_TERRAIN_ALT]: "above terrain",
};

/** A frame in words, else its MAVLink name (MISSION), else its number. */
export function frameName(frame: number): string {
  return FRAME_NAMES[frame] ?? mav.MAV_FRAME_NAMES[frame]?.replace(/^MAV_FRAME_/, "") ?? frameNumber(frame);
}

/** The number behind a frame's name, for its tooltip. */
export function frameNumber(frame: number): string {
  return `MAV_FRAME ${frame}`;
}

const COMMAND_NAMES: Record<number, string> = {
  [mav.MAV_CMD_NAV_WAYPOINT]: "Waypoint",
  [mav.MAV_CMD_NAV_LOITER_UNLIM]: "Loiter",
  [mav.MAV_CMD_NAV_LOITER_TURNS]: "Loiter turns",
  [mav.MAV_CMD_NAV_LOITER_TIME]: "Loiter time",
  [mav.MAV_CMD_NAV_RETURN_TO_LAUNCH]: "Return to launch",
  [mav.MAV_CMD_NAV_LAND]: "Land",
  [mav.MAV_CMD_NAV_TAKEOFF]: "Take-off",
  [mav.MAV_CMD_DO_CHANGE_SPEED]: "Change speed",
};

/** A command in words, else its MAVLink name (DO_DIGICAM_CONTROL), else its number. */
export function commandName(command: number): string {
  return COMMAND_NAMES[command] ?? mav.MAV_CMD_NAMES[command]?.replace(/^MAV_CMD_/, "") ?? commandNumber(command);
}

/** The number behind a command's name, for its tooltip. */
export function commandNumber(command: number): string {
  return `MAV_CMD ${command}`;
}

/** The commands the editor offers in an item's type list. */
export const EDITABLE_COMMANDS = [CMD.TAKEOFF, CMD.WAYPOINT, CMD.LOITER_TIME, CMD.LAND, CMD.RTL] as const;

/** Commands that take the vehicle to their item's latitude and longitude. */
const GOES_TO = new Set<number>([
  mav.MAV_CMD_NAV_WAYPOINT,
  mav.MAV_CMD_NAV_LOITER_UNLIM,
  mav.MAV_CMD_NAV_LOITER_TURNS,
  mav.MAV_CMD_NAV_LOITER_TIME,
  mav.MAV_CMD_NAV_LAND,
  mav.MAV_CMD_NAV_SPLINE_WAYPOINT,
  mav.MAV_CMD_NAV_LOITER_TO_ALT,
  mav.MAV_CMD_NAV_VTOL_TAKEOFF,
  mav.MAV_CMD_NAV_VTOL_LAND,
  mav.MAV_CMD_NAV_PAYLOAD_PLACE,
]);

/** Where an item is on the map: null for an item that acts where the vehicle is. */
export function placeOf(item: MissionItem): [number, number] | null {
  if (!GOES_TO.has(item.command)) return null;
  if (item.lat === 0 && item.lon === 0) return null; // "here" (a land or loiter in place)
  return [item.lat, item.lon];
}

/** Commands whose param4 is a yaw, NaN (null) "keep the heading mode" (MAVLink common.xml). */
const YAW_PARAM4 = new Set<number>([CMD.WAYPOINT, CMD.LOITER_TIME, CMD.LAND, CMD.TAKEOFF]);

export function makeItem(command: number, lat = 0, lon = 0, alt = 0): MissionItem {
  return {
    command,
    frame: FRAME.GLOBAL_RELATIVE_ALT,
    param1: 0,
    param2: 0,
    param3: 0,
    // Unset, as QGC writes it: a yaw of 0 would turn a PX4 vehicle north at every item.
    param4: YAW_PARAM4.has(command) ? null : 0,
    lat,
    lon,
    alt,
    autocontinue: true,
  };
}

/** A DO_CHANGE_SPEED item: ground speed (param1 1) in m/s, throttle unchanged (-1). */
export function speedItem(speed: number): MissionItem {
  const frame = mav.MAV_FRAME_MISSION; // a DO_ command has no place
  return { ...makeItem(CMD.CHANGE_SPEED), frame, param1: 1, param2: speed, param3: -1 };
}

/** A MissionItem with every field the REST body has, from a partial one (a download omits none). */
export function fullItem(item: Partial<MissionItem> & { command: number }): MissionItem {
  return { ...makeItem(item.command), ...item };
}
