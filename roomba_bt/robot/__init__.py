"""The robot connection: mode model, guarded command path, safety on every exit."""
