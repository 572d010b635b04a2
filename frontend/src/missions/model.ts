// The one mission model in the browser: the hub's REST `MissionItem` (generated from
// protocol/messages.py through the OpenAPI document), plus the few MAV_CMD numbers and
// helpers the map and the editor need. No second mission type.
import type { components } from "../generated/api";

type Schemas = components["schemas"];
export type MissionItem = Schemas["MissionItem"];
export type Mission = Schemas["Mission"];
export type MissionCheck = Schemas["MissionCheckResponse"];
export type MissionResult = Schemas["MissionResult"];
export type GotoCheck = Schemas["GotoCheckResponse"];
export type Violation = Schemas["ViolationModel"];

/** MAV_CMD numbers (common.xml). */
export const CMD = {
  WAYPOINT: 16,
  LOITER_TIME: 19,
  RTL: 20,
  LAND: 21,
  TAKEOFF: 22,
  CHANGE_SPEED: 178,
} as const;

/** MAV_FRAME numbers: the altitude's reference. */
export const FRAME = { GLOBAL: 0, GLOBAL_RELATIVE_ALT: 3, GLOBAL_TERRAIN_ALT: 10 } as const;

const FRAME_NAMES: Record<number, string> = {
  0: "above sea level",
  3: "above home",
  10: "above terrain",
};

export function frameName(frame: number): string {
  return FRAME_NAMES[frame] ?? `MAV_FRAME ${frame}`;
}

const COMMAND_NAMES: Record<number, string> = {
  16: "Waypoint",
  17: "Loiter",
  18: "Loiter turns",
  19: "Loiter time",
  20: "Return to launch",
  21: "Land",
  22: "Take-off",
  178: "Change speed",
};

export function commandName(command: number): string {
  return COMMAND_NAMES[command] ?? `MAV_CMD ${command}`;
}

/** The commands the editor offers in an item's type list. */
export const EDITABLE_COMMANDS = [CMD.TAKEOFF, CMD.WAYPOINT, CMD.LOITER_TIME, CMD.LAND, CMD.RTL] as const;

/** Commands that take the vehicle to their item's latitude and longitude. */
const GOES_TO = new Set<number>([16, 17, 18, 19, 21, 82, 31, 84, 85, 94]);

/** Where an item is on the map: null for an item that acts where the vehicle is. */
export function placeOf(item: MissionItem): [number, number] | null {
  if (!GOES_TO.has(item.command)) return null;
  if (item.lat === 0 && item.lon === 0) return null; // "here" (a land or loiter in place)
  return [item.lat, item.lon];
}

export function makeItem(command: number, lat = 0, lon = 0, alt = 0): MissionItem {
  return {
    command,
    frame: FRAME.GLOBAL_RELATIVE_ALT,
    param1: 0,
    param2: 0,
    param3: 0,
    param4: 0,
    lat,
    lon,
    alt,
    autocontinue: true,
  };
}

/** A DO_CHANGE_SPEED item: ground speed (param1 1) in m/s, throttle unchanged (-1). */
export function speedItem(speed: number): MissionItem {
  return { ...makeItem(CMD.CHANGE_SPEED), frame: 2, param1: 1, param2: speed, param3: -1 };
}

/** A MissionItem with every field the REST body has, from a partial one (a download omits none). */
export function fullItem(item: Partial<MissionItem> & { command: number }): MissionItem {
  return { ...makeItem(item.command), ...item };
}
