"""The simulated autopilot's parameters: the values it honours (`values`, SI units), the
table a GCS reads and writes (`table`, ArduCopter's names; `px4`, PX4's), and their
encodings on the wire (`wire`)."""
