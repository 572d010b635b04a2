// REST calls to the hub. URLs are relative to the page, so the dashboard also
// works when the hub sits behind a reverse proxy under a sub-path.
//
// The hub keeps the session in an HttpOnly cookie (`gcs_session`) that the browser
// sends by itself: no token or password is ever held here. A 401 from any call
// except the login ones means the session ended; `request` reports it to the one
// handler set with `onUnauthorized`, which shows the login screen.
import type {
  AuditPage,
  AuditQuery,
  Command,
  CommandResponse,
  CurrentUser,
  EventPage,
  EventQuery,
  Flight,
  FlightExportFormat,
  FlightPage,
  FlightQuery,
  FlightTelemetry,
  HubConfig,
  HubHealth,
  ParamValues,
  SafetyViolation,
} from "./types";

export class ApiError extends Error {
  constructor(
    readonly status: number,
    message: string,
    /** The parsed JSON body, if any (e.g. a safety refusal's `violations`). */
    readonly body: unknown = null,
    /** Seconds from a `Retry-After` header (429). */
    readonly retryAfterS: number | null = null,
  ) {
    super(message);
  }
}

export function apiUrl(path: string): URL {
  return new URL(`api/v1/${path}`, document.baseURI);
}

/** The `violations` of a safety refusal, or an empty list. */
export function violationsOf(body: unknown): SafetyViolation[] {
  const violations = (body as { violations?: unknown } | null)?.violations;
  if (!Array.isArray(violations)) return [];
  return violations.filter(
    (item): item is SafetyViolation => Boolean(item) && typeof (item as SafetyViolation).message === "string",
  );
}

