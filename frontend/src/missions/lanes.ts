// Which of a mission's places get a numbered marker. A short mission numbers every one. A
// long one (a survey's lanes) numbers where the path starts, ends and turns, every take-
// off, landing and return, and the items marked key (active, refused): a number on each of
// a survey's 95 items drew a pile of circles, not lanes. Turns closer on screen than a
// marker's width to a number already drawn are left for the operator to zoom in to.
import type * as L from "leaflet";
import { CMD, type MissionItem } from "./model";

export interface PlacedItem {
  item: MissionItem;
  /** 1 is the first item after home. */
  seq: number;
  at: L.LatLng;
  /** Always numbered (the active item, a refused one). */
  key: boolean;
  movable: boolean;
}

/** More places than this and the mission is drawn as lanes. */
export const LONG_MISSION = 20;
/** A change of heading of at least this many degrees is a turn. */
const TURN_DEG = 30;
/** A turn's number is drawn only this many pixels clear of every other number. */
const MIN_GAP_PX = 28;

const ALWAYS = new Set<number>([CMD.TAKEOFF, CMD.LAND, CMD.RTL]);

/** The seqs to number; `toPixel` places a point on the screen at the map's zoom. */
export function numberedItems(
  placed: readonly PlacedItem[],
  toPixel: (at: L.LatLng) => { x: number; y: number },
): Set<number> {
  if (placed.length <= LONG_MISSION) return new Set(placed.map((place) => place.seq));
  const first = placed[0];
  const last = placed[placed.length - 1];
  const must = placed.filter((place) => place === first || place === last || place.key || ALWAYS.has(place.item.command));
  const turns = placed.filter((_, i) => i > 0 && i < placed.length - 1 && turnsAt(placed, i));
  const numbered = new Set(must.map((place) => place.seq));
  const drawn = must.map((place) => toPixel(place.at));
  for (const turn of turns) {
    if (numbered.has(turn.seq)) continue;
    const pixel = toPixel(turn.at);
    if (drawn.some((other) => Math.hypot(other.x - pixel.x, other.y - pixel.y) < MIN_GAP_PX)) continue;
    numbered.add(turn.seq);
    drawn.push(pixel);
  }
  return numbered;
}

/** Whether the path changes heading at place `i` (by its neighbours that are elsewhere). */
function turnsAt(placed: readonly PlacedItem[], i: number): boolean {
  const here = placed[i].at;
  const before = placed.slice(0, i).reverse().find((place) => !same(place.at, here));
  const after = placed.slice(i + 1).find((place) => !same(place.at, here));
  if (!before || !after) return false;
  const turn = Math.abs(heading(before.at, here) - heading(here, after.at)) % 360;
  return Math.min(turn, 360 - turn) >= TURN_DEG;
}

function same(a: L.LatLng, b: L.LatLng): boolean {
  return a.lat === b.lat && a.lng === b.lng;
}

/** Heading in degrees on a local flat map (east scaled by the latitude's cosine). */
function heading(from: L.LatLng, to: L.LatLng): number {
  const east = (to.lng - from.lng) * Math.cos((from.lat * Math.PI) / 180);
  return (Math.atan2(east, to.lat - from.lat) * 180) / Math.PI;
}
