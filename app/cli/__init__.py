"""touchbench: app/cli."""
