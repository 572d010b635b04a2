// Where the followers' slots are on the map: each slot's offset (common/formation.py's
// Offset: forward and right of the leader's heading, or north and east) around where the
// leader is. A vehicle leader is where it reports; a virtual leader is where its route
// puts it, timed as the hub's LeaderRoute (backend/formation/route.py): straight
// legs at the speed, a pause at each waypoint, the clock started once the followers formed.
import { offsetLatLon } from "../panels/geo";
import type { Offset, RoutePoint } from "./api";

const EARTH_RADIUS_M = 6_371_008.8;

export interface LeaderPose {
  lat: number;
  lon: number;
  /** Clockwise from north. */
  headingRad: number;
}

/** Each follower's slot as [lat, lon] around the leader. */
export function slotPlaces(leader: LeaderPose, slots: Record<string, Offset>): Map<string, [number, number]> {
  const places = new Map<string, [number, number]>();
  const c = Math.cos(leader.headingRad);
  const s = Math.sin(leader.headingRad);
  for (const [vehicleId, slot] of Object.entries(slots)) {
    const [north, east] = slot.frame === "ne" ? [slot.x, slot.y] : [slot.x * c - slot.y * s, slot.x * s + slot.y * c];
    places.set(vehicleId, offsetLatLon(leader.lat, leader.lon, north, east));
  }
  return places;
}

/** A virtual leader's pose `t` seconds into its route (0 until it formed). */
export function routePose(route: readonly RoutePoint[], speedMs: number, pauseS: number, t: number): LeaderPose {
  const rad = Math.PI / 180;
  const { lat: lat0, lon: lon0 } = route[0];
  const local = (p: RoutePoint): [number, number] => [
    (p.lat - lat0) * rad * EARTH_RADIUS_M,
    (p.lon - lon0) * rad * EARTH_RADIUS_M * Math.cos(lat0 * rad),
  ];
  let start = pauseS;
  let heading = 0;
  for (let i = 1; i < route.length; i++) {
    const [n0, e0] = local(route[i - 1]);
    const [n1, e1] = local(route[i]);
    const horizontal = Math.hypot(n1 - n0, e1 - e0);
    const duration = Math.max(horizontal, Math.abs(route[i].alt_m - route[i - 1].alt_m)) / speedMs;
    heading = (Math.atan2(e1 - e0, n1 - n0) + 2 * Math.PI) % (2 * Math.PI);
    const at = (share: number): LeaderPose => ({
      lat: route[i - 1].lat + (route[i].lat - route[i - 1].lat) * share,
      lon: route[i - 1].lon + (route[i].lon - route[i - 1].lon) * share,
      headingRad: heading,
    });
    if (t < start) return at(0); // pausing at the leg's start, already facing along it
    if (t < start + duration) return at((t - start) / duration);
    start += duration + pauseS;
  }
  const last = route[route.length - 1];
  return { lat: last.lat, lon: last.lon, headingRad: heading };
}
