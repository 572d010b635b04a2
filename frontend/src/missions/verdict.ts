// The rails' verdict on the plan being edited: the refusals by the item they name, and
// the verdict in words (OK with the battery it needs, or each violated rule).
import { el } from "../ui/dom";
import type { MissionCheck } from "./model";

/** Each refusal's text (`rule: message`), by the seq of every item it names. */
export function refusalsBySeq(check: MissionCheck | null): Map<number, string[]> {
  const refusals = new Map<number, string[]>();
  for (const violation of check?.violations ?? []) {
    for (const seq of violation.items ?? []) {
      const list = refusals.get(seq) ?? [];
      list.push(`${violation.rule}: ${violation.message}`);
      refusals.set(seq, list);
    }
  }
  return refusals;
}

/** The verdict's head line and its list of violations. */
export function verdictParts(check: MissionCheck): HTMLElement[] {
  const head = el("div", "mission-verdict", "mission-verdict");
  const estimate = check.estimate;
  const battery = estimate ? ` · needs about ${Math.round(estimate.required_pct)}% battery` : "";
  head.textContent = check.ok ? `Rails: OK${battery}` : "Refused by the rails:";
  const list = el("ul", "mission-violations");
  for (const violation of check.violations) {
    const line = el("li", "mission-violation");
    line.dataset.rule = violation.rule;
    line.textContent = `${violation.rule}: ${violation.message}`;
    list.append(line);
  }
  return [head, list];
}
