// One colour per vehicle, the same on the 2D map and in the 3D view: the palette entry
// picked by the CRC-32 of the id's UTF-8 bytes (backend/viz3d/colours.py does the same;
// tests/browser/test_viz3d.py checks the two agree on the map's labels).
export const PALETTE = [
  "#e6194b",
  "#3cb44b",
  "#4363d8",
  "#f58231",
  "#911eb4",
  "#42d4f4",
  "#f032e6",
  "#bfef45",
  "#469990",
  "#9a6324",
  "#800000",
  "#808000",
] as const;

function crc32(bytes: Uint8Array): number {
  let crc = 0xffffffff;
  for (const byte of bytes) {
    crc ^= byte;
    for (let bit = 0; bit < 8; bit++) crc = crc & 1 ? (crc >>> 1) ^ 0xedb88320 : crc >>> 1;
  }
  return (crc ^ 0xffffffff) >>> 0;
}

export function vehicleColour(id: string): string {
  return PALETTE[crc32(new TextEncoder().encode(id)) % PALETTE.length];
}
