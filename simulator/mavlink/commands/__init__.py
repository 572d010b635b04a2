"""Incoming MAVLink to vehicle calls, and the replies the autopilot would send: one
module per family of messages (arming and modes, navigation, parameters, missions,
requested messages), dispatched by `MessageHandler`."""

from simulator.mavlink.commands.base import Command, Reply
from simulator.mavlink.commands.handler import MessageHandler
from simulator.mavlink.commands.requests import StreamControl

__all__ = ["Command", "MessageHandler", "Reply", "StreamControl"]
