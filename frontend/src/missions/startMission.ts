// "Start mission": the sequence that starts a drawn mission, as one action, each step's
// answer in a list and the first refusal ending it with its reason. A drawn mission has no
// start of its own: ArduPilot refuses to arm in AUTO, and armed in STABILIZE it disarms
// itself after a few seconds. What works (QGroundControl's own order for a copter):
//   1. read the mission on board and have the hub's rails check it (`mission-check`);
//   2. the guided mode (ArduPilot's GUIDED), then arm. PX4 has no such mode to arm in:
//      its OFFBOARD refuses to engage without a setpoint stream, and its take-off command
//      switches to TAKEOFF by itself, so on PX4 the vehicle arms in the mode it is in;
//   3. take off to the mission's first height (startHeight.ts: never a made-up 0 m);
//   4. wait, bounded and shown, until airborne near that height (steps 2-4 skipped for a
//      vehicle already in the air);
//   5. the mission mode: AUTO on ArduPilot, MISSION on PX4 (protocol/mission_rules.py).
// A sequence of the hub's own endpoints rather than one endpoint: each command is audited
// and held to the rails as the operator's own, and each answer shows as it comes.
import { runCommand } from "../hub/commands";
import type { Command, VehicleSummary } from "../hub/types";
import { button, el } from "../ui/dom";
import { isAirborne } from "../ui/format";
import { checkMission } from "./api";
import { takeoffHeight } from "./startHeight";
import { missionOnBoard } from "./vehicleMissions";

/** ArduPilot's mode for arming before a take-off command (not PX4's OFFBOARD: above). */
const GUIDED_MODE = "GUIDED";
const MISSION_MODES = ["AUTO", "MISSION"];
const CLIMB_POLL_MS = 250;
/** Bounded: a climb of `height` metres gets this long plus CLIMB_S_PER_M each metre. */
const CLIMB_BASE_S = 20;
const CLIMB_S_PER_M = 3;

type StepState = "running" | "ok" | "refused";

class Refused extends Error {}

export class StartMission {
  readonly element: HTMLElement;
  private readonly startButton: HTMLButtonElement;
  private readonly steps: HTMLOListElement;
  private running = false;

  constructor(private readonly vehicle: () => VehicleSummary | undefined) {
    this.element = el("div", "mission-start", "mission-start");
    this.startButton = button(
      "mission-start",
      "Start mission",
      "Check the mission on board, arm in the guided mode, take off to its first height, then fly it",
    );
    this.startButton.addEventListener("click", () => void this.run());
    this.steps = el("ol", "mission-start-steps", "start-steps");
    this.steps.setAttribute("aria-live", "polite");
    this.element.append(this.startButton, this.steps);
  }

  private async run(): Promise<void> {
    const vehicle = this.vehicle();
    if (this.running || !vehicle) return;
    this.running = true;
    this.startButton.disabled = true;
    this.steps.replaceChildren();
    try {
      await this.sequence(vehicle);
    } catch (error) {
      if (!(error instanceof Refused)) this.step("error", "Stopped", "refused", String(error));
    } finally {
      this.running = false;
      this.startButton.disabled = false;
    }
  }

