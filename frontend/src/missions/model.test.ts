import { describe, expect, it } from "vitest";
import * as mav from "../generated/mavlink";
import { commandName, commandNumber, frameName, frameNumber } from "./model";

describe("command and frame names", () => {
  it("names a command in words where the editor has some", () => {
    expect(commandName(mav.MAV_CMD_NAV_TAKEOFF)).toBe("Take-off");
  });

  it("names any other command as MAVLink does, the number kept for the tooltip", () => {
    expect(commandName(mav.MAV_CMD_DO_DIGICAM_CONTROL)).toBe("DO_DIGICAM_CONTROL");
    expect(commandNumber(mav.MAV_CMD_DO_DIGICAM_CONTROL)).toBe("MAV_CMD 203");
    expect(commandName(mav.MAV_CMD_DO_SET_CAM_TRIGG_DIST)).toBe("DO_SET_CAM_TRIGG_DIST");
  });

  it("names frames as MAVLink does where there are no words", () => {
    expect(frameName(mav.MAV_FRAME_GLOBAL_RELATIVE_ALT)).toBe("above home");
    expect(frameName(mav.MAV_FRAME_MISSION)).toBe("MISSION");
    expect(frameNumber(mav.MAV_FRAME_MISSION)).toBe("MAV_FRAME 2");
  });

  it("keeps the number for a value MAVLink does not know", () => {
    expect(commandName(64999)).toBe("MAV_CMD 64999");
    expect(frameName(250)).toBe("MAV_FRAME 250");
  });
});
