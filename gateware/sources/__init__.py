"""Position sources: each hands on one point per dwell as a stream of offsets."""
