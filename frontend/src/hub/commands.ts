// Runs an operator command and words the answer for the row's result area.
import { ApiError, sendCommand, violationsOf } from "./api";
import type { Command } from "./types";

export type ResultTone = "pending" | "accepted" | "refused" | "error";

export interface CommandFeedback {
  text: string;
  tone: ResultTone;
}

/** Told of every command sent, from any panel, with its answer to come. */
export type CommandListener = (vehicleId: string, command: Command, answer: Promise<CommandFeedback>) => void;
const listeners = new Set<CommandListener>();

/** Follows every command sent (the fleet row shows the latest one's answer); returns the unfollow. */
export function onCommandSent(listener: CommandListener): () => void {
  listeners.add(listener);
  return () => listeners.delete(listener);
}

export function runCommand(vehicleId: string, command: Command): Promise<CommandFeedback> {
  const answer = answerOf(vehicleId, command);
  for (const listener of listeners) listener(vehicleId, command, answer);
  return answer;
}

async function answerOf(vehicleId: string, command: Command): Promise<CommandFeedback> {
  try {
    const { outcome } = await sendCommand(vehicleId, command);
    if (outcome.status === "accepted") return { text: `${command.name}: accepted`, tone: "accepted" };
    const why = outcome.message ? ` — ${outcome.message}` : "";
    return { text: `${command.name}: ${outcome.status}${why}`, tone: "refused" };
  } catch (error) {
    // The hub's safety rails refused it before it reached the vehicle: name every rule broken.
    const violations = error instanceof ApiError ? violationsOf(error.body) : [];
    if (violations.length > 0) {
      const why = violations.map((violation) => violation.message).join("; ");
      return { text: `${command.name}: refused — ${why}`, tone: "refused" };
    }
    const message = error instanceof Error ? error.message : String(error);
    const status =
      error instanceof ApiError && error.status && message !== `HTTP ${error.status}` ? ` (HTTP ${error.status})` : "";
    return { text: `${command.name}: ${message}${status}`, tone: "error" };
  }
}
