"""Controllers and their design rules."""
