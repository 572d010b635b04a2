// The dashboard's icons: inline SVG drawn from path data bundled here, so they look the
// same on every machine (an emoji draws as an empty box where no emoji font is installed)
// and no icon is fetched from anywhere. Each takes the text colour (currentColor).

const SVG_NS = "http://www.w3.org/2000/svg";

/** 24x24 paths; `fill` ones are solid shapes, the others are 2 px strokes. */
const ICONS = {
  warning: { fill: true, d: "M12 2.5 23 21.5H1Zm-1.2 7v6h2.4v-6Zm0 7.6v2.4h2.4v-2.4Z" },
  critical: {
    fill: true,
    d: "M7.6 1.5h8.8l6.1 6.1v8.8l-6.1 6.1H7.6l-6.1-6.1V7.6Zm3.2 4.5v8h2.4V6Zm0 10v2.4h2.4V16Z",
  },
  menu: { fill: false, d: "M3 6h18M3 12h18M3 18h18" },
  close: { fill: false, d: "M5 5l14 14M19 5 5 19" },
  "chevron-down": { fill: false, d: "M5 9l7 7 7-7" },
  "chevron-up": { fill: false, d: "M5 15l7-7 7 7" },
} as const;

export type IconName = keyof typeof ICONS;

/** An icon element; `label` makes it an image with that name, otherwise it is decoration. */
export function icon(name: IconName, label?: string): SVGSVGElement {
  const { fill, d } = ICONS[name];
  const svg = document.createElementNS(SVG_NS, "svg");
  svg.setAttribute("viewBox", "0 0 24 24");
  svg.setAttribute("class", `icon icon-${name}`);
  svg.dataset.icon = name;
  if (label) {
    svg.setAttribute("role", "img");
    svg.setAttribute("aria-label", label);
  } else {
    svg.setAttribute("aria-hidden", "true");
  }
  const path = document.createElementNS(SVG_NS, "path");
  path.setAttribute("d", d);
  if (fill) {
    path.setAttribute("fill", "currentColor");
    path.setAttribute("fill-rule", "evenodd");
  } else {
    path.setAttribute("fill", "none");
    path.setAttribute("stroke", "currentColor");
    path.setAttribute("stroke-width", "2");
    path.setAttribute("stroke-linecap", "round");
    path.setAttribute("stroke-linejoin", "round");
  }
  svg.append(path);
  return svg;
}

/** Puts `name`'s icon (or nothing, for null) in `holder`, redrawing only on a change. */
export function setIcon(holder: Element, name: IconName | null, label?: string): void {
  const current = holder.querySelector("svg[data-icon]")?.getAttribute("data-icon") ?? null;
  if (current === name) return;
  holder.replaceChildren(...(name ? [icon(name, label)] : []));
}
