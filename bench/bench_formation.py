"""Formation tracking benchmark: the seed scenario (a leader flies a 20 m square with
2 s pauses at 8 m, two followers in a triangle at 3 m spacing, 2 m and 3 m up) in the
simulator on its sped-up clock, against the leader's speed (0.5 to 5 m/s, no link delay)
and the link's delay (0 to 300 ms at 1.5 m/s).

    .venv/bin/python bench/bench_formation.py

Three controllers: the agent's leader-following (position + velocity feed-forward, the
leader predicted over the delay), its consensus (k_leader 1, k_neighbour 0.5, each
follower hearing the other, its state delayed as the leader's), and the seed's (position
only, no prediction). The figure is the worse follower's horizontal RMS error and its
maximum, during the legs. Prints Markdown tables; asserts nothing.
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from common.formation import ConsensusGains, Controller
from tests.support.formation_sim import FormationRun, fly_formation
from vehicle_agents.control.formation_follower import FollowerSettings

CONTROLLERS = {
    "leader-following": {"feed_forward": True},
    "consensus": {"controller": Controller.CONSENSUS, "gains": ConsensusGains(1.0, 0.5)},
    # the seed's open-loop waypoints: no velocity, no prediction over the delay
    "position only": {"feed_forward": False, "settings": FollowerSettings(max_lead_s=0.0)},
}


def _cell(run: FormationRun) -> str:
    worst = max(run.errors_xy, key=run.rms_xy)
    return f"{run.rms_xy(worst):.2f} / {run.max_xy(worst):.2f}"


def main() -> None:
    print("| leader speed (m/s) | " + " | ".join(CONTROLLERS) + " |")
    print("| --- |" + " --- |" * len(CONTROLLERS))
    for speed in (0.5, 1.0, 1.5, 2.0, 3.0, 5.0):
        cells = [_cell(fly_formation(speed_ms=speed, **kw)) for kw in CONTROLLERS.values()]  # type: ignore[arg-type]
        print(f"| {speed:g} | " + " | ".join(cells) + " |", flush=True)
    print()
    print("| link delay (ms), 1.5 m/s | " + " | ".join(CONTROLLERS) + " |")
    print("| --- |" + " --- |" * len(CONTROLLERS))
    for delay_ms in (0, 100, 200, 300):
        cells = [
            _cell(fly_formation(link_delay_s=delay_ms / 1000, **kw))  # type: ignore[arg-type]
            for kw in CONTROLLERS.values()
        ]
        print(f"| {delay_ms} | " + " | ".join(cells) + " |", flush=True)
    print("\ncells: worst follower's horizontal RMS / max error in metres, during the legs")


if __name__ == "__main__":
    main()