/** Turns `{"detail": "..."}` or FastAPI's 422 `{"detail": [{loc, msg}]}` into one line. */
export function describeErrorBody(body: unknown, status: number): string {
  const violations = violationsOf(body);
  if (violations.length > 0) return violations.map((v) => v.message).join("; ");
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

/** The hub's reason for a refusal (a 422's message, a rails violation), else the error's. */
export function errorText(error: unknown): string {
  if (error instanceof ApiError) return describeErrorBody(error.body, error.status) || error.message;
  return (error as Error).message;
}

// ---------------------------------------------------------------- session end

type UnauthorizedHandler = (message: string) => void;

let unauthorizedHandler: UnauthorizedHandler = () => {};
/**
 * Bumped at every login and logout, so a 401 that answers a request made under an
 * earlier session cannot end the current one.
 */
let sessionEpoch = 0;

/** Sets the one place that reacts to an ended session (shows the login screen). */
export function onUnauthorized(handler: UnauthorizedHandler): void {
  unauthorizedHandler = handler;
}

function newSession(): void {
  sessionEpoch++;
}

interface RequestOptions {
  /** A 401 is an answer for the caller (wrong password, not logged in), not a session end. */
  own401?: boolean;
}

export async function request<T>(path: string, init?: RequestInit, options: RequestOptions = {}): Promise<T> {
  const epoch = sessionEpoch;
  let response: Response;
  try {
    // Same origin, so the session cookie goes along; "same-origin" says so explicitly.
    response = await fetch(apiUrl(path), { credentials: "same-origin", ...init });
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
  if (!response.ok) {
    const retryAfter = Number.parseFloat(response.headers.get("Retry-After") ?? "");
    const error = new ApiError(
      response.status,
      describeErrorBody(body, response.status),
      body,
      Number.isFinite(retryAfter) ? retryAfter : null,
    );
    if (response.status === 401 && !options.own401 && epoch === sessionEpoch) {
      unauthorizedHandler(error.message);
    }
    throw error;
  }
  return body as T;
}

function postJson<T>(path: string, payload: unknown, options?: RequestOptions): Promise<T> {
  return request<T>(
    path,
    { method: "POST", headers: { "Content-Type": "application/json" }, body: JSON.stringify(payload) },
    options,
  );
}

/** Turns this dashboard's own 3D viewer to the vehicle, which it then follows
 * (backend/viz3d/viewers.py: the viewer's page told us its id and secret). */
export function selectInViewer(viewer: number, secret: string, vehicleId: string): Promise<unknown> {
  return postJson(`viz/viewers/${viewer}/selection`, { secret, vehicle_id: vehicleId });
}

// ---------------------------------------------------------------- auth

/** Logs in; the hub sets the session cookie. Throws ApiError 401 / 429 with the hub's words. */
export async function login(username: string, password: string): Promise<CurrentUser> {
  const user = await postJson<CurrentUser>("auth/login", { username, password }, { own401: true });
  newSession();
  return user;
}

/** Ends the session (the hub clears the cookie). An already ended session counts as done. */
export async function logout(): Promise<void> {
  try {
    await request<null>("auth/logout", { method: "POST" }, { own401: true });
  } catch (error) {
    if (!(error instanceof ApiError && error.status === 401)) throw error;
  } finally {
    newSession();
  }
}

/** Who is logged in, or null when nobody is (or the session expired). */
export async function fetchCurrentUser(): Promise<CurrentUser | null> {
  try {
    return await request<CurrentUser>("auth/me", undefined, { own401: true });
  } catch (error) {
    if (error instanceof ApiError && error.status === 401) return null;
    throw error;
  }
}

/** Asks whether the session still holds; reports a 401 like any other call. */
export function checkSession(): Promise<CurrentUser> {
  return request<CurrentUser>("auth/me");
}

// ---------------------------------------------------------------- dashboard data

export function fetchConfig(): Promise<HubConfig> {
  return request<HubConfig>("config");
}

export function fetchHealth(): Promise<HubHealth> {
  return request<HubHealth>("health");
}

export function sendCommand(vehicleId: string, command: Command): Promise<CommandResponse> {
  return postJson<CommandResponse>(`vehicles/${encodeURIComponent(vehicleId)}/commands`, command);
}

/** Writes one flight-controller parameter (PUT, audited by the hub; a safety-critical
 * one is an admin's to change); resolves once the vehicle echoed the new value. */
export function setParam(vehicleId: string, param: string, value: number): Promise<ParamValues> {
  return request<ParamValues>(`vehicles/${encodeURIComponent(vehicleId)}/params/${encodeURIComponent(param)}`, {
    method: "PUT",
    headers: { "Content-Type": "application/json" },
    body: JSON.stringify({ value }),
  });
}

export function fetchAudit(query: AuditQuery): Promise<AuditPage> {
  const params = new URLSearchParams({ limit: String(query.limit) });
  if (query.beforeId !== undefined) params.set("before_id", String(query.beforeId));
  if (query.actor) params.set("actor", query.actor);
  if (query.action) params.set("action", query.action);
  return request<AuditPage>(`audit?${params}`);
}

// ---------------------------------------------------------------- flight logs

export function fetchFlights(query: FlightQuery): Promise<FlightPage> {
  const params = new URLSearchParams({ limit: String(query.limit) });
  if (query.vehicleId) params.set("vehicle_id", query.vehicleId);
  if (query.beforeId !== undefined) params.set("before_id", String(query.beforeId));
  return request<FlightPage>(`flights?${params}`);
}

export function fetchFlight(id: number): Promise<Flight> {
  return request<Flight>(`flights/${id}`);
}

/** The flight's samples, downsampled by the hub to at most `points` (up to 10000). */
export function fetchFlightTelemetry(id: number, points: number): Promise<FlightTelemetry> {
  return request<FlightTelemetry>(`flights/${id}/telemetry?points=${points}`);
}

export function fetchEvents(query: EventQuery): Promise<EventPage> {
  const params = new URLSearchParams({
    vehicle_id: query.vehicleId,
    start: String(query.start),
    end: String(query.end),
    limit: String(query.limit),
  });
  if (query.beforeId !== undefined) params.set("before_id", String(query.beforeId));
  return request<EventPage>(`events?${params}`);
}

/** A plain download link: the session cookie authenticates it. */
export function flightExportUrl(id: number, format: FlightExportFormat): string {
  return apiUrl(`flights/${id}/export.${format}`).toString();
}
