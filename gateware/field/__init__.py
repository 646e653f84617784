"""Field transforms between the position sources and the PHY: scale, offset, saturation."""
