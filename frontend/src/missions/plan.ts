// QGroundControl's `.plan` file (JSON), read and written for the one mission model.
//
// The format (QGC's "Plan File Format", src/MissionManager/MissionController.cc and
// MissionItem.cc): {fileType: "Plan", version: 1, groundStation, mission, geoFence,
// rallyPoints}; `mission` is {version: 2, firmwareType, vehicleType, cruiseSpeed, hoverSpeed,
// plannedHomePosition: [lat, lon, alt], items}; a "SimpleItem" carries one MAVLink item as
// {command, frame, params: [p1..p4, lat, lon, alt] (NaN written as null), autoContinue,
// doJumpId}. A null is QGC's NaN, MAVLink's "unset" (a yaw that keeps the heading): in
// params 1-4 it stays null (NaN on the wire; the hub's mission rules refuse it where the
// command gives NaN no meaning), in the position it is refused, naming the item. Never 0:
// a null altitude read as 0 is a waypoint at sea level, a null yaw read as 0 faces north. Complex items (surveys, corridor scans) are QGC's own patterns, expanded into
// simple items only by QGC: a file with one is refused, naming it, rather than flown partly.
import { fullItem, type MissionItem } from "./model";

/** MAV_AUTOPILOT and MAV_TYPE numbers QGC writes as firmwareType / vehicleType. */
const MAV_AUTOPILOT_ARDUPILOTMEGA = 3;
const MAV_AUTOPILOT_PX4 = 12;
const MAV_TYPE_QUADROTOR = 2;

/** A SimpleItem's params 5-7, by name: MISSION_ITEM_INT's x, y and z, with no "unset". */
const POSITION = [
  [4, "latitude"],
  [5, "longitude"],
  [6, "altitude"],
] as const;

export interface PlanFile {
  items: MissionItem[];
  /** The plan's planned home [lat, lon, alt AMSL], if it has one. */
  home: [number, number, number] | null;
}

export class PlanError extends Error {}

export interface PlanOptions {
  home?: [number, number, number] | null;
  autopilot?: string | null;
  cruiseSpeed?: number;
  hoverSpeed?: number;
}

/** The JSON object of a `.plan` file for these items (item 1 is the first after home). */
export function toPlan(items: readonly MissionItem[], options: PlanOptions = {}): Record<string, unknown> {
  const firstPlace = items.find((item) => item.lat !== 0 || item.lon !== 0);
  const home = options.home ?? (firstPlace ? [firstPlace.lat, firstPlace.lon, 0] : [0, 0, 0]);
  return {
    fileType: "Plan",
    version: 1,
    groundStation: "Fleet GCS",
    mission: {
      version: 2,
      firmwareType: options.autopilot === "px4" ? MAV_AUTOPILOT_PX4 : MAV_AUTOPILOT_ARDUPILOTMEGA,
      vehicleType: MAV_TYPE_QUADROTOR,
      cruiseSpeed: options.cruiseSpeed ?? 15,
      hoverSpeed: options.hoverSpeed ?? 5,
      plannedHomePosition: home,
      items: items.map((item, index) => ({
        type: "SimpleItem",
        command: item.command,
        frame: item.frame,
        params: [item.param1, item.param2, item.param3, item.param4, item.lat, item.lon, item.alt].map((value) =>
          Number.isFinite(value) ? value : null,
        ),
        autoContinue: item.autocontinue,
        doJumpId: index + 1,
      })),
    },
    geoFence: { version: 2, circles: [], polygons: [] },
    rallyPoints: { version: 2, points: [] },
  };
}

/** The `.plan` file's text, as QGC writes it (indented JSON). */
export function writePlan(items: readonly MissionItem[], options: PlanOptions = {}): string {
  return JSON.stringify(toPlan(items, options), null, 4) + "\n";
}

function isObject(value: unknown): value is Record<string, unknown> {
  return typeof value === "object" && value !== null && !Array.isArray(value);
}

function need<T>(ok: boolean, value: unknown, where: string, what: string): T {
  if (!ok) throw new PlanError(`${where}: ${what}`);
  return value as T;
}

function number(value: unknown, where: string): number {
  return need<number>(typeof value === "number" && Number.isFinite(value), value, where, "must be a number");
}

/** Reads a `.plan` file's text; throws PlanError naming the field that is wrong. */
export function readPlan(text: string): PlanFile {
  let json: unknown;
  try {
    json = JSON.parse(text);
  } catch (error) {
    throw new PlanError(`not JSON: ${error instanceof Error ? error.message : String(error)}`);
  }
  if (!isObject(json)) throw new PlanError("not a .plan file: the file is not a JSON object");
  if (json.fileType !== "Plan") throw new PlanError(`fileType: "${String(json.fileType)}" is not "Plan"`);
  const mission = json.mission;
  if (!isObject(mission)) throw new PlanError("mission: missing (a .plan file needs a mission object)");
  if (mission.version !== 2) {
    throw new PlanError(`mission.version: ${String(mission.version)} is not supported (QGC's current is 2)`);
  }
  const rawItems = need<unknown[]>(Array.isArray(mission.items), mission.items, "mission.items", "must be a list");
  const items: MissionItem[] = [];
  rawItems.forEach((raw, index) => {
    const where = `mission.items[${index}]`;
    if (!isObject(raw)) throw new PlanError(`${where}: must be an object`);
    if (raw.type === "ComplexItem") {
      const kind = typeof raw.complexItemType === "string" ? raw.complexItemType : "complex item";
      throw new PlanError(
        `${where}: a QGroundControl ${kind}; open the plan in QGroundControl and save it with the pattern's items, or draw it here`,
      );
    }
    if (raw.type !== "SimpleItem") throw new PlanError(`${where}.type: "${String(raw.type)}" is not "SimpleItem"`);
    const params = need<unknown[]>(
      Array.isArray(raw.params) && raw.params.length === 7,
      raw.params,
      `${where}.params`,
      "must be a list of 7 numbers (null for none)",
    );
    // QGC writes NaN (an unset parameter, e.g. a yaw that keeps the heading) as null.
    const [p1, p2, p3, p4] = params.slice(0, 4).map((value, i) =>
      value === null ? null : number(value, `${where}.params[${i}]`),
    );
    const [lat, lon, alt] = POSITION.map(([i, name]) => {
      if (params[i] === null) {
        throw new PlanError(`item ${index + 1}: ${name} is empty (null) in the .plan (${where}.params[${i}])`);
      }
      return number(params[i], `${where}.params[${i}]`);
    });
    const autoContinue = raw.autoContinue ?? true;
    if (typeof autoContinue !== "boolean") throw new PlanError(`${where}.autoContinue: must be true or false`);
    items.push(
      fullItem({
        command: number(raw.command, `${where}.command`),
        frame: number(raw.frame, `${where}.frame`),
        param1: p1,
        param2: p2,
        param3: p3,
        param4: p4,
        lat,
        lon,
        alt,
        autocontinue: autoContinue,
      }),
    );
  });
  const planned = mission.plannedHomePosition;
  const home =
    Array.isArray(planned) && planned.length === 3 && planned.every((v) => typeof v === "number")
      ? (planned as [number, number, number])
      : null;
  return { items, home };
}
