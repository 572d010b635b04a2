// Wires the dashboard together: config -> map, WebSocket -> store -> views.
import { fetchConfig } from "./api";
import { PROTOCOL_VERSION } from "./generated/protocol";
import { runCommand } from "./commands";
import { FleetSocket } from "./connection";
import { FleetStore } from "./fleet";
import { FleetTable } from "./fleetTable";
import { linkState } from "./format";
import { Header } from "./header";
import { FleetMap } from "./map";
import type { HubConfig, HubToClient } from "./types";
// Last, so the theme overrides Leaflet's stylesheet (imported by ./map).
import "./style.css";

const OFFLINE_CONFIG: HubConfig = { basemap_url: null, basemap_attribution: "", basemap_max_zoom: 19 };

async function main(): Promise<void> {
  const header = new Header();
  const config = await fetchConfig().catch((error: Error) => {
    header.showNotice(`Could not load the hub's config (${error.message}); showing no basemap.`);
    return OFFLINE_CONFIG;
  });
  if (config.protocol !== undefined && config.protocol !== PROTOCOL_VERSION) {
    header.showNotice(
      `The hub speaks protocol ${config.protocol}; this dashboard was built for ${PROTOCOL_VERSION}. Reload or rebuild it.`,
      true,
    );
  }

  const select = (id: string, pan: boolean) => {
    table.select(id);
    map.select(id, pan);
  };
  const map = new FleetMap(document.getElementById("map")!, config, (id) => select(id, false));
  const table = new FleetTable(
    document.querySelector<HTMLTableSectionElement>("#fleet-table tbody")!,
    runCommand,
    (id) => select(id, true),
  );

  const store = new FleetStore(({ changed, removed, all }) => {
    for (const id of removed) {
      table.remove(id);
      map.remove(id);
    }
    table.update(changed);
    map.update(changed);
    let online = 0;
    for (const vehicle of all.values()) if (linkState(vehicle) !== "offline") online++;
    header.setCounts(all.size, online);
  });

  const onMessage = (message: HubToClient) => {
    switch (message.type) {
      case "fleet":
        store.replaceAll(message.vehicles);
        break;
      case "vehicle":
        store.upsert(message.vehicle);
        break;
      case "error":
        header.showNotice(`Hub: ${message.message}`);
        break;
      case "pong":
        break;
    }
  };

  new FleetSocket({ onMessage, onState: (state, retry) => header.setConnection(state, retry) }).start();
}

void main();
