// The active map tool, shown on the map itself (not in a panel that may be folded or off
// screen): "Drawing survey area — Esc or Done to finish", with the Done button. Esc ends
// the tool from anywhere on the page. One banner per map, made by the first tool.
import * as L from "leaflet";
import { button, el } from "../ui/dom";
import { mapToolsOf } from "./mapTools";

const bannered = new WeakSet<L.Map>();

export function showToolBanner(map: L.Map): void {
  if (bannered.has(map)) return;
  bannered.add(map);
  const tools = mapToolsOf(map);
  const banner = el("div", "map-tool-banner", "map-tool-banner");
  banner.setAttribute("role", "status");
  banner.hidden = true;
  const label = el("span", "map-tool-label", "map-tool-label");
  const done = button("map-tool-done", "Done", "Finish with this map tool (Esc)");
  done.addEventListener("click", () => tools.endActive());
  banner.append(label, done);
  // The banner's own clicks stay off the map: Done must not become a waypoint.
  L.DomEvent.disableClickPropagation(banner);
  map.getContainer().append(banner);

  tools.subscribe((active) => {
    banner.hidden = active === null;
    label.textContent = active ? `${active.label} — Esc or Done to finish` : "";
  });
  const onKey = (event: KeyboardEvent): void => {
    if (event.key === "Escape" && tools.active) tools.endActive();
  };
  document.addEventListener("keydown", onKey);
  map.on("unload", () => {
    document.removeEventListener("keydown", onKey);
    banner.remove();
  });
}
