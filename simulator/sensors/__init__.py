"""The simulated sensors: a 2-D LIDAR that ray-casts the world (`lidar`), and the
camera's nadir view of the synthetic ground (`camera`). No I/O."""
