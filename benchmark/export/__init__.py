"""Trained models in formats other programs run (ONNX)."""
