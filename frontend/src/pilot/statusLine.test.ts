import { describe, expect, it } from "vitest";
import type { LeaseRefusal } from "../generated/protocol";
import { type PilotActivity, statusLine } from "./statusLine";

const idle: PilotActivity = { sendingWith: null, asking: false, fixNote: null, refusal: undefined, isAdmin: false, stoppedWhy: null };
const refusal = { vehicle_id: "a", reason: "SYSID_MYGCS is 255", fix: { param: "SYSID_MYGCS", value: 255 } } as unknown as LeaseRefusal;

describe("the pilot's status line", () => {
  it("says what the panel is doing, flying first", () => {
    expect(statusLine(idle)).toEqual({ text: "not flown by hand", state: "idle" });
    expect(statusLine({ ...idle, sendingWith: "Gamepad", asking: true, refusal })).toEqual({ text: "flying with Gamepad, 25 Hz", state: "sending" });
    expect(statusLine({ ...idle, asking: true, refusal })).toEqual({ text: "asking for control…", state: "asking" });
    expect(statusLine({ ...idle, stoppedWhy: "page hidden" })).toEqual({ text: "stopped: page hidden — the vehicle holds", state: "stopped" });
  });

  it("gives a refusal's reason, and tells a non-admin that an admin can fix it", () => {
    expect(statusLine({ ...idle, refusal, isAdmin: true }).text).toBe("control refused: SYSID_MYGCS is 255");
    expect(statusLine({ ...idle, refusal }).text).toBe("control refused: SYSID_MYGCS is 255 — an admin can make this change from this panel");
    expect(statusLine({ ...idle, refusal, fixNote: "setting SYSID_MYGCS to 255…" })).toEqual({ text: "setting SYSID_MYGCS to 255…", state: "refused" });
  });
});
