// The three inputs a pilot can fly with, each giving the same normalised axes and
// buttons: on-screen twin sticks (nipplejs, for touch and mouse), the keyboard, and a
// gamepad through the Gamepad API. Each also says why it cannot be trusted right now
// (a gamepad gone or frozen), and then the pilot panel stops sending.
import nipplejs from "nipplejs";
import { type Axes, type AxisName, CENTRED, clampUnit } from "./shaping";

/** MANUAL_CONTROL button bits the agent acts on (vehicle_agents/control/manual.py). */
export const BUTTON_SELECT = 1 << 0;
export const BUTTON_HOLD = 1 << 1;

export type SourceName = "touch" | "keyboard" | "gamepad";

export interface Reading {
  axes: Axes;
  buttons: number;
}

export interface InputSource {
  readonly name: SourceName;
  read(nowMs: number): Reading;
  /** Why this input must not be streamed now, or null. */
  problem(nowMs: number): string | null;
  destroy(): void;
}

/** A button pressed on the page is held this long, so a frame at 25 Hz carries it. */
const PRESS_MS = 150;

class Presses {
  private until = new Map<number, number>();
  press(bit: number): void {
    this.until.set(bit, performance.now() + PRESS_MS);
  }
  bits(nowMs: number): number {
    let bits = 0;
    for (const [bit, until] of this.until) if (nowMs < until) bits |= bit;
    return bits;
  }
}

// ------------------------------------------------------------------ twin sticks

/** Mode 2 sticks: left throttle (up) and yaw (right), right pitch (forward) and roll (right). */
export class TouchSticks implements InputSource {
  readonly name = "touch";
  private axes: Axes = { ...CENTRED };
  private readonly collections: ReturnType<typeof nipplejs.create>[] = [];
  readonly presses = new Presses();

  constructor(left: HTMLElement, right: HTMLElement) {
    this.bind(left, "throttle", "yaw");
    this.bind(right, "pitch", "roll");
  }

  private bind(zone: HTMLElement, vertical: AxisName, horizontal: AxisName): void {
    const size = Math.max(60, Math.min(zone.clientWidth, zone.clientHeight, 140) - 20);
    const collection = nipplejs.create({
      zone,
      mode: "static",
      position: { left: "50%", top: "50%" },
      size,
      color: "#4b8bd6",
      restOpacity: 0.8,
    });
    collection.on("move", (event) => {
      const data = event.data;
      const reach = Math.min(1, data.distance / (size / 2));
      // nipplejs' vector: unit length, y up.
      this.axes[vertical] = clampUnit(data.vector.y * reach);
      this.axes[horizontal] = clampUnit(data.vector.x * reach);
    });
    collection.on("end", () => {
      this.axes[vertical] = 0;
      this.axes[horizontal] = 0;
    });
    this.collections.push(collection);
  }

  read(nowMs: number): Reading {
    return { axes: { ...this.axes }, buttons: this.presses.bits(nowMs) };
  }

  problem(): string | null {
    return null; // the page's own liveness (hidden, blurred) covers a hand held still
  }

  destroy(): void {
    for (const collection of this.collections) collection.destroy();
  }
}

// ------------------------------------------------------------------ keyboard

/** Keys to (axis, direction): WASD pitch and roll, the arrows throttle and yaw. */
const KEY_AXES: Record<string, [AxisName, number]> = {
  KeyW: ["pitch", 1],
  KeyS: ["pitch", -1],
  KeyA: ["roll", -1],
  KeyD: ["roll", 1],
  ArrowUp: ["throttle", 1],
  ArrowDown: ["throttle", -1],
  ArrowLeft: ["yaw", -1],
  ArrowRight: ["yaw", 1],
};

export interface KeyboardSettings {
  /** How much each press (and each auto-repeat) adds, as the seed's keyboard stepped. */
  step: number;
  /** The most a held key reaches. */
  sensitivity: number;
}

export class KeyboardInput implements InputSource {
  readonly name = "keyboard";
  private axes: Axes = { ...CENTRED };
  private readonly held = new Set<string>();
  private readonly presses = new Presses();
  private readonly listeners = new AbortController();

  constructor(public settings: KeyboardSettings) {
    const options = { signal: this.listeners.signal };
    window.addEventListener("keydown", (event) => this.onKey(event, true), options);
    window.addEventListener("keyup", (event) => this.onKey(event, false), options);
    // A key released while the window had no focus sends no keyup.
    window.addEventListener("blur", () => this.releaseAll(), options);
  }

