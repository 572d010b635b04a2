"""MAVLink forwarding: third-party GCSs (QGroundControl, MAVProxy) reach the vehicle
through the agent, as they would through mavlink-router, while the hub keeps its view.

Each endpoint is one UDP socket towards one GCS. ``udpout:HOST:PORT`` sends to a fixed
address (QGroundControl listens on 14550); ``udpin:HOST:PORT`` listens, and answers the
address the GCS last wrote from. Frames are routed by the ids they carry, with
mavlink-router's rules (``Endpoint::accept_msg``):

- a frame never goes back where its source has been heard from (no loops);
- a frame without a target, or for system 0, goes everywhere else;
- a frame for system S, component C, goes only where S/C has been heard from (where S
  has, if C is 0 or absent). Towards the flight controller the system is enough: the
  autopilot routes on to its own components.

So the vehicle's telemetry reaches every GCS, a GCS's command reaches the vehicle, the
answer reaches only the GCS that asked, and the agent's own exchanges with the vehicle
(addressed to its ``source_system``) reach no GCS. A frame that comes back carrying the
autopilot's own ids is a routing loop: it is dropped and counted.

Rate requests are the exception: the flight controller keeps one set of stream rates per
link, shared by the agent and every GCS behind it, so a GCS's REQUEST_DATA_STREAM and
SET_MESSAGE_INTERVAL (COMMAND_LONG or COMMAND_INT) go through ``RateMerger``
(fcu/rate_merger.py): the flight controller is sent the highest rate each stream needs, once, and
a SET_MESSAGE_INTERVAL asking for no more than is already set is answered ACCEPTED here,
on the autopilot's behalf, and not sent on. Otherwise MAVProxy's REQUEST_DATA_STREAM every
~15 s lowered the agent's position rate, and the two asked in turn forever.

Other frames travel unchanged (their sequence numbers and signatures too). The vehicle's are
sent from the FCU reader thread, through a tap, with a non-blocking ``sendto``: there is
no queue and no thread per GCS, a datagram the kernel will not take is dropped and
counted, and a GCS that is gone can never stall the reader. A GCS's frames are read on the
event loop and written to the vehicle there, like the agent's own.
"""
