// The hub's survey endpoints (backend/survey/routes.py), typed with the generated REST types.
import { ApiError, request } from "../hub/api";
import type { components } from "../generated/api";

type Schemas = components["schemas"];
export type SurveyRequest = Schemas["SurveyRequest"];
export type SurveyPreview = Schemas["SurveyPreview"];
export type SurveyPart = Schemas["SurveyPart"];
export type SurveyDetail = Schemas["SurveyDetail"];
export type SurveyRun = Schemas["SurveyRun"];
/** Progress as the REST API gives it; the live feed's `survey` message has the same fields. */
export type SurveyProgress = Schemas["SurveyUpdate"];
export type GeoJsonPolygon = Schemas["GeoJsonPolygon"];
export type SurveyFileFormat = Schemas["SurveyFile"]["format"];
export type CameraPreset = Schemas["CameraPreset"];
export type MosaicDetail = Schemas["MosaicDetail"];

function post<T>(path: string, body: unknown, signal?: AbortSignal): Promise<T> {
  return request<T>(path, {
    method: "POST",
    headers: { "Content-Type": "application/json" },
    body: body === undefined ? undefined : JSON.stringify(body),
    signal,
  });
}

const survey = (id: string) => `surveys/${encodeURIComponent(id)}`;

/** The hub's camera presets: the only names a survey's `camera.preset` may take. */
export function cameraPresets(): Promise<CameraPreset[]> {
  return request<CameraPreset[]>("surveys/cameras");
}

/** The plan split across the drones, each part checked by the rails; nothing is uploaded. */
export function previewSurvey(body: SurveyRequest, signal?: AbortSignal): Promise<SurveyPreview> {
  return post<SurveyPreview>("surveys/preview", body, signal);
}

export function createSurvey(body: SurveyRequest): Promise<SurveyDetail> {
  return post<SurveyDetail>("surveys", body);
}

export function startSurvey(id: string): Promise<SurveyDetail> {
  return post<SurveyDetail>(`${survey(id)}/start`, undefined);
}

export function getSurvey(id: string): Promise<SurveyDetail> {
  return request<SurveyDetail>(survey(id));
}

export function acceptHandover(id: string): Promise<SurveyDetail> {
  return post<SurveyDetail>(`${survey(id)}/handover/accept`, undefined);
}

export function abortSurvey(id: string): Promise<SurveyDetail> {
  return post<SurveyDetail>(`${survey(id)}/abort`, undefined);
}

/** A survey request's fields (at least `area`) from a QGC .plan, a KML or a GeoJSON file. */
export function importArea(format: SurveyFileFormat, content: string): Promise<Partial<SurveyRequest>> {
  return post<Partial<SurveyRequest>>("surveys/import", { format, content });
}

/** Every survey mosaic the hub holds, finished ones too (they outlive a restart). */
export function listMosaics(): Promise<MosaicDetail[]> {
  return request<MosaicDetail[]>("mosaics");
}

/** The survey's live orthomosaic (backend/imagery/mosaic/routes.py); null until a photo reaches it. */
export async function getMosaic(id: string): Promise<MosaicDetail | null> {
  try {
    return await request<MosaicDetail>(`mosaics/${encodeURIComponent(id)}`);
  } catch (error) {
    if (error instanceof ApiError && error.status === 404) return null;
    throw error;
  }
}
