// The fleet list's heading: how many vehicles, and the button that folds the list to
// that one line (the side column then gives its room to the selected vehicle's panels).
import { setIcon } from "../ui/icons";

export class FleetFold {
  private readonly button: HTMLButtonElement;
  private readonly title: HTMLElement;
  private readonly controller = new AbortController();

  constructor(private readonly panel: HTMLElement) {
    this.button = panel.querySelector<HTMLButtonElement>('[data-action="fold-fleet"]')!;
    this.title = panel.querySelector<HTMLElement>(".fleet-title")!;
    this.button.addEventListener("click", () => this.setFolded(!this.folded), { signal: this.controller.signal });
    this.setFolded(false);
  }

  get folded(): boolean {
    return this.panel.classList.contains("folded");
  }

  setCount(total: number): void {
    const text = `Fleet · ${total}`;
    if (this.title.textContent !== text) this.title.textContent = text;
  }

  setFolded(folded: boolean): void {
    this.panel.classList.toggle("folded", folded);
    this.button.setAttribute("aria-expanded", String(!folded));
    this.button.title = folded ? "Show the fleet list" : "Fold the fleet list";
    this.button.setAttribute("aria-label", this.button.title);
    setIcon(this.button, folded ? "chevron-down" : "chevron-up");
  }

  destroy(): void {
    this.controller.abort();
    this.setFolded(false);
    this.title.textContent = "Fleet";
  }
}
