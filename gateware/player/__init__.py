"""Stand-alone marking: a job image in the flash, played on a start input."""
