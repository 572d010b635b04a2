// How the map's area is shared with the 3D view, as the operator left it: the 3D view's
// share of the width beside the map, or the whole area. Kept in localStorage, so the
// split is where it was after a reload or the next login on this browser.

export const STORAGE_KEY = "gcs.viz3d.split";
/** The 3D view's share of the map's area beside the map: neither side narrower than a fifth. */
export const MIN_SHARE = 0.2;
export const MAX_SHARE = 0.8;
export const DEFAULT_SHARE = 0.5;
/** One arrow key press on the divider moves it by this share of the area. */
export const KEY_STEP = 0.05;
/** Below this width the map's area is too narrow for two views: the 3D view replaces the map. */
export const NARROW_AREA_PX = 720;

export interface SplitShare {
  /** The 3D view's share of the area while it is beside the map. */
  share: number;
  /** The operator asked for the 3D view instead of the map (on a wide screen). */
  full: boolean;
}

export function clampShare(share: number): number {
  return Math.min(MAX_SHARE, Math.max(MIN_SHARE, share));
}

export function loadShare(storage: Pick<Storage, "getItem"> = localStorage): SplitShare {
  try {
    const saved = JSON.parse(storage.getItem(STORAGE_KEY) ?? "null") as Partial<SplitShare> | null;
    const share = typeof saved?.share === "number" && Number.isFinite(saved.share) ? clampShare(saved.share) : DEFAULT_SHARE;
    return { share, full: saved?.full === true };
  } catch {
    return { share: DEFAULT_SHARE, full: false }; // a hand-edited or foreign value: start afresh
  }
}

export function saveShare(split: SplitShare, storage: Pick<Storage, "setItem"> = localStorage): void {
  try {
    storage.setItem(STORAGE_KEY, JSON.stringify(split));
  } catch {
    // Storage full or refused (a private window): the split still works, unremembered.
  }
}

/** The share after a key press on the divider, or null for a key the divider ignores.
 * The divider's value is the map's side (the separator's primary pane, on the left), so
 * ArrowLeft moves the divider left: a smaller map and a wider 3D view. */
export function shareAfterKey(share: number, key: string): number | null {
  switch (key) {
    case "ArrowLeft":
    case "ArrowUp":
      return clampShare(share + KEY_STEP);
    case "ArrowRight":
    case "ArrowDown":
      return clampShare(share - KEY_STEP);
    case "Home":
      return MAX_SHARE;
    case "End":
      return MIN_SHARE;
    default:
      return null;
  }
}
