"""The wire protocol: every message between agent, hub and clients (`messages`), what hubs
say to each other about a routed command (`routing`), and the
ranges of MAVLink's wire types that bound them (`mavlink_wire`).

The leaf of the tree: it imports nothing of ours, and everything else may import it.
"""
