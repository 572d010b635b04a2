// The edits of a plan, on its items (no DOM): new items at sensible places and heights,
// a command changed with what it needs, a speed folded in or out, a row deleted.
import type { VehicleSummary } from "../hub/types";
import { speedIndexFor } from "./itemRows";
import { CMD, type MissionItem, makeItem, speedItem } from "./model";

export const DEFAULT_ALT_M = 20;
const GROUND_TYPES = new Set(["rover", "boat", "submarine"]);
type State = VehicleSummary["state"] | undefined;

/** Where a take-off item stands: the vehicle's home, else where it is now, as
 * QGroundControl writes a take-off at the launch point. PX4 flies to a take-off's
 * position once it has climbed (ArduPilot climbs where it stands), so 0, 0 would send
 * it towards 0°N 0°E; with no position known yet it stays 0, 0, which the hub's check
 * refuses on PX4 with the reason. */
export function launchPoint(state: State): { lat: number; lon: number } {
  if (state?.home_lat != null && state.home_lon != null) return { lat: state.home_lat, lon: state.home_lon };
  if (state?.lat != null && state.lon != null) return { lat: state.lat, lon: state.lon };
  return { lat: 0, lon: 0 };
}

/** What an edit starts from: a copy of the mission known on board, else (for a vehicle that
 * flies) a take-off at its launch point. */
export function startingPlan(known: readonly MissionItem[] | undefined, vehicle: VehicleSummary | undefined): MissionItem[] {
  const plan = known ? known.map((item) => ({ ...item })) : [];
  if (plan.length === 0 && vehicle && !GROUND_TYPES.has(vehicle.vehicle_type)) {
    const launch = launchPoint(vehicle.state);
    plan.push(makeItem(CMD.TAKEOFF, launch.lat, launch.lon, DEFAULT_ALT_M));
  }
  return plan;
}

/** The height of the last item before `before` that has one (else the default). */
export function lastAltitude(items: readonly MissionItem[], before: number): number {
  for (let i = before - 1; i >= 0; i--) {
    const item = items[i];
    if (item.command !== CMD.CHANGE_SPEED && item.command !== CMD.RTL && item.alt > 0) return item.alt;
  }
  return DEFAULT_ALT_M;
}

/** A new item of `command` at the end of `items`. */
export function newItem(command: number, items: readonly MissionItem[], state: State): MissionItem {
  const alt = command === CMD.RTL || command === CMD.LAND ? 0 : lastAltitude(items, items.length);
  const item = makeItem(command, 0, 0, alt);
  if (command === CMD.TAKEOFF) Object.assign(item, launchPoint(state));
  if (command === CMD.LOITER_TIME) {
    // Loiter where the previous place was (a loiter at 0, 0 would be "here").
    const last = [...items].reverse().find((i) => i.lat !== 0 || i.lon !== 0);
    Object.assign(item, { param1: 30, lat: last?.lat ?? state?.lat ?? 0, lon: last?.lon ?? state?.lon ?? 0 });
  }
  return item;
}

/** Turns `item` into a `command`, with the place and parameters that command needs. */
export function changeCommand(item: MissionItem, command: number, state: State): void {
  const place = item.lat !== 0 || item.lon !== 0;
  item.command = command;
  if (command === CMD.TAKEOFF) Object.assign(item, launchPoint(state));
  if (command === CMD.RTL) Object.assign(item, { lat: 0, lon: 0 });
  if (command === CMD.RTL) item.alt = 0;
  if (command === CMD.LOITER_TIME && !((item.param1 ?? 0) > 0)) item.param1 = 30;
  if ((command === CMD.WAYPOINT || command === CMD.LOITER_TIME) && !place) {
    Object.assign(item, { lat: state?.lat ?? 0, lon: state?.lon ?? 0 });
  }
  if (command !== CMD.LOITER_TIME) item.param1 = 0;
}

/** Sets the speed from item `index` on (null or not positive: the folded speed item goes). */
export function setSpeed(items: MissionItem[], index: number, speed: number | null): void {
  const folded = speedIndexFor(items, index);
  if (speed === null || !(speed > 0)) {
    if (folded !== null) items.splice(folded, 1);
  } else if (folded !== null) items[folded].param2 = speed;
  else items.splice(index, 0, speedItem(speed));
}

/** Deletes the row of item `index`: the item and the speed folded into it. */
export function deleteRow(items: MissionItem[], index: number): void {
  const folded = speedIndexFor(items, index);
  items.splice(folded ?? index, folded === null ? 1 : 2);
}
