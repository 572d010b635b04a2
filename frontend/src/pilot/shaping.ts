// Stick shaping, the same for every input: dead zone, expo curve, maximum and a slew-rate
// limit per axis, so that a keyboard's steps and a twitchy thumb become smooth commands.
// Pure functions plus one small stateful slew limiter; no DOM.
import type { ManualAxes } from "../generated/protocol";

export const AXES = ["pitch", "roll", "throttle", "yaw"] as const;
export type AxisName = (typeof AXES)[number];

/** Normalised axes, each in [-1, 1]: pitch forward +, roll right +, throttle up +, yaw clockwise +. */
export type Axes = Record<AxisName, number>;

export interface AxisShape {
  /** Inputs within this of centre are centre. */
  deadzone: number;
  /** 0 linear, 1 cubic: fine control near centre. */
  expo: number;
  /** The most the output may change per second (full travel is 2). */
  slewPerS: number;
  /** Output scale: 0.5 flies at half the autopilot's stick speed. */
  max: number;
}
export type Shaping = Record<AxisName, AxisShape>;

export const CENTRED: Axes = { pitch: 0, roll: 0, throttle: 0, yaw: 0 };

export function defaultShaping(): Shaping {
  const shape = (): AxisShape => ({ deadzone: 0.05, expo: 0.3, slewPerS: 4, max: 1 });
  return { pitch: shape(), roll: shape(), throttle: shape(), yaw: shape() };
}

function finite(value: number): number {
  return Number.isFinite(value) ? value : 0; // never send NaN: the hub refuses it anyway
}

export function clampUnit(value: number): number {
  return Math.max(-1, Math.min(1, finite(value)));
}

export function applyDeadzone(value: number, deadzone: number): number {
  const magnitude = Math.abs(value);
  if (magnitude <= deadzone) return 0;
  return (Math.sign(value) * (magnitude - deadzone)) / (1 - deadzone);
}

export function applyExpo(value: number, expo: number): number {
  return (1 - expo) * value + expo * value * value * value;
}

/** One axis's shaped target, before the slew limit. */
export function shapeAxis(value: number, shape: AxisShape): number {
  return clampUnit(applyExpo(applyDeadzone(clampUnit(value), shape.deadzone), shape.expo) * shape.max);
}

/** Holds the last output so each axis moves towards its target at most `slewPerS`. */
export class Shaper {
  private last: Axes = { ...CENTRED };

  constructor(public shaping: Shaping) {}

  shape(raw: Axes, dtS: number): Axes {
    const out = { ...CENTRED };
    for (const axis of AXES) {
      const shape = this.shaping[axis];
      const target = shapeAxis(raw[axis], shape);
      const step = Math.max(0, shape.slewPerS) * Math.max(0, dtS);
      const previous = this.last[axis];
      out[axis] = previous + Math.max(-step, Math.min(step, target - previous));
    }
    this.last = out;
    return out;
  }

  reset(): void {
    this.last = { ...CENTRED };
  }
}

/** MAVLink MANUAL_CONTROL's ranges: x, y, r in -1000..1000; z 0..1000 with 500 at mid stick. */
export function toManualAxes(axes: Axes, buttons: number): ManualAxes {
  const scale = (value: number) => Math.round(clampUnit(value) * 1000);
  return {
    x: scale(axes.pitch),
    y: scale(axes.roll),
    z: Math.round(500 + clampUnit(axes.throttle) * 500),
    r: scale(axes.yaw),
    buttons: buttons & 0xffff,
  };
}
