// Three small stacked uPlot charts of a flight (altitude, ground speed, battery)
// over the replay clock, with a vertical line at the replay position. Hovering
// one chart shows the cursor on all three; clicking a chart seeks the replay.
import uPlot from "uplot";
import "uplot/dist/uPlot.min.css";
import { formatClock, type FlightTrack } from "./replayTrack";
import type { FlightSample } from "../hub/types";

interface ChartSpec {
  key: "altitude" | "groundspeed" | "battery";
  title: string;
  unit: string;
  colour: string;
  value(sample: FlightSample): number | null;
}

const CHARTS: ChartSpec[] = [
  { key: "altitude", title: "Altitude", unit: "m", colour: "#4fb3ff", value: (s) => s.alt_rel },
  { key: "groundspeed", title: "Ground speed", unit: "m/s", colour: "#3ecf8e", value: (s) => s.groundspeed },
  {
    key: "battery",
    title: "Battery",
    unit: "%",
    colour: "#f5b942",
    value: (s) => (s.battery_remaining !== null && s.battery_remaining >= 0 ? s.battery_remaining : null),
  },
];

const CHART_HEIGHT = 92;
/** Whole seconds and minutes between x ticks, however short the flight. */
const TIME_INCREMENTS = [1, 2, 5, 10, 15, 30, 60, 120, 300, 600, 900, 1800, 3600, 7200, 14400, 28800];
const AXIS_COLOUR = "#8796a8";
const GRID_COLOUR = "rgba(135, 150, 168, 0.14)";

function clockTick(seconds: number): string {
  const text = formatClock(seconds);
  return text.startsWith("00:") ? text.slice(3) : text;
}

interface Chart {
  plot: uPlot;
  line: HTMLDivElement;
}

export class ReplayCharts {
  readonly element: HTMLDivElement;
  private charts: Chart[] = [];
  private resizeObserver: ResizeObserver | null = null;
  private position = 0;

  constructor(private readonly onSeek: (t: number) => void) {
    this.element = document.createElement("div");
    this.element.className = "replay-charts";
  }

  /** Builds the charts for a flight; the element must be in the document and visible. */
  show(track: FlightTrack): void {
    this.destroy();
    const x = Array.from(track.times);
    const width = this.chartWidth();
    const syncKey = `replay-${track.flight.id}`;
    for (const spec of CHARTS) {
      const wrapper = document.createElement("figure");
      wrapper.className = "replay-chart";
      wrapper.dataset.chart = spec.key;
      const caption = document.createElement("figcaption");
      caption.textContent = `${spec.title} (${spec.unit})`;
      wrapper.append(caption);
      this.element.append(wrapper);

      const y = track.samples.map((sample) => {
        const value = spec.value(sample);
        return value !== null && Number.isFinite(value) ? value : null;
      });
      const plot = new uPlot(
        {
          width,
          height: CHART_HEIGHT,
          legend: { show: false },
          cursor: { sync: { key: syncKey }, drag: { x: false, y: false }, points: { size: 6 } },
          scales: { x: { time: false, range: [0, Math.max(track.duration, 1)] } },
          axes: [
            {
              stroke: AXIS_COLOUR,
              grid: { stroke: GRID_COLOUR, width: 1 },
              ticks: { stroke: GRID_COLOUR, width: 1, size: 4 },
              size: 26,
              font: "11px system-ui, sans-serif",
              incrs: TIME_INCREMENTS,
              values: (_u, splits) => splits.map(clockTick),
            },
            {
              stroke: AXIS_COLOUR,
              grid: { stroke: GRID_COLOUR, width: 1 },
              ticks: { stroke: GRID_COLOUR, width: 1, size: 4 },
              size: 44,
              font: "11px system-ui, sans-serif",
            },
          ],
          series: [
            { label: "time" },
            { label: spec.title, stroke: spec.colour, width: 1.5, points: { show: false }, spanGaps: false },
          ],
        },
        [x, y],
        wrapper,
      );
      const line = document.createElement("div");
      line.className = "replay-chart-position";
      plot.over.append(line);
      plot.over.addEventListener("click", (event: MouseEvent) => {
        this.onSeek(plot.posToVal(event.offsetX, "x"));
      });
      this.charts.push({ plot, line });
    }
    this.resizeObserver = new ResizeObserver(() => this.resize());
    this.resizeObserver.observe(this.element);
    this.setPosition(this.position);
  }

  /** Moves the vertical line to `t` seconds since the flight's start. */
  setPosition(t: number): void {
    this.position = t;
    for (const { plot, line } of this.charts) {
      const left = plot.valToPos(t, "x");
      line.style.transform = `translateX(${Number.isFinite(left) ? left : 0}px)`;
    }
  }

  destroy(): void {
    this.resizeObserver?.disconnect();
    this.resizeObserver = null;
    for (const { plot } of this.charts) plot.destroy();
    this.charts = [];
    this.element.replaceChildren();
  }

  private chartWidth(): number {
    return Math.max(200, Math.floor(this.element.clientWidth));
  }

  private resize(): void {
    const width = this.chartWidth();
    for (const { plot } of this.charts) {
      if (plot.width !== width) plot.setSize({ width, height: CHART_HEIGHT });
    }
    this.setPosition(this.position);
  }
}
