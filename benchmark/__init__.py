"""touchbench: benchmark."""
