// The vehicle's symbol: a heading arrow, or a dot without a heading. The live map draws
// its outline on a canvas (map/vehicleLayer.ts); the replay shows this SVG.

const SVG_NS = "http://www.w3.org/2000/svg";
export const ICON_SIZE = 28;

function svgElement<K extends keyof SVGElementTagNameMap>(
  tag: K,
  attributes: Record<string, string>,
): SVGElementTagNameMap[K] {
  const element = document.createElementNS(SVG_NS, tag);
  for (const [name, value] of Object.entries(attributes)) element.setAttribute(name, value);
  return element;
}

/** The heading arrow (and the dot shown instead when there is no heading); also used by the replay. */
export function vehicleSymbol(): SVGSVGElement {
  const symbol = svgElement("svg", {
    class: "vehicle-symbol",
    viewBox: "0 0 28 28",
    width: String(ICON_SIZE),
    height: String(ICON_SIZE),
    "aria-hidden": "true",
  });
  symbol.append(
    svgElement("path", { class: "vehicle-arrow", d: "M14 2 L24 25 L14 19.5 L4 25 Z" }),
    svgElement("circle", { class: "vehicle-dot", cx: "14", cy: "14", r: "7" }),
  );
  return symbol;
}
