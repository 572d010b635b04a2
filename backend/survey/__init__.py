"""Area surveys in flight: the service between the pure planner and the fleet (issue 17)."""
