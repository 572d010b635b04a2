// The change a refused lease names (ArduPilot's SYSID_MYGCS, PX4's COM_RC_IN_MODE), made
// by an admin: confirmed first, then written through the hub's audited parameter write.
import { ApiError, setParam } from "../hub/api";
import type { LeaseRefusal, ParamFix } from "../generated/protocol";

/** Asks the admin whether to make the change. */
export function confirmFix(vehicleId: string, refusal: LeaseRefusal, fix: ParamFix): boolean {
  return window.confirm(
    `Set ${fix.param} to ${fix.value} on ${vehicleId}?\n\n` +
      `Manual control was refused: ${refusal.reason}.\n\n` +
      "This changes a parameter on the flight controller (recorded in the audit log); control is then asked for again.",
  );
}

/** Writes the parameter; null when done, else why it failed, in words. */
export async function writeFix(vehicleId: string, fix: ParamFix): Promise<string | null> {
  try {
    await setParam(vehicleId, fix.param, fix.value);
    return null;
  } catch (error) {
    const why = error instanceof ApiError ? error.message : String(error);
    return `could not set ${fix.param}: ${why}`;
  }
}
