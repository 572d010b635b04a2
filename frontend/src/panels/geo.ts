// Distances on the map for the panels: the great-circle (haversine) distance is within
// 0.5% of the ellipsoid's at the few kilometres a vehicle flies from home.
const EARTH_RADIUS_M = 6_371_008.8;

export function distanceM(lat1: number, lon1: number, lat2: number, lon2: number): number {
  const rad = Math.PI / 180;
  const dLat = (lat2 - lat1) * rad;
  const dLon = (lon2 - lon1) * rad;
  const a = Math.sin(dLat / 2) ** 2 + Math.cos(lat1 * rad) * Math.cos(lat2 * rad) * Math.sin(dLon / 2) ** 2;
  return 2 * EARTH_RADIUS_M * Math.asin(Math.min(1, Math.sqrt(a)));
}

/** The point `north` and `east` metres from (lat, lon), on the local tangent plane. */
export function offsetLatLon(lat: number, lon: number, north: number, east: number): [number, number] {
  const degrees = 180 / Math.PI / EARTH_RADIUS_M;
  return [lat + north * degrees, lon + (east * degrees) / Math.cos((lat * Math.PI) / 180)];
}
