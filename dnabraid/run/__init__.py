"""The thermal run layer."""
