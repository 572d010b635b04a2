"""What the simulator serves besides MAVLink: the simulated LIDAR's serial line over TCP
(`lidar`), the camera's photos over HTTP (`photos`), and the camera as the agent's real
cameras (`cameras`: a MAVLink camera component, or a folder of files)."""
