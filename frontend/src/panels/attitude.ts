// A small attitude indicator: the horizon rolls and moves with pitch, the heading is
// written under it. SVG built once; `update` only sets two transforms and a text.
const SVG_NS = "http://www.w3.org/2000/svg";
/** Pixels of the 100-unit viewBox per degree of pitch: ±40° fills the dial. */
const PX_PER_DEGREE = 1.25;

function svg<K extends keyof SVGElementTagNameMap>(tag: K, attributes: Record<string, string>): SVGElementTagNameMap[K] {
  const node = document.createElementNS(SVG_NS, tag);
  for (const [name, value] of Object.entries(attributes)) node.setAttribute(name, value);
  return node;
}

export class AttitudeIndicator {
  readonly element: SVGSVGElement;
  private readonly horizon: SVGGElement;
  private readonly heading: SVGTextElement;

  constructor() {
    this.element = svg("svg", { class: "attitude", viewBox: "0 0 100 100", role: "img" });
    this.element.dataset.field = "attitude";
    const clip = svg("clipPath", { id: "attitude-clip" });
    clip.append(svg("circle", { cx: "50", cy: "50", r: "46" }));
    const defs = svg("defs", {});
    defs.append(clip);
    this.horizon = svg("g", { class: "attitude-horizon" });
    this.horizon.append(
      svg("rect", { class: "attitude-sky", x: "-100", y: "-150", width: "300", height: "200" }),
      svg("rect", { class: "attitude-ground", x: "-100", y: "50", width: "300", height: "200" }),
      svg("line", { class: "attitude-line", x1: "-100", y1: "50", x2: "200", y2: "50" }),
    );
    for (const pitch of [-20, -10, 10, 20]) {
      const y = String(50 - pitch * PX_PER_DEGREE);
      const half = pitch % 20 === 0 ? 14 : 8;
      this.horizon.append(svg("line", { class: "attitude-ladder", x1: String(50 - half), y1: y, x2: String(50 + half), y2: y }));
    }
    const dial = svg("g", { "clip-path": "url(#attitude-clip)" });
    dial.append(this.horizon);
    const aircraft = svg("path", { class: "attitude-aircraft", d: "M22 50 H42 L50 57 L58 50 H78" });
    const rim = svg("circle", { class: "attitude-rim", cx: "50", cy: "50", r: "46" });
    this.heading = svg("text", { class: "attitude-heading", x: "50", y: "90", "text-anchor": "middle" });
    this.element.append(defs, dial, aircraft, rim, this.heading);
    this.update(null, null, null);
  }

  update(rollDeg: number | null | undefined, pitchDeg: number | null | undefined, headingDeg: number | null | undefined): void {
    const roll = rollDeg ?? 0;
    const pitch = Math.max(-60, Math.min(60, pitchDeg ?? 0));
    // Rolling right tilts the horizon left: rotate by -roll about the centre.
    this.horizon.setAttribute("transform", `rotate(${(-roll).toFixed(1)} 50 50) translate(0 ${(pitch * PX_PER_DEGREE).toFixed(1)})`);
    const heading = headingDeg === null || headingDeg === undefined ? "—" : `${String(Math.round(((headingDeg % 360) + 360) % 360)).padStart(3, "0")}°`;
    if (this.heading.textContent !== heading) this.heading.textContent = heading;
    const label =
      rollDeg === null || rollDeg === undefined
        ? "Attitude unknown"
        : `Roll ${roll.toFixed(0)}°, pitch ${(pitchDeg ?? 0).toFixed(0)}°, heading ${heading}`;
    this.element.setAttribute("aria-label", label);
  }
}