  private onKey(event: KeyboardEvent, down: boolean): void {
    const target = event.target as HTMLElement | null;
    if (target && ["INPUT", "SELECT", "TEXTAREA"].includes(target.tagName)) return;
    if (event.code === "Space" || event.code === "KeyH") {
      if (down && !event.repeat) this.presses.press(event.code === "Space" ? BUTTON_SELECT : BUTTON_HOLD);
      event.preventDefault();
      return;
    }
    const mapping = KEY_AXES[event.code];
    if (!mapping) return;
    event.preventDefault(); // the arrows would scroll the page
    const [axis, direction] = mapping;
    if (down) {
      this.held.add(event.code);
      const limit = this.settings.sensitivity;
      const next = this.axes[axis] + direction * this.settings.step;
      this.axes[axis] = Math.max(-limit, Math.min(limit, next));
    } else {
      this.held.delete(event.code);
      const stillHeld = [...this.held].some((code) => KEY_AXES[code]?.[0] === axis);
      if (!stillHeld) this.axes[axis] = 0;
    }
  }

  private releaseAll(): void {
    this.held.clear();
    this.axes = { ...CENTRED };
  }

  read(nowMs: number): Reading {
    return { axes: { ...this.axes }, buttons: this.presses.bits(nowMs) };
  }

  problem(): string | null {
    return null;
  }

  destroy(): void {
    this.listeners.abort();
  }
}

// ------------------------------------------------------------------ gamepad

export interface AxisMapping {
  axis: number;
  invert: boolean;
}
export interface GamepadMapping {
  axes: Record<AxisName, AxisMapping>;
  select: number;
  hold: number;
}

/** The standard mapping in mode 2: left stick throttle and yaw, right stick pitch and roll. */
export function defaultGamepadMapping(): GamepadMapping {
  return {
    axes: {
      throttle: { axis: 1, invert: true },
      yaw: { axis: 0, invert: false },
      pitch: { axis: 3, invert: true },
      roll: { axis: 2, invert: false },
    },
    select: 0,
    hold: 1,
  };
}

/** Same off-centre values this long: frozen (the agent's own limit is 3 s). */
export const GAMEPAD_FROZEN_MS = 2500;
const CENTRE_TOLERANCE = 0.1;

export class GamepadInput implements InputSource {
  readonly name = "gamepad";
  private lastKey = "";
  private unchangedSince = 0;
  private offCentre = false;

  constructor(
    public mapping: GamepadMapping,
    private readonly getGamepads: () => (Gamepad | null)[] = () => navigator.getGamepads(),
  ) {}

  pad(): Gamepad | null {
    return this.getGamepads().find((pad) => pad?.connected) ?? null;
  }

  read(nowMs: number): Reading {
    const pad = this.pad();
    if (!pad) return { axes: { ...CENTRED }, buttons: 0 };
    const axes = { ...CENTRED };
    for (const [axis, map] of Object.entries(this.mapping.axes) as [AxisName, AxisMapping][]) {
      const value = pad.axes[map.axis] ?? 0;
      axes[axis] = clampUnit(map.invert ? -value : value);
    }
    let buttons = 0;
    if (pad.buttons[this.mapping.select]?.pressed) buttons |= BUTTON_SELECT;
    if (pad.buttons[this.mapping.hold]?.pressed) buttons |= BUTTON_HOLD;
    // Frozen: the raw values (and the pad's own timestamp) unchanged while off centre.
    const key = `${pad.timestamp}|${pad.axes.join(",")}|${pad.buttons.map((b) => (b.pressed ? 1 : 0)).join("")}`;
    if (key !== this.lastKey) {
      this.lastKey = key;
      this.unchangedSince = nowMs;
    }
    this.offCentre = Object.values(axes).some((value) => Math.abs(value) > CENTRE_TOLERANCE);
    return { axes, buttons };
  }

  problem(nowMs: number): string | null {
    if (!this.pad()) return "gamepad disconnected";
    if (this.offCentre && this.unchangedSince > 0 && nowMs - this.unchangedSince > GAMEPAD_FROZEN_MS) {
      return `gamepad frozen: the same off-centre values for ${((nowMs - this.unchangedSince) / 1000).toFixed(1)} s`;
    }
    return null;
  }

  destroy(): void {}
}

/** What the pilot picks from, in words. */
export const SOURCE_LABELS: Record<SourceName, string> = {
  touch: "On-screen sticks",
  keyboard: "Keyboard (WASD, arrows)",
  gamepad: "Gamepad",
};

/** Starts reading the named input (the touch sticks in the two zones given). */
export function openSource(name: SourceName, zones: readonly [HTMLElement, HTMLElement], keyboard: KeyboardSettings, mapping: GamepadMapping): InputSource {
  if (name === "touch") return new TouchSticks(zones[0], zones[1]);
  if (name === "keyboard") return new KeyboardInput(keyboard);
  return new GamepadInput(mapping);
}
