// The pilot panel's status line in words, from what the panel is doing: flying, asking
// for control, fixing a refusal's cause, refused, or stopped (and why).
import type { LeaseRefusal } from "../generated/protocol";

export interface PilotActivity {
  /** The input being flown with, while frames go out. */
  sendingWith: string | null;
  asking: boolean;
  /** What the fix button is doing or why it failed. */
  fixNote: string | null;
  refusal: LeaseRefusal | undefined;
  isAdmin: boolean;
  stoppedWhy: string | null;
}

export interface StatusLine {
  text: string;
  /** `data-state` of the line, for styles and tests. */
  state: "idle" | "sending" | "asking" | "refused" | "stopped";
}

/** Idle: nobody flies this vehicle from here (it may well be in the air, under its autopilot). */
export const NOT_FLOWN = "not flown by hand";

export function statusLine(activity: PilotActivity): StatusLine {
  const { refusal } = activity;
  if (activity.sendingWith !== null) return { text: `flying with ${activity.sendingWith}, 25 Hz`, state: "sending" };
  if (activity.asking) return { text: "asking for control…", state: "asking" };
  if (activity.fixNote) return { text: activity.fixNote, state: "refused" };
  if (refusal) {
    let text = `control refused: ${refusal.reason}`;
    if (refusal.fix && !activity.isAdmin) text += " — an admin can make this change from this panel";
    return { text, state: "refused" };
  }
  if (activity.stoppedWhy) return { text: `stopped: ${activity.stoppedWhy} — the vehicle holds`, state: "stopped" };
  return { text: NOT_FLOWN, state: "idle" };
}
