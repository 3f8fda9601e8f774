"""touchbench: features."""
