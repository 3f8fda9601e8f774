"""touchbench: app."""
