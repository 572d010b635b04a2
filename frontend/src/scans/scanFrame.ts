// A subscriber's binary scan frame (protocol/scans.py): "GSCV", the vehicle id, then the
// agent's scan frame, little-endian. Its returns are placed as the hub places them: a
// pose per beam, interpolated between the turn's start and end, through the sensor's
// mount and the body's attitude. Near the vehicle (12 m at most) metres become degrees
// on the local sphere, which is centimetre-exact at that range.

const CLIENT_MAGIC = "GSCV";
const SCAN_MAGIC = "GSCN";
const HEADER_BYTES = 140;
const EARTH_RADIUS_M = 6_371_008.8;

export interface ScanPoints {
  vehicleId: string;
  seq: number;
  /** UTC of the first beam, Unix seconds. */
  time: number;
  /** [latitude, longitude] of each return. */
  points: [number, number][];
}

interface Pose {
  lat: number;
  lon: number;
  roll: number;
  pitch: number;
  yaw: number;
}

type Matrix = [number, number, number, number, number, number, number, number, number];

function magic(view: DataView, at: number): string {
  return String.fromCharCode(...[0, 1, 2, 3].map((i) => view.getUint8(at + i)));
}

function pose(view: DataView, at: number): Pose {
  return {
    lat: view.getFloat64(at, true),
    lon: view.getFloat64(at + 8, true),
    roll: view.getFloat32(at + 20, true),
    pitch: view.getFloat32(at + 24, true),
    yaw: view.getFloat32(at + 28, true),
  };
}

/** ZYX Euler angles as a rotation of the body's axes into the parent's (row-major). */
function rotation(roll: number, pitch: number, yaw: number): Matrix {
  const [cr, sr, cp, sp, cy, sy] = [Math.cos(roll), Math.sin(roll), Math.cos(pitch), Math.sin(pitch), Math.cos(yaw), Math.sin(yaw)];
  return [
    cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr,
    sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr,
    -sp, cp * sr, cp * cr,
  ];
}

function apply(m: Matrix, x: number, y: number, z: number): [number, number, number] {
  return [m[0] * x + m[1] * y + m[2] * z, m[3] * x + m[4] * y + m[5] * z, m[6] * x + m[7] * y + m[8] * z];
}

function wrap(angle: number): number {
  return ((((angle + Math.PI) % (2 * Math.PI)) + 2 * Math.PI) % (2 * Math.PI)) - Math.PI;
}

/** The frame's returns, or null for anything that is not a subscriber's scan frame. */
export function decodeScan(data: ArrayBuffer): ScanPoints | null {
  const view = new DataView(data);
  if (data.byteLength < 5 || magic(view, 0) !== CLIENT_MAGIC) return null;
  const idLength = view.getUint8(4);
  const vehicleId = new TextDecoder().decode(new Uint8Array(data, 5, idLength));
  const at = 5 + idLength;
  if (data.byteLength < at + HEADER_BYTES || magic(view, at) !== SCAN_MAGIC) return null;
  const beams = view.getUint16(at + 6, true);
  if (data.byteLength !== at + HEADER_BYTES + 2 * beams) return null;
  const seq = Number(view.getBigUint64(at + 8, true));
  const time = view.getFloat64(at + 24, true);
  const angleMin = view.getFloat32(at + 36, true);
  const increment = view.getFloat32(at + 40, true);
  const scale = view.getFloat32(at + 44, true);
  const start = pose(view, at + 52);
  const end = pose(view, at + 84);
  const m = [0, 1, 2, 3, 4, 5].map((i) => view.getFloat32(at + 116 + 4 * i, true));
  const mount = rotation(m[3], m[4], m[5]);
  const points: [number, number][] = [];
  for (let i = 0; i < beams; i++) {
    const raw = view.getUint16(at + HEADER_BYTES + 2 * i, true);
    if (raw === 0) continue; // no return
    const r = raw * scale;
    const share = i / beams;
    const a = angleMin + i * increment;
    // The sensor's x forward, y left, z up; as forward-right-down, then on the body.
    const [fx, fy, fz] = apply(mount, r * Math.cos(a), -r * Math.sin(a), 0);
    const attitude = rotation(
      start.roll + wrap(end.roll - start.roll) * share,
      start.pitch + wrap(end.pitch - start.pitch) * share,
      start.yaw + wrap(end.yaw - start.yaw) * share,
    );
    const [north, east] = apply(attitude, fx + m[0], fy + m[1], fz + m[2]);
    const lat = start.lat + (end.lat - start.lat) * share;
    const lon = start.lon + (end.lon - start.lon) * share;
    const degrees = 180 / Math.PI / EARTH_RADIUS_M;
    points.push([lat + north * degrees, lon + (east * degrees) / Math.cos((lat * Math.PI) / 180)]);
  }
  return { vehicleId, seq, time, points };
}
