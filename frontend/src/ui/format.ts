// Display formatting for telemetry values. Missing values show as an em dash.
import type { VehicleState, VehicleSummary } from "../hub/types";

export const MISSING = "—";

type Num = number | null | undefined;

function fixed(value: Num, digits: number, unit: string): string {
  if (value === null || value === undefined || !Number.isFinite(value)) return MISSING;
  const text = value.toFixed(digits);
  // Avoid "-0.0" for tiny negative values.
  return `${Number(text) === 0 ? (0).toFixed(digits) : text} ${unit}`;
}

export const formatAltitude = (metres: Num): string => fixed(metres, 1, "m");
export const formatSpeed = (metresPerSecond: Num): string => fixed(metresPerSecond, 1, "m/s");

export function formatBattery(state: VehicleState | null | undefined): string {
  if (!state) return MISSING;
  const parts: string[] = [];
  const percent = state.battery_remaining;
  if (percent !== null && percent !== undefined && percent >= 0) parts.push(`${Math.round(percent)}%`);
  if (state.battery_voltage !== null && state.battery_voltage !== undefined) {
    parts.push(`${state.battery_voltage.toFixed(1)} V`);
  }
  return parts.length ? parts.join(" · ") : MISSING;
}

const FIX_NAMES = ["No GPS", "No fix", "2D", "3D", "DGPS", "RTK float", "RTK fixed", "Static", "PPP"];

export function formatGps(state: VehicleState | null | undefined): string {
  if (!state) return MISSING;
  const fix = FIX_NAMES[state.gps_fix] ?? `fix ${state.gps_fix}`;
  const sats = state.satellites;
  return sats === null || sats === undefined ? fix : `${fix} · ${sats} sats`;
}

/** "ARMED", or "disarmed" with whether it may take off: a good fix is not enough (the
 * autopilot's EKF may not use it yet); the reason, when not ready, is the cell's title. */
export function formatArmed(state: VehicleState | null | undefined): string {
  if (!state) return MISSING;
  if (state.armed) return "ARMED";
  if (state.ready_to_fly === true) return "disarmed · ready";
  if (state.ready_to_fly === false) return "disarmed · not ready";
  return "disarmed";
}

const LANDED_LABELS: Record<NonNullable<VehicleState["landed_state"]>, string> = {
  on_ground: "on ground",
  takeoff: "taking off",
  in_air: "in air",
  landing: "landing",
};

/** `landed_state`, the field that says whether it flies; "~" marks the agent's guess
 * (the autopilot does not report one). */
export function formatLanded(state: VehicleState | null | undefined): string {
  if (!state?.landed_state) return MISSING;
  const label = LANDED_LABELS[state.landed_state];
  return state.landed_state_source === "derived" ? `~${label}` : label;
}

export function isAirborne(state: VehicleState | null | undefined): boolean {
  return Boolean(state?.landed_state && state.landed_state !== "on_ground");
}

export function readinessTitle(state: VehicleState | null | undefined): string {
  if (!state || state.armed || state.ready_to_fly !== false) return formatArmed(state);
  return `Not ready to fly: ${state.not_ready_reason ?? "the autopilot's checks fail"}`;
}

export type LinkState = "online" | "no-fcu" | "offline";

export function linkState(vehicle: VehicleSummary): LinkState {
  if (!vehicle.connected) return "offline";
  if (vehicle.state && !vehicle.state.fcu_connected) return "no-fcu";
  return "online";
}

export const LINK_LABELS: Record<LinkState, string> = {
  online: "online",
  "no-fcu": "no FCU link",
  offline: "offline",
};

export function formatLastSeen(lastSeen: Num, now = Date.now() / 1000): string {
  if (lastSeen === null || lastSeen === undefined) return "never seen";
  const ago = Math.max(0, now - lastSeen);
  if (ago < 2) return "seen just now";
  if (ago < 120) return `seen ${Math.round(ago)} s ago`;
  if (ago < 7200) return `seen ${Math.round(ago / 60)} min ago`;
  return `seen ${new Date(lastSeen * 1000).toLocaleString()}`;
}
