// The height "Start mission" takes off to: the first take-off item's, else the first
// placed item's, in metres above home. A height the dashboard cannot know above home
// (above terrain, above sea level with no home altitude) or an empty one is refused with
// its reason: a missing height must never become a take-off to 0 m.
import * as mav from "../generated/mavlink";
import { CMD, type MissionItem, placeOf } from "./model";

export type TakeoffHeight = { metres: number; from: string } | { refused: string };

const RELATIVE = new Set<number>([mav.MAV_FRAME_GLOBAL_RELATIVE_ALT, mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT]);
const SEA_LEVEL = new Set<number>([mav.MAV_FRAME_GLOBAL, mav.MAV_FRAME_GLOBAL_INT]);
/** The take-off command's own floor (protocol/messages/commands.py: altitude > 0.5). */
const LOWEST_M = 0.5;

export function takeoffHeight(items: readonly MissionItem[], homeAltMsl: number | null | undefined): TakeoffHeight {
  const index = items.findIndex((item) => item.command === CMD.TAKEOFF);
  const at = index >= 0 ? index : items.findIndex((item) => placeOf(item) !== null);
  if (at < 0) return { refused: "the mission has no take-off item and no waypoint to take its height from" };
  const item = items[at];
  const from = `item ${at + 1}`;
  const alt = item.alt as number | null;
  if (alt === null || !Number.isFinite(alt)) return { refused: `${from} has no altitude` };
  let metres: number;
  if (RELATIVE.has(item.frame)) metres = alt;
  else if (SEA_LEVEL.has(item.frame) && homeAltMsl != null) metres = alt - homeAltMsl;
  else if (SEA_LEVEL.has(item.frame)) return { refused: `${from} is above sea level and the home altitude is not known yet` };
  else return { refused: `${from}'s altitude is not above home (frame ${item.frame}): take off by hand first` };
  if (!(metres > LOWEST_M)) return { refused: `${from} is ${metres.toFixed(1)} m above home: too low to take off to` };
  return { metres, from };
}
