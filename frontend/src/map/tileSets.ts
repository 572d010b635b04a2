// The hub's offline tile sets (GET /api/v1/tiles).
import { apiUrl } from "../hub/api";
import type { components } from "../generated/api";

export type TileSet = components["schemas"]["TileSet"];

export async function fetchTileSets(): Promise<TileSet[]> {
  const response = await fetch(apiUrl("tiles"), { credentials: "same-origin" });
  if (!response.ok) throw new Error(`the hub answered ${response.status}`);
  return (await response.json()) as TileSet[];
}
