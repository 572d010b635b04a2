/** One colour per drone, in the order the drones are listed (distinct on the base maps). */
export const DRONE_COLOURS = ["#ff7f0e", "#1f9bff", "#2ca02c", "#e377c2", "#bcbd22", "#17becf", "#d62728", "#9467bd"];

export function droneColour(index: number): string {
  return DRONE_COLOURS[index % DRONE_COLOURS.length];
}
