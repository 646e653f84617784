"""Physical layer: the XY2-100 scan head bus."""
