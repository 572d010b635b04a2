// The drones to fly a survey: one checkbox per vehicle of the fleet, in id order (the
// order the preview colours them in). A vehicle that leaves the fleet leaves the choice.
import type { VehicleSummary } from "../hub/types";
import { el } from "../ui/dom";

export class DroneChooser {
  readonly element = el("div", "survey-drones", "survey-drones");
  private readonly vehicles = new Set<string>();
  private readonly chosen = new Set<string>();

  constructor(private readonly onChange: () => void) {}

  /** The chosen drones' ids, in the fleet list's order. */
  get ids(): string[] {
    return [...this.vehicles].sort().filter((id) => this.chosen.has(id));
  }

  update(vehicles: Iterable<VehicleSummary>): void {
    let added = false;
    for (const vehicle of vehicles) {
      if (!this.vehicles.has(vehicle.id)) added = true;
      this.vehicles.add(vehicle.id);
    }
    if (added) this.render();
  }

  remove(id: string): void {
    this.vehicles.delete(id);
    this.chosen.delete(id);
    this.render();
  }

  private render(): void {
    const ids = [...this.vehicles].sort();
    const title = el("span", "survey-drones-title");
    title.textContent = "Drones:";
    this.element.replaceChildren(
      title,
      ...ids.map((id) => {
        const label = el("label", "survey-drone");
        label.dataset.vehicleId = id;
        const box = el("input", "survey-drone-box");
        box.type = "checkbox";
        box.checked = this.chosen.has(id);
        box.addEventListener("change", () => {
          if (box.checked) this.chosen.add(id);
          else this.chosen.delete(id);
          this.onChange();
        });
        label.append(box, ` ${id}`);
        return label;
      }),
    );
  }
}
