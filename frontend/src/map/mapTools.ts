// One map tool at a time. A tool is anything that takes the map's clicks for itself (the
// mission editor's waypoints, the survey's corners, the formation's route): two at once
// once made survey corners into a mission's waypoints. Starting a tool ends the one before
// it, folding the panel a tool belongs to ends it, and the banner on the map (toolBanner.ts)
// names the active tool with its way out (Esc, Done).
//
// No Leaflet and no DOM here beyond an owner element's identity: the rules are unit-tested.

export interface MapTool {
  /** What the banner says while the tool is on, e.g. "Drawing survey area". */
  readonly label: string;
  /** The panel the tool belongs to: folding it ends the tool. */
  readonly owner?: object;
  /** Called when something else ends the tool (another tool, Esc, Done, a fold). */
  ended(): void;
}

type Listener = (active: MapTool | null) => void;

export class MapToolRegistry {
  private current: MapTool | null = null;
  private readonly listeners = new Set<Listener>();

  get active(): MapTool | null {
    return this.current;
  }

  isActive(tool: MapTool): boolean {
    return this.current === tool;
  }

  /** `tool` takes the map: the tool that had it is ended first. */
  start(tool: MapTool): void {
    if (this.current === tool) return;
    const before = this.current;
    this.current = tool;
    before?.ended(); // told after the switch: an ended() that releases itself changes nothing
    this.notify();
  }

  /** The tool stopped itself (its own Done, Clear, an upload): nothing to call back. */
  release(tool: MapTool): void {
    if (this.current !== tool) return;
    this.current = null;
    this.notify();
  }

  /** Ends the active tool from outside (Esc, the banner's Done): it is told. */
  endActive(): void {
    const tool = this.current;
    if (!tool) return;
    this.current = null;
    tool.ended();
    this.notify();
  }

  /** A panel folded: its tool, if it is the active one, ends. */
  endOwnedBy(owner: object): void {
    if (this.current?.owner === owner) this.endActive();
  }

  /** `listener` hears every change of the active tool; returns its unsubscribe. */
  subscribe(listener: Listener): () => void {
    this.listeners.add(listener);
    return () => this.listeners.delete(listener);
  }

  private notify(): void {
    for (const listener of this.listeners) listener(this.current);
  }
}

// One registry per map: the panels find it from the map they draw on, with no wiring
// through the dashboard's constructor.
const registries = new WeakMap<object, MapToolRegistry>();

export function mapToolsOf(map: object): MapToolRegistry {
  let registry = registries.get(map);
  if (!registry) {
    registry = new MapToolRegistry();
    registries.set(map, registry);
  }
  return registry;
}
