import { describe, expect, it } from "vitest";
import {
  type AxisShape,
  CENTRED,
  Shaper,
  applyDeadzone,
  applyExpo,
  clampUnit,
  defaultShaping,
  shapeAxis,
  toManualAxes,
} from "./shaping";

const linear: AxisShape = { deadzone: 0, expo: 0, slewPerS: 100, max: 1 };

describe("stick shaping", () => {
  it("clamps to [-1, 1] and turns NaN and infinities into centre", () => {
    expect(clampUnit(1.5)).toBe(1);
    expect(clampUnit(-3)).toBe(-1);
    expect(clampUnit(0.25)).toBe(0.25);
    expect(clampUnit(Number.NaN)).toBe(0);
    expect(clampUnit(Number.POSITIVE_INFINITY)).toBe(0);
  });

  it("centres inputs within the dead zone and rescales the rest to full travel", () => {
    expect(applyDeadzone(0.05, 0.1)).toBe(0);
    expect(applyDeadzone(-0.1, 0.1)).toBe(0);
    expect(applyDeadzone(1, 0.1)).toBeCloseTo(1);
    expect(applyDeadzone(-1, 0.1)).toBeCloseTo(-1);
    expect(applyDeadzone(0.55, 0.1)).toBeCloseTo(0.5);
  });

  it("softens the centre with expo but keeps the ends and the sign", () => {
    expect(applyExpo(1, 0.7)).toBeCloseTo(1);
    expect(applyExpo(-1, 0.7)).toBeCloseTo(-1);
    expect(applyExpo(0.5, 0)).toBe(0.5);
    expect(applyExpo(0.5, 1)).toBeCloseTo(0.125);
    expect(Math.abs(applyExpo(0.3, 0.5))).toBeLessThan(0.3);
    expect(applyExpo(-0.3, 0.5)).toBeCloseTo(-applyExpo(0.3, 0.5));
  });

  it("scales by the axis maximum after the curve", () => {
    expect(shapeAxis(1, { ...linear, max: 0.5 })).toBeCloseTo(0.5);
    expect(shapeAxis(2, linear)).toBe(1); // out-of-range input is clamped first
    expect(shapeAxis(0.04, defaultShaping().pitch)).toBe(0); // inside the default dead zone
  });

  it("limits how fast each axis moves, per second of elapsed time", () => {
    const shaping = defaultShaping();
    for (const shape of Object.values(shaping)) Object.assign(shape, { ...linear, slewPerS: 2 });
    const shaper = new Shaper(shaping);
    const full = { ...CENTRED, pitch: 1, yaw: -1 };
    expect(shaper.shape(full, 0.1)).toEqual({ pitch: 0.2, roll: 0, throttle: 0, yaw: -0.2 });
    const second = shaper.shape(full, 0.1);
    expect(second.pitch).toBeCloseTo(0.4);
    expect(second.yaw).toBeCloseTo(-0.4);
    expect(shaper.shape(full, 10).pitch).toBe(1); // reaches the target, never past it
    expect(shaper.shape(full, -1).pitch).toBe(1); // a negative step does not move it
    shaper.reset();
    expect(shaper.shape(CENTRED, 0.1)).toEqual(CENTRED);
  });

  it("maps to MANUAL_CONTROL's ranges: ±1000, throttle 0..1000 with mid stick at 500", () => {
    expect(toManualAxes({ pitch: 1, roll: -1, throttle: 0, yaw: 0.5 }, 3)).toEqual({ x: 1000, y: -1000, z: 500, r: 500, buttons: 3 });
    expect(toManualAxes({ ...CENTRED, throttle: -1 }, 0).z).toBe(0);
    expect(toManualAxes({ ...CENTRED, throttle: 1 }, 0).z).toBe(1000);
    expect(toManualAxes({ ...CENTRED, pitch: Number.NaN }, 0x1_0001).x).toBe(0);
    expect(toManualAxes(CENTRED, 0x1_0001).buttons).toBe(1); // 16 button bits only
  });
});
