// Where an upload goes: one tick box per vehicle, the edited one ticked and fixed (the
// plan's own vehicle is always a target), the others off unless ticked on purpose.
import { el } from "../ui/dom";

/** The boxes, the plan's own vehicle first, then the others by name; `ticked` follows the ticks. */
export function targetBoxes(vehicleIds: Iterable<string>, editedId: string | null, ticked: Set<string>): HTMLElement[] {
  const ids = [...vehicleIds].sort().sort((a, b) => +(b === editedId) - +(a === editedId));
  const boxes: HTMLElement[] = ids.map((id) => {
    const edited = id === editedId;
    const label = el("label", edited ? "mission-target edited" : "mission-target");
    const box = el("input", "mission-target-box");
    box.type = "checkbox";
    box.value = id;
    box.checked = edited || ticked.has(id);
    box.disabled = edited;
    box.addEventListener("change", () => {
      if (box.checked) ticked.add(id);
      else ticked.delete(id);
    });
    const name = el("span", "mission-target-name");
    name.textContent = edited ? `${id} (this plan's)` : id;
    label.append(box, name);
    return label;
  });
  if (boxes.length === 0) {
    const none = el("span", "mission-target-none");
    none.textContent = "no vehicle";
    boxes.push(none);
  }
  return boxes;
}
