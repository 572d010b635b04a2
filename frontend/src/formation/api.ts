// The hub's formation endpoints (backend/formation/routes.py), typed with the generated REST types.
import { request } from "../hub/api";
import type { components } from "../generated/api";

type Schemas = components["schemas"];
export type FormationRequest = Schemas["FormationRequest"];
export type FormationStatus = Schemas["FormationStatus"];
export type StoredFormation = Schemas["StoredFormationModel"];
export type ShapeChange = Schemas["ShapeChange"];
export type Shape = Schemas["Shape"];
export type Controller = Schemas["Controller"];
export type RoutePoint = Schemas["RoutePoint"];
export type Offset = Schemas["OffsetModel"];

/** The fields the hub defaults may be left out of a request. */
type Defaulted = "pause_s" | "obstacle_clearance_m" | "k_leader" | "k_neighbour" | "shape" | "spacing_m" | "min_separation_m" | "controller";
export type FormationBody = Omit<FormationRequest, Defaulted> & Partial<Pick<FormationRequest, Defaulted>>;

/** Every `Shape` preset of common/formation.py (a Record, so a new one fails the typecheck
 * until it is named here), in the order the panel offers them. */
export const SHAPE_NAMES: Record<Shape, string> = {
  wedge: "Wedge (V behind)",
  line: "Line abreast",
  column: "Column",
  circle: "Circle",
  triangle: "Triangle",
};
export const CONTROLLER_NAMES: Record<Controller, string> = {
  leader_follower: "Leader-follower",
  consensus: "Consensus",
};

function send<T>(method: string, path: string, body?: unknown): Promise<T> {
  return request<T>(path, {
    method,
    headers: { "Content-Type": "application/json" },
    body: body === undefined ? undefined : JSON.stringify(body),
  });
}

const formation = (id: string) => `formations/${encodeURIComponent(id)}`;

/** Checked (a 422 names the refusal) and started: every member gets its slot. */
export function startFormation(body: FormationBody): Promise<FormationStatus> {
  return send<FormationStatus>("POST", "formations", body);
}

/** Live: joining (no `formed_at`) or formed, each follower's error from its slot, `stopped`. */
export function getFormation(id: string): Promise<FormationStatus> {
  return request<FormationStatus>(formation(id));
}

/** The latest formations as stored, newest first. */
export async function listFormations(limit = 10): Promise<StoredFormation[]> {
  return (await request<Schemas["StoredFormations"]>(`formations?limit=${limit}`)).formations;
}

/** A new shape or spacing in flight; the followers glide to their new slots. */
export function changeFormation(id: string, change: ShapeChange): Promise<FormationStatus> {
  return send<FormationStatus>("PATCH", formation(id), change);
}

export function stopFormation(id: string): Promise<FormationStatus> {
  return send<FormationStatus>("POST", `${formation(id)}/stop`);
}
