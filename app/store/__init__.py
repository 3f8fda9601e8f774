"""touchbench: app/store."""
