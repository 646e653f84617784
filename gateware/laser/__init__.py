"""Laser control: the DB25 fiber laser interface and its interlocks."""
