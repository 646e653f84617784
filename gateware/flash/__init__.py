"""Reading the configuration flash after configuration."""
