"""What moves the vehicle on the hub's behalf: the hub's commands carried out
(`executor`), flying by hand from the browser (`manual`), the formation follower
(`formation`, with the leader's scans in `formation_obstacles`), and what the vehicle
does when the hub is out of reach (`hub_failsafe`)."""
