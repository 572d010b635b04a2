// The pilot's settings, kept in this browser per operator and per vehicle (shaping,
// keyboard) or per operator (the gamepad's mapping: it is a property of the device).
import { type GamepadMapping, type KeyboardSettings, defaultGamepadMapping } from "./inputs";
import { AXES, type Shaping, defaultShaping } from "./shaping";

export interface PilotSettings {
  shaping: Shaping;
  keyboard: KeyboardSettings;
}

function load<T>(key: string, fallback: T, valid: (value: unknown) => boolean): T {
  try {
    const stored = JSON.parse(localStorage.getItem(key) ?? "null") as unknown;
    return stored !== null && valid(stored) ? (stored as T) : fallback;
  } catch {
    return fallback;
  }
}

const isNumber = (value: unknown) => typeof value === "number" && Number.isFinite(value);

function validSettings(value: unknown): boolean {
  const settings = value as PilotSettings;
  return (
    typeof settings === "object" &&
    AXES.every((axis) =>
      ["deadzone", "expo", "slewPerS", "max"].every((k) => isNumber((settings.shaping?.[axis] as unknown as Record<string, unknown>)?.[k])),
    ) &&
    isNumber(settings.keyboard?.step) &&
    isNumber(settings.keyboard?.sensitivity)
  );
}

export function loadSettings(user: string, vehicleId: string): PilotSettings {
  const fallback = { shaping: defaultShaping(), keyboard: { step: 0.25, sensitivity: 0.6 } };
  return load(`gcs.pilot.${user}.${vehicleId}`, fallback, validSettings);
}

export function saveSettings(user: string, vehicleId: string, settings: PilotSettings): void {
  localStorage.setItem(`gcs.pilot.${user}.${vehicleId}`, JSON.stringify(settings));
}

export function loadMapping(user: string): GamepadMapping {
  return load(`gcs.pilot.${user}.gamepad`, defaultGamepadMapping(), (value) => {
    const mapping = value as GamepadMapping;
    return AXES.every((axis) => isNumber(mapping.axes?.[axis]?.axis)) && isNumber(mapping.select);
  });
}

export function saveMapping(user: string, mapping: GamepadMapping): void {
  localStorage.setItem(`gcs.pilot.${user}.gamepad`, JSON.stringify(mapping));
}
