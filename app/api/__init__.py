"""touchbench: app/api."""
