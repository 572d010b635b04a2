"""Manual control, the whole feature on the hub: who may fly a vehicle by hand from the
browser, and what input reaches it.

- `lease`: the one-pilot-per-vehicle lease, its expiry and the input it admits (newest
  first, at most 100 Hz).
- `claims` over `store`: the lease made exclusive across hubs sharing one database (a
  compare-and-set row per vehicle, also used by the surveys' ownership).
- `service`: ``ManualControl``, the lease's life (granted once the agent opened browser
  control, ended however it ends, told to every feed, audited, revoked after a restart).
- `pilot`: one live feed's lease requests and sticks (``PilotChannel``), the refusals told
  to the pilot and the event feed, and `relay`: the sticks to the vehicle's agent, newest
  wins.

The live sessions reach it through the hub (``Hub.manual_control``): the client feed hands
a pilot's messages to its ``PilotChannel``, the agent gateway the agent's word to the
service. Nothing of it is a REST route: leases and sticks travel on the live feed.
"""
