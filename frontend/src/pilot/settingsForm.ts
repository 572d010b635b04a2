// The pilot's settings form: the stick shaping of each axis for one vehicle, the
// keyboard's step and sensitivity, and the gamepad mapping screen (which axis, and which
// way, is which; which buttons act), each saved in this browser as it changes.
import { element, field, setText } from "../ui/dom";
import type { GamepadMapping } from "./inputs";
import { type PilotSettings, saveMapping, saveSettings } from "./settings";
import { AXES, type AxisName } from "./shaping";

/** The form's summary, shaping table, keyboard line and gamepad mapping. */
export function settingsFormParts(user: string, vehicleId: string, settings: PilotSettings, mapping: GamepadMapping): HTMLElement[] {
  const save = () => saveSettings(user, vehicleId, settings);
  const number = (name: string, value: number, step: number, set: (v: number) => void) => {
    const input = field("input", name, { type: "number", value: String(value), step: String(step), className: "pilot-number" });
    input.addEventListener("change", () => {
      const parsed = Number(input.value);
      if (!Number.isFinite(parsed)) return;
      set(parsed);
      save();
    });
    return input;
  };
  const rows = AXES.map((axis: AxisName) => {
    const shape = settings.shaping[axis];
    return element(
      "tr",
      {},
      element("th", { textContent: axis }),
      element("td", {}, number(`shape-${axis}-deadzone`, shape.deadzone, 0.01, (v) => (shape.deadzone = Math.min(0.5, Math.max(0, v))))),
      element("td", {}, number(`shape-${axis}-expo`, shape.expo, 0.05, (v) => (shape.expo = Math.min(1, Math.max(0, v))))),
      element("td", {}, number(`shape-${axis}-slew`, shape.slewPerS, 0.5, (v) => (shape.slewPerS = Math.min(20, Math.max(0.1, v))))),
      element("td", {}, number(`shape-${axis}-max`, shape.max, 0.05, (v) => (shape.max = Math.min(1, Math.max(0, v))))),
    );
  });
  const header = element("tr", {}, ...["", "dead zone", "expo", "slew /s", "max"].map((t) => element("th", { textContent: t })));
  const keyboard = element(
    "p",
    { className: "pilot-keyboard" },
    "Keyboard step ",
    number("keyboard-step", settings.keyboard.step, 0.05, (v) => (settings.keyboard.step = Math.min(1, Math.max(0.01, v)))),
    " sensitivity ",
    number("keyboard-sensitivity", settings.keyboard.sensitivity, 0.05, (v) => (settings.keyboard.sensitivity = Math.min(1, Math.max(0.05, v)))),
  );
  return [
    element("summary", { textContent: `Stick shaping for ${vehicleId}, keyboard, gamepad mapping` }),
    element("table", { className: "pilot-shaping" }, header, ...rows),
    keyboard,
    mappingForm(user, mapping),
  ];
}

/** The gamepad mapping screen: which axis (and which way) is which, which buttons act. */
function mappingForm(user: string, mapping: GamepadMapping): HTMLElement {
  const save = () => saveMapping(user, mapping);
  const indexPicker = (name: string, current: number, count: number, set: (v: number) => void) => {
    const picker = field("select", name);
    for (let i = 0; i < count; i++) picker.append(element("option", { value: String(i), textContent: String(i), selected: i === current }));
    picker.addEventListener("change", () => (set(Number(picker.value)), save()));
    return picker;
  };
  const rows = AXES.map((axis: AxisName) => {
    const map = mapping.axes[axis];
    const invert = field("input", `map-${axis}-invert`, { type: "checkbox", checked: map.invert });
    invert.addEventListener("change", () => ((map.invert = invert.checked), save()));
    return element(
      "tr",
      {},
      element("th", { textContent: axis }),
      element("td", {}, indexPicker(`map-${axis}-axis`, map.axis, 8, (v) => (map.axis = v))),
      element("td", {}, element("label", {}, invert, " invert")),
    );
  });
  const live = field("code", "gamepad-live", { textContent: "move a stick to see its axis" });
  const poll = window.setInterval(() => {
    if (!live.isConnected) return window.clearInterval(poll);
    const pad = navigator.getGamepads?.().find((p) => p?.connected);
    setText(live, pad ? pad.axes.map((v, i) => `${i}: ${v.toFixed(2)}`).join("  ") : "no gamepad connected");
  }, 200);
  return element(
    "fieldset",
    { className: "pilot-mapping" },
    element("legend", { textContent: "Gamepad mapping" }),
    element("table", {}, ...rows),
    element("p", {}, "Select button ", indexPicker("map-select", mapping.select, 16, (v) => (mapping.select = v)), " hold button ", indexPicker("map-hold", mapping.hold, 16, (v) => (mapping.hold = v))),
    live,
  );
}
