"""The simulated world: obstacles a LIDAR sees (`obstacles`) and the ground texture a
camera photographs (`ground`)."""
