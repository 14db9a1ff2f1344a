"""Pictures and animation of results."""
