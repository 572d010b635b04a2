// REST calls to the hub. URLs are relative to the page, so the dashboard also
// works when the hub sits behind a reverse proxy under a sub-path.
import type { Command, CommandResponse, HubConfig } from "./types";

export class ApiError extends Error {
  constructor(
    readonly status: number,
    message: string,
  ) {
    super(message);
  }
}

export function apiUrl(path: string): URL {
  return new URL(`api/v1/${path}`, document.baseURI);
}

/** Turns `{"detail": "..."}` or FastAPI's 422 `{"detail": [{loc, msg}]}` into one line. */
export function describeErrorBody(body: unknown, status: number): string {
  const detail = (body as { detail?: unknown } | null)?.detail;
  if (typeof detail === "string" && detail) return detail;
  if (Array.isArray(detail) && detail.length > 0) {
    return detail
      .map((item: { loc?: unknown[]; msg?: string }) => {
        const loc = (item.loc ?? []).filter((part) => part !== "body").join(".");
        return loc ? `${loc}: ${item.msg ?? "invalid"}` : (item.msg ?? "invalid");
      })
      .join("; ");
  }
  return `HTTP ${status}`;
}

async function request<T>(path: string, init?: RequestInit): Promise<T> {
  let response: Response;
  try {
    response = await fetch(apiUrl(path), init);
  } catch {
    throw new ApiError(0, "hub unreachable");
  }
  const text = await response.text();
  let body: unknown = null;
  try {
    body = text ? JSON.parse(text) : null;
  } catch {
    body = null;
  }
  if (!response.ok) throw new ApiError(response.status, describeErrorBody(body, response.status));
  return body as T;
}

export function fetchConfig(): Promise<HubConfig> {
  return request<HubConfig>("config");
}

export function sendCommand(vehicleId: string, command: Command): Promise<CommandResponse> {
  return request<CommandResponse>(`vehicles/${encodeURIComponent(vehicleId)}/commands`, {
    method: "POST",
    headers: { "Content-Type": "application/json" },
    body: JSON.stringify(command),
  });
}
