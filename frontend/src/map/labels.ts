// Where vehicle labels go when vehicles crowd together: a label that would overlap one
// already placed is not drawn, and joins that one, which then shows a count ("+3").
// Greedy in priority order (the selected vehicle first), with a grid of placed boxes so
// 1,000 labels take well under a millisecond.

export interface LabelBox {
  id: string;
  /** Top-left corner and size, in screen pixels. */
  x: number;
  y: number;
  width: number;
  height: number;
  /** Higher is placed first (the selected vehicle). */
  priority: number;
}

/** Each shown label's id, with the ids of the labels merged into it. */
export type LabelLayout = Map<string, string[]>;

const CELL_PX = 96;

function overlaps(a: LabelBox, b: LabelBox): boolean {
  return a.x < b.x + b.width && b.x < a.x + a.width && a.y < b.y + b.height && b.y < a.y + a.height;
}

export function placeLabels(boxes: readonly LabelBox[]): LabelLayout {
  const order = [...boxes].sort(
    (a, b) => b.priority - a.priority || (a.id < b.id ? -1 : a.id > b.id ? 1 : 0),
  );
  const grid = new Map<string, LabelBox[]>();
  const layout: LabelLayout = new Map();
  const cellsOf = (box: LabelBox): string[] => {
    const keys: string[] = [];
    for (let cx = Math.floor(box.x / CELL_PX); cx <= Math.floor((box.x + box.width) / CELL_PX); cx++) {
      for (let cy = Math.floor(box.y / CELL_PX); cy <= Math.floor((box.y + box.height) / CELL_PX); cy++) {
        keys.push(`${cx},${cy}`);
      }
    }
    return keys;
  };
  for (const box of order) {
    const cells = cellsOf(box);
    let host: LabelBox | undefined;
    for (const key of cells) {
      host = grid.get(key)?.find((placed) => overlaps(placed, box));
      if (host) break;
    }
    if (host) {
      layout.get(host.id)!.push(box.id);
      continue;
    }
    layout.set(box.id, []);
    for (const key of cells) {
      const list = grid.get(key);
      if (list) list.push(box);
      else grid.set(key, [box]);
    }
  }
  return layout;
}
