"""Recognition benchmarks: synthetic and realistic pictures, cell renders, the camera."""
