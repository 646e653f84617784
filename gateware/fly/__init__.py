"""Marking on the fly: the encoders that tell where the part on the belt is."""
