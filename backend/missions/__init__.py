"""Mission planners on the hub: each produces `MissionItem` lists (`survey/`, `formation/`)
that the safety package checks (`backend.safety`: the mission body, its places, battery,
rails and the AUTO gate). Pure domain logic: no HTTP, no I/O."""
