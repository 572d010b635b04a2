// The mission's items as list rows: number, command (a picker while editing), altitude
// with its frame, loiter time, the speed folded in from a DO_CHANGE_SPEED before the item,
// delete, and the rails' refusals on the items they name. A speed item is MAVLink's own,
// shown folded into the row of the item it applies to.
import { button, el } from "../ui/dom";
import { CMD, EDITABLE_COMMANDS, type MissionItem, commandName, commandNumber, frameName, frameNumber } from "./model";

/** What a row's controls change, by item index. */
export interface RowEdits {
  setCommand(index: number, command: number): void;
  /** Applies a change to the plan being edited. */
  edit(change: (items: MissionItem[]) => void): void;
  setSpeed(index: number, speed: number | null): void;
  deleteRow(index: number): void;
}

export interface RowsShown {
  items: readonly MissionItem[];
  editing: boolean;
  /** The vehicle's current item (seq), when showing its mission. */
  current: number | null;
  /** The rails' refusals, by item seq (index + 1). */
  refusals: ReadonlyMap<number, string[]>;
}

export function numberInput(field: string, value: number | null, title: string, min = 0): HTMLInputElement {
  const input = el("input", "mission-number", field);
  input.type = "number";
  input.step = "any";
  input.min = String(min);
  input.title = title;
  input.value = value === null ? "" : String(Math.round(value * 10) / 10);
  return input;
}

/** The speed item folded into the row of item `index`, if there is one. */
export function speedIndexFor(items: readonly MissionItem[], index: number): number | null {
  const before = index - 1;
  return before >= 0 && items[before].command === CMD.CHANGE_SPEED && items[index].command !== CMD.CHANGE_SPEED
    ? before
    : null;
}

/** The buttons that add a take-off, loiter, land or RTL item at the end, and clear the plan. */
export function adderButtons(add: (command: number) => void, clear: () => void): HTMLElement {
  const adders = el("div", "mission-add");
  for (const [command, text] of [
    [CMD.TAKEOFF, "+ Take-off"],
    [CMD.LOITER_TIME, "+ Loiter"],
    [CMD.LAND, "+ Land"],
    [CMD.RTL, "+ RTL"],
  ] as const) {
    const adder = button(`mission-add-${command}`, text, `Add a ${commandName(command)} item at the end`);
    adder.addEventListener("click", () => add(command));
    adders.append(adder);
  }
  const clearButton = button("mission-clear", "Clear", "Remove every item of the plan being edited");
  clearButton.addEventListener("click", clear);
  adders.append(clearButton);
  return adders;
}

/** The list's rows (an empty-list note when there are no items). */
export function missionRows(shown: RowsShown, edits: RowEdits): HTMLLIElement[] {
  const { items, editing } = shown;
  const rows: HTMLLIElement[] = [];
  items.forEach((item, index) => {
    if (item.command === CMD.CHANGE_SPEED && index + 1 < items.length && items[index + 1].command !== CMD.CHANGE_SPEED) {
      return; // folded into the next item's row
    }
    rows.push(missionRow(shown, edits, index));
  });
  if (items.length === 0) {
    const empty = el("li", "mission-empty");
    empty.textContent = editing ? "No items yet: click the map to add a waypoint." : "No mission known for this vehicle.";
    rows.push(empty);
  }
  return rows;
}

function missionRow({ items, editing, current, refusals: refused }: RowsShown, edits: RowEdits, index: number): HTMLLIElement {
  const item = items[index];
  const seq = index + 1;
  const folded = speedIndexFor(items, index);
  const row = el("li", "mission-row");
  row.dataset.seq = String(seq);
  row.dataset.command = String(item.command);
  const refusals = [...(refused.get(seq) ?? []), ...(folded === null ? [] : (refused.get(folded + 1) ?? []))];
  row.classList.toggle("refused", refusals.length > 0);
  row.classList.toggle("active", current === seq);

  const number = el("span", "mission-seq");
  number.textContent = String(seq);
  row.append(number);

  if (editing && (EDITABLE_COMMANDS as readonly number[]).includes(item.command)) {
    const kind = el("select", "mission-kind", "command");
    for (const command of EDITABLE_COMMANDS) {
      kind.append(new Option(commandName(command), String(command), false, command === item.command));
    }
    kind.addEventListener("change", () => edits.setCommand(index, Number(kind.value)));
    row.append(kind);
  } else {
    const name = el("span", "mission-kind", "command");
    name.textContent = commandName(item.command);
    name.title = commandNumber(item.command);
    row.append(name);
  }

  const hasAlt = item.command !== CMD.RTL && item.command !== CMD.CHANGE_SPEED;
  if (hasAlt) {
    const alt = numberInput("alt", item.alt, "Altitude, metres", -1000);
    alt.disabled = !editing;
    alt.addEventListener("change", () => {
      const value = Number.parseFloat(alt.value);
      if (Number.isFinite(value)) edits.edit((list) => (list[index].alt = value));
    });
    const frame = el("span", "mission-frame", "frame");
    frame.textContent = `m ${frameName(item.frame)}`;
    frame.title = frameNumber(item.frame);
    row.append(alt, frame);
  }
  if (item.command === CMD.LOITER_TIME) {
    const time = numberInput("loiter-time", item.param1, "Loiter time, seconds");
    time.disabled = !editing;
    time.addEventListener("change", () => {
      const value = Number.parseFloat(time.value);
      if (Number.isFinite(value)) edits.edit((list) => (list[index].param1 = value));
    });
    row.append(time, Object.assign(el("span", "mission-unit"), { textContent: "s" }));
  }
  const speedable = item.command === CMD.WAYPOINT || item.command === CMD.LOITER_TIME || item.command === CMD.TAKEOFF;
  if (speedable && (editing || folded !== null)) {
    const speed = numberInput("speed", folded === null ? null : items[folded].param2, "Ground speed from here on, m/s (empty: unchanged)");
    speed.placeholder = "speed";
    speed.disabled = !editing;
    speed.addEventListener("change", () => {
      const value = Number.parseFloat(speed.value);
      edits.setSpeed(index, Number.isFinite(value) ? value : null);
    });
    row.append(speed, Object.assign(el("span", "mission-unit"), { textContent: "m/s" }));
  }
  if (item.lat !== 0 || item.lon !== 0) {
    row.dataset.lat = String(item.lat);
    row.dataset.lon = String(item.lon);
  }
  if (editing) {
    const remove = button("delete", "✕", `Delete item ${seq}`);
    remove.addEventListener("click", () => edits.deleteRow(index));
    row.append(remove);
  }
  if (refusals.length > 0) {
    const why = el("div", "mission-row-refusal", "refusal");
    why.textContent = refusals.join("; ");
    row.append(why);
  }
  return row;
}
