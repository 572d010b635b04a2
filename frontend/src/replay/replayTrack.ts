// The replay's model of one flight: its samples on a clock that counts seconds
// from the start of the flight, and what the vehicle was doing at any moment of
// it (position and heading interpolated between samples). No DOM, no Leaflet.
import type { Flight, FlightSample } from "../hub/types";

export interface ReplayPoint {
  /** Seconds since the flight's start. */
  t: number;
  lat: number;
  lon: number;
  /** Null when the vehicle reported none near this moment. */
  heading: number | null;
}

/** What the replay shows at one moment. */
export interface ReplayState {
  t: number;
  position: ReplayPoint | null;
  altRel: number | null;
  groundspeed: number | null;
  batteryRemaining: number | null;
  batteryVoltage: number | null;
  mode: string | null;
  armed: boolean | null;
}

type NumericField = "alt_rel" | "groundspeed";

function finite(value: number | null | undefined): value is number {
  return value !== null && value !== undefined && Number.isFinite(value);
}

/** The last index whose time is <= `t` in an ascending list, or -1. */
export function indexAtOrBefore(times: ArrayLike<number>, t: number): number {
  let low = 0;
  let high = times.length - 1;
  let found = -1;
  while (low <= high) {
    const middle = (low + high) >> 1;
    if (times[middle] <= t) {
      found = middle;
      low = middle + 1;
    } else {
      high = middle - 1;
    }
  }
  return found;
}

/** The shortest way round from `a` to `b`, `f` of the way (degrees, 0..360). */
export function lerpAngle(a: number, b: number, f: number): number {
  const delta = ((((b - a) % 360) + 540) % 360) - 180;
  return (((a + delta * f) % 360) + 360) % 360;
}

/** `HH:MM:SS` for a number of seconds (negative and NaN read as zero). */
export function formatClock(seconds: number): string {
  const total = Number.isFinite(seconds) && seconds > 0 ? Math.floor(seconds) : 0;
  const pad = (value: number) => String(value).padStart(2, "0");
  return `${pad(Math.floor(total / 3600))}:${pad(Math.floor(total / 60) % 60)}:${pad(total % 60)}`;
}

export class FlightTrack {
  /** Unix seconds of replay time 0. */
  readonly origin: number;
  /** Seconds from replay time 0 to the end of the flight. */
  readonly duration: number;
  /** Every sample's time, in seconds since `origin`. */
  readonly times: Float64Array;
  /** The samples that have a position (the drawn track). */
  readonly points: ReplayPoint[];
  private readonly pointTimes: Float64Array;

  constructor(
    readonly flight: Flight,
    readonly samples: FlightSample[],
  ) {
    const first = samples.length > 0 ? samples[0].time : flight.start_time;
    const last = samples.length > 0 ? samples[samples.length - 1].time : flight.start_time;
    this.origin = Math.min(flight.start_time, first);
    const end = Math.max(flight.end_time ?? last, last);
    this.duration = Math.max(0, end - this.origin);
    this.times = Float64Array.from(samples, (sample) => sample.time - this.origin);
    this.points = [];
    samples.forEach((sample, index) => {
      if (!finite(sample.lat) || !finite(sample.lon)) return;
      // A flight controller without a fix reports 0,0: not a place the vehicle was.
      if (sample.lat === 0 && sample.lon === 0) return;
      this.points.push({
        t: this.times[index],
        lat: sample.lat,
        lon: sample.lon,
        heading: finite(sample.heading_deg) ? sample.heading_deg : null,
      });
    });
    this.pointTimes = Float64Array.from(this.points, (point) => point.t);
  }

  get isEmpty(): boolean {
    return this.samples.length === 0;
  }

  clamp(t: number): number {
    return Math.min(Math.max(Number.isFinite(t) ? t : 0, 0), this.duration);
  }

  /** Where the vehicle was at `t`, interpolated between the two samples around it. */
  positionAt(t: number): ReplayPoint | null {
    const points = this.points;
    if (points.length === 0) return null;
    const index = indexAtOrBefore(this.pointTimes, t);
    if (index < 0) return { ...points[0], t };
    if (index >= points.length - 1) return { ...points[points.length - 1], t };
    const a = points[index];
    const b = points[index + 1];
    const span = b.t - a.t;
    const f = span > 0 ? (t - a.t) / span : 0;
    let heading: number | null;
    if (a.heading !== null && b.heading !== null) heading = lerpAngle(a.heading, b.heading, f);
    else heading = f < 0.5 ? a.heading : b.heading;
    return { t, lat: a.lat + (b.lat - a.lat) * f, lon: a.lon + (b.lon - a.lon) * f, heading };
  }

  /** Everything the replay shows at `t`: measured values interpolated, modes as last reported. */
  stateAt(t: number): ReplayState {
    const index = indexAtOrBefore(this.times, t);
    const sample = index >= 0 ? this.samples[index] : this.samples[0];
    return {
      t,
      position: this.positionAt(t),
      altRel: this.interpolate("alt_rel", index, t),
      groundspeed: this.interpolate("groundspeed", index, t),
      batteryRemaining:
        finite(sample?.battery_remaining) && sample.battery_remaining >= 0 ? sample.battery_remaining : null,
      batteryVoltage: finite(sample?.battery_voltage) ? sample.battery_voltage : null,
      mode: sample?.mode ?? null,
      armed: sample?.armed ?? null,
    };
  }

  private interpolate(field: NumericField, index: number, t: number): number | null {
    const samples = this.samples;
    if (samples.length === 0) return null;
    if (index < 0) return samples[0][field];
    const a = samples[index][field];
    const next = samples[index + 1];
    if (!next || !finite(a) || !finite(next[field])) return a;
    const span = this.times[index + 1] - this.times[index];
    const f = span > 0 ? (t - this.times[index]) / span : 0;
    return a + (next[field] - a) * f;
  }
}
