"""Who is calling, and what they may do: accounts, tokens, roles and the one policy."""
