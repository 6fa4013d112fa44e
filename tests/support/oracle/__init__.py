"""Slow, obviously right references for tests (never imported by the package)."""
