// The hub's mission and go-to endpoints, typed with the generated REST types.
import { request } from "../hub/api";
import type { GotoCheck, MissionCheck, MissionItem, MissionResult } from "./model";

function post<T>(path: string, body: unknown, method = "POST"): Promise<T> {
  return request<T>(path, { method, headers: { "Content-Type": "application/json" }, body: JSON.stringify(body) });
}

const vehicle = (id: string) => `vehicles/${encodeURIComponent(id)}`;

/** The rails' verdict on a mission, without sending it (`mission-check`). */
export function checkMission(vehicleId: string, items: MissionItem[], signal?: AbortSignal): Promise<MissionCheck> {
  return request<MissionCheck>(`${vehicle(vehicleId)}/mission-check`, {
    method: "POST",
    headers: { "Content-Type": "application/json" },
    body: JSON.stringify({ items }),
    signal,
  });
}

export function uploadMission(vehicleId: string, items: MissionItem[]): Promise<MissionResult> {
  return post<MissionResult>(`${vehicle(vehicleId)}/mission`, { items });
}

/** The mission on the vehicle; item 0 of the answer is home. */
export function downloadMission(vehicleId: string): Promise<MissionResult> {
  return request<MissionResult>(`${vehicle(vehicleId)}/mission`);
}

export function checkGoto(vehicleId: string, lat: number, lon: number, altitude: number): Promise<GotoCheck> {
  return post<GotoCheck>(`${vehicle(vehicleId)}/goto-check`, { lat, lon, altitude });
}
