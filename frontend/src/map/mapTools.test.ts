import { describe, expect, it, vi } from "vitest";
import { type MapTool, MapToolRegistry, mapToolsOf } from "./mapTools";

function tool(label: string, owner?: object) {
  const ended = vi.fn<() => void>();
  return { label, owner, ended } satisfies MapTool;
}

describe("MapToolRegistry", () => {
  it("starting a tool ends the one before it, and tells it", () => {
    const registry = new MapToolRegistry();
    const survey = tool("Drawing survey area");
    const mission = tool("Editing mission");
    registry.start(survey);
    registry.start(mission);
    expect(survey.ended).toHaveBeenCalledTimes(1);
    expect(mission.ended).not.toHaveBeenCalled();
    expect(registry.active).toBe(mission);
    expect(registry.isActive(survey)).toBe(false);
  });

  it("starting the active tool again changes nothing", () => {
    const registry = new MapToolRegistry();
    const survey = tool("Drawing survey area");
    registry.start(survey);
    registry.start(survey);
    expect(survey.ended).not.toHaveBeenCalled();
    expect(registry.active).toBe(survey);
  });

  it("a tool that stops itself is not called back", () => {
    const registry = new MapToolRegistry();
    const survey = tool("Drawing survey area");
    registry.start(survey);
    registry.release(survey);
    expect(survey.ended).not.toHaveBeenCalled();
    expect(registry.active).toBeNull();
  });

  it("releasing a tool that is not active leaves the active one", () => {
    const registry = new MapToolRegistry();
    const survey = tool("survey");
    const mission = tool("mission");
    registry.start(survey);
    registry.start(mission);
    registry.release(survey);
    expect(registry.active).toBe(mission);
  });

  it("ending from outside (Esc, Done) ends the active tool", () => {
    const registry = new MapToolRegistry();
    const survey = tool("survey");
    registry.start(survey);
    registry.endActive();
    expect(survey.ended).toHaveBeenCalledTimes(1);
    expect(registry.active).toBeNull();
    registry.endActive(); // nothing active: nothing happens
    expect(survey.ended).toHaveBeenCalledTimes(1);
  });

  it("folding a panel ends its own tool only", () => {
    const registry = new MapToolRegistry();
    const surveyPanel = {};
    const missionPanel = {};
    const survey = tool("survey", surveyPanel);
    registry.start(survey);
    registry.endOwnedBy(missionPanel);
    expect(registry.active).toBe(survey);
    registry.endOwnedBy(surveyPanel);
    expect(survey.ended).toHaveBeenCalledTimes(1);
    expect(registry.active).toBeNull();
  });

  it("listeners hear each change, with the tool that is active", () => {
    const registry = new MapToolRegistry();
    const heard: (string | null)[] = [];
    const stop = registry.subscribe((active) => heard.push(active?.label ?? null));
    const survey = tool("survey");
    registry.start(survey);
    registry.start(tool("mission"));
    registry.endActive();
    stop();
    registry.start(survey);
    expect(heard).toEqual(["survey", "mission", null]);
  });

  it("a tool's ended() may start nothing and still leaves the new tool active", () => {
    const registry = new MapToolRegistry();
    const first: MapTool = { label: "first", ended: () => registry.release(first) };
    const second = tool("second");
    registry.start(first);
    registry.start(second);
    expect(registry.active).toBe(second);
  });
});

describe("mapToolsOf", () => {
  it("gives one registry per map", () => {
    const a = {};
    const b = {};
    expect(mapToolsOf(a)).toBe(mapToolsOf(a));
    expect(mapToolsOf(a)).not.toBe(mapToolsOf(b));
  });
});