  private async sequence(vehicle: VehicleSummary): Promise<void> {
    const id = vehicle.id;
    const check = this.step("check", "Check", "running", "reading the mission on board…");
    const items = (await missionOnBoard(id)) ?? [];
    if (items.length === 0) this.fail(check, "no mission on board: upload one first");
    const verdict = await checkMission(id, items);
    if (!verdict.ok) {
      this.fail(check, verdict.violations.map((v) => `${v.rule}: ${v.message}`).join("; ") || "refused by the rails");
    }
    const height = takeoffHeight(items, vehicle.state?.home_alt_msl);
    if ("refused" in height) this.fail(check, `take-off height: ${height.refused}`);
    this.done(check, `${items.length} items, rails OK; take-off to ${height.metres} m (${height.from})`);

    // Already in the air (below the first height too): no take-off, which ArduPilot refuses
    // to a flying copter; the mission mode flies its take-off item as a climb.
    const flying =
      vehicle.state?.armed && (isAirborne(vehicle.state) || (vehicle.state.alt_rel ?? 0) >= near(height.metres));
    if (!flying) {
      const guided = vehicle.autopilot === "px4" ? undefined : vehicle.modes.find((mode) => mode === GUIDED_MODE);
      if (guided && vehicle.state?.mode !== guided) await this.command("mode", `Mode ${guided}`, id, { name: "set_mode", mode: guided });
      if (!vehicle.state?.armed) await this.command("arm", "Arm", id, { name: "arm" });
      await this.command("takeoff", `Take off to ${height.metres} m`, id, { name: "takeoff", altitude: height.metres });
      await this.climb(id, height.metres);
    }
    const mission = vehicle.modes.find((mode) => MISSION_MODES.includes(mode));
    if (!mission) {
      const step = this.step("mission", "Mission mode", "running", "");
      this.fail(step, `no mission mode among its modes (${vehicle.modes.join(", ") || "none"})`);
    }
    await this.command("mission", `Mode ${mission}`, id, { name: "set_mode", mode: mission });
  }

  private async command(key: string, title: string, id: string, command: Command): Promise<void> {
    const step = this.step(key, title, "running", "sent…");
    const feedback = await runCommand(id, command);
    if (feedback.tone !== "accepted") this.fail(step, feedback.text);
    this.done(step, feedback.text);
  }

  /** Until airborne near `metres` above home, at most a bounded time, the climb shown. */
  private climb(id: string, metres: number): Promise<void> {
    const limitS = Math.round(CLIMB_BASE_S + CLIMB_S_PER_M * metres);
    const step = this.step("climb", "Climb", "running", `waiting up to ${limitS} s`);
    const started = Date.now();
    return new Promise((resolve, reject) => {
      const timer = window.setInterval(() => {
        const state = this.vehicle()?.id === id ? this.vehicle()?.state : undefined;
        const alt = state?.alt_rel ?? null;
        const shown = alt === null ? "height unknown" : `${alt.toFixed(1)} of ${metres} m`;
        if (alt !== null && alt >= near(metres) && state?.armed) {
          window.clearInterval(timer);
          this.done(step, `airborne at ${shown}`);
          resolve();
        } else if (Date.now() - started > limitS * 1000 || (state && !state.armed)) {
          window.clearInterval(timer);
          const why = state && !state.armed ? "disarmed" : `not near ${metres} m after ${limitS} s`;
          try {
            this.fail(step, `${why} (${shown})`);
          } catch (error) {
            reject(error);
          }
        } else {
          this.show(step, "running", `${shown}, waiting up to ${limitS} s`);
        }
      }, CLIMB_POLL_MS);
    });
  }

  private step(key: string, title: string, state: StepState, text: string): HTMLLIElement {
    const row = el("li", "mission-start-step");
    row.dataset.step = key;
    row.append(el("span", "mission-start-name"), el("span", "mission-start-text"));
    (row.firstChild as HTMLElement).textContent = `${title}: `;
    this.steps.append(row);
    this.show(row, state, text);
    return row;
  }

  private show(row: HTMLLIElement, state: StepState, text: string): void {
    row.dataset.state = state;
    (row.lastChild as HTMLElement).textContent = text;
  }

  private done(row: HTMLLIElement, text: string): void {
    this.show(row, "ok", text);
  }

  /** The step refused: its reason shown whole, and the sequence stops here. */
  private fail(row: HTMLLIElement, why: string): never {
    this.show(row, "refused", why);
    throw new Refused(why);
  }
}

/** Near enough a take-off height to start the mission: within a metre or a tenth. */
function near(metres: number): number {
  return metres - Math.max(1, metres * 0.1);
}
