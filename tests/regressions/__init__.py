"""Regression corpus: every lexicographic problem that ever failed a test, saved as npz."""
