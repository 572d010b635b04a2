// What needs the operator's eye, per vehicle: battery, link age, GPS fix and the
// autopilot's estimator (EKF) health. Pure: the state, the clock and the levels in,
// a level and its reasons out; the views draw them on the row, the marker and the header.
import type { VehicleSummary } from "../hub/types";
import type { IconName } from "../ui/icons";

export type WarningLevel = "ok" | "warning" | "critical";
export type WarningKind = "battery" | "link" | "gps" | "ekf";

export interface Warning {
  kind: WarningKind;
  level: Exclude<WarningLevel, "ok">;
  text: string;
}

export interface WarningLevels {
  /** Percent of the pack left at or under which the battery is a warning. */
  batteryLowPercent: number;
  /** ... and critical. */
  batteryCriticalPercent: number;
  /** Seconds without telemetry before the link is stale (warning) and lost (critical). */
  linkStaleS: number;
  linkLostS: number;
}

export const DEFAULT_LEVELS: WarningLevels = {
  batteryLowPercent: 30,
  batteryCriticalPercent: 15,
  linkStaleS: 2,
  linkLostS: 5,
};

export interface VehicleWarnings {
  level: WarningLevel;
  warnings: Warning[];
}

/** The icon drawn with a level (beside the colour, for colour-blind eyes); none when ok. */
export const LEVEL_ICONS: Record<WarningLevel, IconName | null> = { ok: null, warning: "warning", critical: "critical" };

export function evaluate(
  vehicle: VehicleSummary,
  linkAgeS: number | null,
  levels: WarningLevels,
  /** The autopilot's own battery failsafe has triggered (its STATUSTEXT or failsafe event). */
  batteryFailsafe: boolean,
): VehicleWarnings {
  const warnings: Warning[] = [];
  const state = vehicle.state ?? null;

  if (!vehicle.connected) {
    warnings.push({ kind: "link", level: "critical", text: "agent offline" });
  } else if (state && !state.fcu_connected) {
    warnings.push({ kind: "link", level: "critical", text: "no link to the flight controller" });
  } else if (linkAgeS !== null && linkAgeS >= levels.linkLostS) {
    warnings.push({ kind: "link", level: "critical", text: `link lost: no telemetry for ${Math.round(linkAgeS)} s` });
  } else if (linkAgeS !== null && linkAgeS >= levels.linkStaleS) {
    warnings.push({ kind: "link", level: "warning", text: `link stale: no telemetry for ${linkAgeS.toFixed(1)} s` });
  }

  const percent = state?.battery_remaining;
  if (batteryFailsafe) {
    warnings.push({ kind: "battery", level: "critical", text: "battery failsafe (the autopilot's)" });
  } else if (percent !== null && percent !== undefined && percent >= 0) {
    if (percent <= levels.batteryCriticalPercent) {
      warnings.push({ kind: "battery", level: "critical", text: `battery critical: ${Math.round(percent)}%` });
    } else if (percent <= levels.batteryLowPercent) {
      warnings.push({ kind: "battery", level: "warning", text: `battery low: ${Math.round(percent)}%` });
    }
  }

  if (state && state.gps_fix < 3) {
    // A rover or a copter in a manual mode may run without a fix: a warning, not critical.
    warnings.push({ kind: "gps", level: "warning", text: state.gps_fix < 2 ? "no GPS fix" : "2D GPS fix only" });
  }
  if (state && !state.armed && state.ready_to_fly === false) {
    warnings.push({ kind: "ekf", level: "warning", text: `not ready: ${state.not_ready_reason ?? "pre-arm checks fail"}` });
  }

  const level: WarningLevel = warnings.some((w) => w.level === "critical")
    ? "critical"
    : warnings.length > 0
      ? "warning"
      : "ok";
  return { level, warnings };
}

const STORAGE_KEY = "gcs.warningLevels";

/** The operator's levels, kept in this browser. */
export function loadLevels(): WarningLevels {
  try {
    const saved = JSON.parse(localStorage.getItem(STORAGE_KEY) ?? "null") as Partial<WarningLevels> | null;
    return validLevels({ ...DEFAULT_LEVELS, ...(saved ?? {}) }) ?? DEFAULT_LEVELS;
  } catch {
    return DEFAULT_LEVELS;
  }
}

export function saveLevels(levels: WarningLevels): void {
  localStorage.setItem(STORAGE_KEY, JSON.stringify(levels));
}

/** Null unless 0 ≤ critical < low ≤ 100. */
export function validLevels(levels: WarningLevels): WarningLevels | null {
  const { batteryLowPercent: low, batteryCriticalPercent: critical } = levels;
  if (![low, critical].every((v) => Number.isFinite(v))) return null;
  if (critical < 0 || low > 100 || critical >= low) return null;
  return levels;
}
