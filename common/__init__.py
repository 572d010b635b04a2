"""Small, pure helpers that the agent, the hub and the command line all use: the retry
policy and address checks. A leaf beside `protocol`: it imports nothing of ours.
"""
