"""touchbench: drivers."""
